// RouteAutopilot: the path-following law of an autopilot that steers ONLY on what qnav publishes
// (QNAV_ROUTE_GUIDANCE + QNAV_ROUTE_STATUS, docs/qnav.dbc), the taught track it recorded itself and
// its own dead reckoning. The same class closes the loop in `qnav route follow --sim` (both the
// qnav-guided vehicle and the dead-reckoning-only baseline) and is meant for qnavd's sim vehicle; the
// law is written down in docs/route.md ("Closed loop: the autopilot law") for ArduSub / PX4.
//
// The taught track: the autopilot's own dead-reckoned poses logged while qnav taught the route (every
// few metres, from the teach's first to its last pose, route order) in the TEACH frame, and for each
// node the index of its pose in that log (node_at[i]: the pose logged when NAV_STATUS.NodeIndex
// reported node i; the route file's node poses are the same numbers). T maps the autopilot's
// dead-reckoned frame NOW into the teach frame.
// Per new fix (a ROUTE_STATUS whose TileSeq differs from the last, paired with the ROUTE_GUIDANCE sent
// right before it) with status Tracking or DeadReckoned, node n = TargetNode:
//   A  = own dead-reckoned pose guidance_age_m of own travel (or guidance_age_s) before the frame
//        arrived (qnav's offsets describe the vehicle at the sensed tile's centre, half a tile earlier);
//   in = (sgn * (spacing - DistToNext), sgn * CrossTrack, HeadingError - (reverse ? pi : 0)),
//        sgn = +1 forward / -1 reverse, spacing = the track's mean node spacing;
//   V  = track[node_at[n]] (+) in          (the vehicle in the teach frame at A's time)
//   T  = V (+) A^-1
// Every control step, P = T (+) own dead-reckoned position now; on the track in the direction of
// travel: foot point F at along-track s (searched near the last one), cross-track e (+ starboard),
// carrot C = the track point at s + lookahead_m (the track extended past its end):
//   chi_d  = bearing(F -> C) - clamp(atan(k_e * e / lookahead_m), +-max_intercept_rad)   (teach frame)
//   course = chi_d - T.heading        (own frame),  heading = course - beta,  speed = cruise
// beta = the DVL's sideslip atan2(v_starboard, v_forward) (0 when crab_compensation is off).
// HoldCourse / NotRepeating: hold the course steered when it arrived (before any fix: the heading
// at reset); with follow_track_on_hold and a frame, keep following the track on dead reckoning.
// RouteEnd: with a frame, keep following the track with the last frame (later Tracking /
// DeadReckoned fixes still re-anchor it, HoldCourse does not stop it) up to the track's end; without
// one, stop at once. s past the track's end while following: stop (speed 0, heading held).
// The dead-reckoning-only baseline is the same law with T set once (set_frame) and no frames.
// stbd(h) = (-sin h, cos h) in (north, east); headings are compass (clockwise from north).
// Memory: the borrowed track (caller storage) and a fixed ring of kHistory poses; no heap.
// Time: on_frame O(signals); command() O(search window); the history look-up O(kHistory).
#pragma once

#include <cstddef>
#include <cstdint>

#include "drivers/qnavcan/messages.hpp"
#include "hal/core/can.hpp"
#include "nav/core/counters.hpp"
#include "nav/core/geometry.hpp"
#include "nav/core/span.hpp"
#include "nav/core/status.hpp"

namespace qnav::pipeline {

struct RouteAutopilotConfig {
  double lookahead_m = 25.0;      // LOS look-ahead distance Delta along the track (route follow: 25 m best of 25-100)
  double cross_track_gain = 1.0;  // k_e: multiplies the cross-track inside the LOS angle
  double max_intercept_rad = 0.5236;  // 30 deg: steepest approach to the route
  double guidance_age_s = 0.0;        // age of qnav's guidance when it arrives (tile duration / 2)
  // > 0: the age as own dead-reckoned travel instead (tiles sized in metres: half the tile length);
  // guidance_age_s is then not used. The vehicle's speed over ground (current) does not change it.
  double guidance_age_m = 0.0;
  double cruise_speed_mps = 1.5;
  bool reverse = false;           // the route is followed from its end to its start
  bool crab_compensation = true;  // steer course over ground (DVL sideslip), not heading
  // HoldCourse / NotRepeating with a frame known (a past fix, or set_frame at the start): keep
  // following the taught track on dead reckoning instead of holding a straight course.
  bool follow_track_on_hold = false;
};

enum class AutopilotMode : std::uint8_t { kHoldCourse, kFollowing, kStopped };
const char* to_string(AutopilotMode m) noexcept;

struct AutopilotCommand {
  AutopilotMode mode = AutopilotMode::kHoldCourse;
  double heading_rad = 0.0;    // compass heading to steer
  double speed_mps = 0.0;      // surge speed to hold
  double course_rad = 0.0;     // the course over ground wanted (heading + sideslip)
  double cross_track_m = 0.0;  // the autopilot's own estimate now (0 without a frame)
  double along_m = 0.0;        // along the taught track in the direction of travel (teach frame)
  bool has_line = false;       // the frame onto the taught track is known
};

// One piece of route guidance as the autopilot uses it (decoded from the bus, or computed by the
// dead-reckoning baseline against a taught track).
struct RouteFix {
  drivers::qnavcan::GuidanceState status = drivers::qnavcan::GuidanceState::kHoldCourse;
  double cross_track_m = 0.0;      // + vehicle to starboard of the route (direction of travel)
  double heading_error_rad = 0.0;  // vehicle heading - route heading
  double dist_to_next_m = 0.0;     // to the next node in the direction of travel
  std::uint32_t node = 0;          // the node the offsets refer to (TargetNode)
};

enum class AutopilotCounter : std::uint8_t { kFrames, kDecodeErrors, kFixes, kSteerFixes, kUnpairedStatus, kCount };
inline constexpr const char* kAutopilotCounterNames[] = {"frames", "decode_errors", "fixes", "steer_fixes",
                                                         "unpaired_status"};

class RouteAutopilot {
 public:
  static constexpr std::size_t kHistory = 512;
  static constexpr double kHistoryStepS = 0.5;  // 256 s of history

