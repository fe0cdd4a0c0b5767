// VoComponent: Mode = Vo. Each stereo pair through pipeline::VoOdometry (as `qnav vo` runs it) with
// the attitude at the pair's time and the dead-reckoned displacement since the previous pair as the
// translation prior; the body's motion since the last QNAV_VO_STEP sent is published as an
// increment (never repeated). This component owns the increment: its anchor, its inlier count.
// Consumes: reset() when Mode = Vo is entered; on_pair(pair, left and right images, attitude, dead
//   reckoning) per stereo pair.
// Produces: QNAV_VO_STEP on the publisher; the body pose (NED, from the start of the mode) for the
//   MAVLink estimate; a FrameReport per pair (log line, observer); camera_lost() for FaultCameraLost.
// A pair without attitude is not processed in 3D-VME (counted: no_attitude); a pair the VO cannot
// measure is dead-reckoned from the last velocity (VO_STEP Inliers = 0). No pair for vo.stale_s:
// FaultCameraLost (no VO_STEP is sent: the autopilot dead-reckons on its own).
// Memory: the VO's arena (the table's "vo" buffer). Time: one VO step per pair (the vo budget).
#pragma once

#include <cstdint>

#include "drivers/qnavcan/publisher.hpp"
#include "firmware/pipeline/dead_reckoner.hpp"
#include "firmware/pipeline/vo_odometry.hpp"
#include "firmware/qnavd/components/component.hpp"
#include "firmware/qnavd/components/nav_inputs.hpp"
#include "firmware/qnavd/messages.hpp"

namespace qnav::daemon {

// One stereo pair as the nav worker reported it (log line, tests).
struct FrameReport {
  std::uint32_t seq = 0;
  std::uint32_t flags = 0;       // nav/vo VoFlag bits (0 when not processed)
  bool processed = false;        // false: no attitude at the pair's time
  bool visual = false;
  std::uint32_t inliers = 0;
  Pose3 world_T_body;            // the VO's body pose (NED, from the start of the Vo mode)
  bool has_truth = false;
  Pose3 truth_world_T_body;
  double truth_path_m = 0.0;
  std::int64_t stamp_ns = 0;
  double latency_ms = 0.0;       // pair popped -> outputs queued
};

class VoComponent {
 public:
  explicit VoComponent(const NavContext& ctx) noexcept : ctx_(ctx) {}
  Status init(StaticMemory* mem, drivers::qnavcan::QnavCanPublisher& publisher);
  bool ready() const noexcept { return ready_; }
  // Mode = Vo entered: a new chain, the body at the origin of this run in the attitude of its first pair.
  void reset(std::int64_t now_ns) noexcept;
  // False when the pair is older than the previous one (counted out of order by the worker).
  bool in_order(std::int64_t sample_ns) noexcept { return order_.advance(sample_ns); }
  // One pair from its frame slot (left then right, each vo.max_width x vo.max_height), with the
  // newest attitude at or before it (if not stale) and the dead reckoning from the inputs. nullptr: a
  // pair of another size than the slot (a software fault, counted).
  FrameReport* on_pair(const FrameMsg& f, const std::uint8_t* slot, const NavInputs& inputs) noexcept;
  // The pair's log line (log.format json or kv), latency_ms filled in by the caller.
  void log_pair(const FrameReport& r) const noexcept;
  // Mode = Vo: no pair for vo.stale_s since the last one (or the mode's start).
  bool camera_lost(std::int64_t now_ns) const noexcept;

  bool chain_started() const noexcept { return chain_started_; }
  Pose3 body_pose() const noexcept { return vo_.body_pose(); }
  std::uint32_t frames() const noexcept { return vo_.frames(); }
  std::uint32_t visual_steps() const noexcept { return vo_.visual_steps(); }
  std::uint32_t no_attitude() const noexcept { return no_attitude_; }

 private:
  void publish_increment(std::uint32_t inliers) noexcept;

  const NavContext& ctx_;  // the worker's: its log is set in NavWorker::init
  pipeline::VoOdometry vo_;
  StageArena arena_;
  drivers::qnavcan::QnavCanPublisher* publisher_ = nullptr;
  bool ready_ = false;
  SampleOrder order_;                // the last stereo pair's sample time
  std::int64_t mode_start_ns_ = 0;
  Pose3 anchor_, last_set_;           // body poses: at the start of the pending increment, at its last update
  std::uint32_t interval_inliers_ = 0;  // smallest inlier count of the increment's steps (0 = one was not visual)
  FrameReport report_{};
  Pose2 prev_dr_{};                   // dead-reckoned pose at the previous pair (the VO's odometry prior)
  bool prev_dr_valid_ = false;
  bool chain_started_ = false;        // the first pair of this Vo mode was processed
  std::uint32_t no_attitude_ = 0;
};

}  // namespace qnav::daemon
