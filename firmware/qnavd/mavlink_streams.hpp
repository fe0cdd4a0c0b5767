// MavlinkStreams: what qnavd sends over MAVLink on its own schedule (part of MavlinkEndpoint,
// mavlink_endpoint.hpp; nav thread), from a MavSnapshot of the worker's state at its sample time:
//   HEARTBEAT 1 Hz (MAV_TYPE_ONBOARD_CONTROLLER, MAV_AUTOPILOT_INVALID; custom_mode = qnav's mode);
//   ODOMETRY at odometry_hz, on multiples of its period in sample time (frame LOCAL_FRD = 20
//     north-aligned, child BODY_FRD = 12, the NavEstimate's position, the attitude quaternion, the DVL
//     body velocity, reset_counter, quality);
//   VISION_POSITION_DELTA at the same rate (the estimate's motion since the last one, body frame);
//   DISTANCE_SENSOR at the same rate with the DVL altitude (while it reports one);
//   NAMED_VALUE_FLOAT 1 Hz in Repeat: xtrack_m, xtrack_sig, side (-1 port, 0 on, 1 starboard,
//     2 unknown), node; STATUSTEXT on a mode change and a fault bit that rises;
//   SET_POSITION_TARGET_LOCAL_NED 1 Hz with mavlink.guided, in Repeat with a route fix, while the
//     autopilot's HEARTBEAT says GUIDED (ArduSub custom_mode 4) and armed.
// Loss (DVL lost, attitude lost, camera lost in Vo): ODOMETRY quality = -1 with velocity NaN at once
// (the next period), VISION_POSITION_DELTA not sent (and rebased: the first delta after the loss
// starts from the recovered position). Never a zero delta for "no data".
// Owns: the schedule and the last delta's base. Memory: no heap. Time: a few frames per publish.
#pragma once

#include <cstdint>

#include "drivers/qnavcan/messages.hpp"
#include "firmware/pipeline/nav_estimate.hpp"
#include "firmware/qnavd/config.hpp"
#include "firmware/qnavd/messages.hpp"
#include "firmware/qnavd/mavlink_wire.hpp"
#include "nav/core/geometry.hpp"
#include "nav/core/spsc_ring.hpp"

namespace qnav::daemon {

// What the worker hands over each loop (its sample time, its mode, faults and the estimate).
struct MavSnapshot {
  std::int64_t now_ns = 0;
  drivers::qnavcan::Mode mode = drivers::qnavcan::Mode::kIdle;
  std::uint16_t faults = 0;        // qnavcan fault bits
  bool loss = false;               // DVL lost, attitude lost, or camera lost in Mode = Vo
  bool have_attitude = false;
  Mat3d world_R_body = Mat3d::Identity();  // NED <- FRD
  bool have_velocity = false;
  double vx_mps = 0.0, vy_mps = 0.0;       // DVL body velocity (forward, starboard)
  double altitude_m = -1.0;                // DVL altitude; < 0 unknown
  double confidence_pct = 0.0;             // Repeat: the localiser's probability
  bool localised = false;
  const pipeline::NavEstimate* estimate = nullptr;
  // Repeat guidance
  bool in_repeat = false;
  bool route_fix = false;          // a route fix placed the estimate in the route frame (this repeat)
  bool guidance_valid = false;     // tracking (not hold course), offsets known
  double cross_track_m = 0.0, cross_track_sigma_m = 0.0;
  int side = 2;
  std::uint32_t node = 0;
  Vec2d waypoint_ne = Vec2d::Zero();  // route frame
};

class MavlinkStreams {
 public:
  MavlinkStreams(const DaemonConfig& c, MavlinkWire& wire) noexcept : cfg_(c), wire_(wire) {}
  // The streams due at s.now_ns into tx (the first call starts the schedule). guided_armed: the
  // autopilot reports GUIDED and armed. True when the 1 Hz slot was due (the caller's once-a-second work).
  bool publish(const MavSnapshot& s, bool guided_armed, SpscRing<MavBytes>& tx) noexcept;
  std::uint32_t odometry_sent() const noexcept { return odometry_sent_; }
  std::uint32_t targets_sent() const noexcept { return targets_sent_; }
  // The sample time of the first publish (time 0 of boot_ms and the logs).
  std::int64_t start_ns() const noexcept { return start_ns_; }

 private:
  std::uint32_t boot_ms(std::int64_t now_ns) const noexcept;
  // The first instant of the ODOMETRY grid (multiples of 1 / odometry_hz in sample time) after t.
  std::int64_t odometry_grid_after(std::int64_t t) const noexcept;
  void status_changes(const MavSnapshot& s, SpscRing<MavBytes>& tx) noexcept;
  // ODOMETRY, VISION_POSITION_DELTA and DISTANCE_SENSOR of one grid instant.
  void odometry(const MavSnapshot& s, const pipeline::NavEstimate& e, SpscRing<MavBytes>& tx) noexcept;
  void slow(const MavSnapshot& s, bool guided_armed, SpscRing<MavBytes>& tx) noexcept;

  const DaemonConfig& cfg_;
  MavlinkWire& wire_;
  std::uint32_t odometry_sent_ = 0, targets_sent_ = 0;
  bool started_ = false;
  std::int64_t start_ns_ = 0, next_hb_ns_ = 0, next_odo_ns_ = 0, next_slow_ns_ = 0;
  drivers::qnavcan::Mode last_mode_ = drivers::qnavcan::Mode::kIdle;
  std::uint16_t last_faults_ = 0;
  bool delta_base_ = false;
  std::int64_t delta_ns_ = 0;
  double delta_n_ = 0.0, delta_e_ = 0.0, delta_d_ = 0.0, delta_yaw_ = 0.0, delta_roll_ = 0.0, delta_pitch_ = 0.0;
  std::uint8_t delta_reset_ = 0;
};

}  // namespace qnav::daemon