  // Starts afresh: no frame (hold the heading of dr_pose), cruise. track, node_at: the taught track as
  // above (>= 2 poses, >= 1 node, indices increasing and inside the track; borrowed: they must outlive
  // the autopilot's use). kInvalidArgument otherwise.
  Status reset(const RouteAutopilotConfig& config, Span<const Pose2> track, Span<const std::uint32_t> node_at,
               std::int64_t t_ns, const Pose2& dr_pose) noexcept;
  // Follows the track now with a known frame (dead reckoning -> teach frame): the baseline, or a
  // vehicle that knows where it starts on the route.
  void set_frame(const Pose2& dr_to_teach) noexcept;
  // The vehicle's own dead reckoning (pose in its DR frame, compass heading) and the DVL's sideslip
  // (rad, + velocity to starboard of the heading) at t_ns. Non-finite values are ignored.
  void on_nav(std::int64_t t_ns, const Pose2& dr_pose, double sideslip_rad) noexcept;
  // A CAN frame off the bus at t_ns. ROUTE_GUIDANCE is held until its ROUTE_STATUS; a status with a
  // new TileSeq is one fix. Other ids: ignored (ok). Bad frames: the codec's error, counted.
  Status on_frame(const hal::CanFrame& frame, std::int64_t t_ns) noexcept;
  // One fix applied directly (as decoded), describing the vehicle age_s before t_ns.
  void on_fix(const RouteFix& fix, std::int64_t t_ns, double age_s) noexcept;
  // The command now; also advances the foot-point search (call once per control step).
  AutopilotCommand command() noexcept;

  const CounterSet<AutopilotCounter>& counters() const noexcept { return counters_; }
  const RouteAutopilotConfig& config() const noexcept { return cfg_; }

 private:
  Pose2 pose_at(std::int64_t t_ns) const noexcept;
  Pose2 pose_travelled_back(double back_m) const noexcept;
  Vec2d pt(std::size_t i) const noexcept;  // track point i in the direction of travel
  void locate(const Vec2d& p, double& along_m, double& cross_m, Vec2d& foot, std::size_t& seg) const noexcept;
  Vec2d point_at(double along_m) const noexcept;
  RouteAutopilotConfig cfg_{};
  Span<const Pose2> track_{};
  Span<const std::uint32_t> node_at_{};
  std::size_t seg_hint_ = 0;  // segment of the last foot point (travel order)
  double cum_hint_ = 0.0;     // along-track at the start of that segment
  double spacing_m_ = 0.0, track_length_m_ = 0.0;
  Pose2 pose_{};
  double sideslip_rad_ = 0.0;
  bool has_line_ = false, stopped_ = false, following_ = false;
  bool route_end_ = false;  // RouteEnd arrived with a frame: following the track on to its end
  Pose2 dr_to_teach_{};
  double chi_hold_ = 0.0;  // course held on HoldCourse (own frame)
  double last_course_ = 0.0;
  double stop_heading_ = 0.0;
  bool have_guidance_ = false, have_seq_ = false;
  std::uint16_t last_seq_ = 0;
  drivers::qnavcan::RouteGuidance guidance_{};
  struct Hist {
    std::int64_t t_ns = 0;
    Pose2 pose{};
    double travelled_m = 0.0;  // own dead-reckoned travel since reset
  };
  double travelled_m_ = 0.0;
  Hist hist_[kHistory];
  std::size_t hist_n_ = 0, hist_head_ = 0;  // head_ = next slot
  CounterSet<AutopilotCounter> counters_{kAutopilotCounterNames};
};

}  // namespace qnav::pipeline
