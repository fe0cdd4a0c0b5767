// RouteAutopilot: the path-following law of an autopilot that steers ONLY on what qnav publishes
// (QNAV_ROUTE_GUIDANCE + QNAV_ROUTE_STATUS, docs/qnav.dbc) plus its own dead reckoning. The same
// class closes the loop in `qnav route follow --sim` and is meant for qnavd's sim vehicle; the law
// is written down in docs/route.md ("Closed loop: the autopilot law") for ArduSub / PX4.
//
// Per new fix (a ROUTE_STATUS whose TileSeq differs from the last one, paired with the
// ROUTE_GUIDANCE sent right before it), status Tracking or DeadReckoned:
//   anchor A  = the autopilot's own dead-reckoned pose guidance_age_s before the frame arrived
//               (qnav's offsets describe the vehicle at the sensed tile's centre, half a tile ago);
//   chi_r     = A.heading - HeadingError                    (route direction in the DR frame)
//   L         = A.position - CrossTrack * stbd(chi_r)       (a point on the route, DR frame)
// Every control step, with P the dead-reckoned position now and beta the DVL's sideslip
// (atan2(v_starboard, v_forward), bottom track; 0 when crab_compensation is off):
//   e         = (P - L) . stbd(chi_r)                         (cross-track now, + starboard)
//   chi_d     = chi_r - clamp(atan(k_e * e / lookahead_m), +-max_intercept_rad)   (LOS + gain)
//   heading   = chi_d - beta,  speed = cruise_speed_mps
// HoldCourse / NotRepeating (and before the first fix): course chi_hold = the last route
// direction (or the heading at reset), heading = chi_hold - beta. RouteEnd: stop (speed 0,
// heading held). stbd(h) = (-sin h, cos h) in (north, east); headings are compass (clockwise).
// Memory: a fixed ring of kHistory dead-reckoned poses (one per history_step_s); no heap.
// Time: on_frame O(signals); command() O(1); on_nav O(1); the history look-up O(kHistory).
#pragma once

#include <cstddef>
#include <cstdint>

#include "drivers/qnavcan/messages.hpp"
#include "hal/core/can.hpp"
#include "nav/core/counters.hpp"
#include "nav/core/geometry.hpp"
#include "nav/core/status.hpp"

namespace qnav::pipeline {

struct RouteAutopilotConfig {
  double lookahead_m = 100.0;         // LOS look-ahead distance Delta along the route
  double cross_track_gain = 1.0;      // k_e: multiplies the cross-track inside the LOS angle
  double max_intercept_rad = 0.5236;  // 30 deg: steepest approach to the route
  double guidance_age_s = 0.0;        // age of qnav's guidance when it arrives (tile duration / 2)
  double cruise_speed_mps = 1.5;
  bool crab_compensation = true;      // steer course over ground (DVL sideslip), not heading
};

enum class AutopilotMode : std::uint8_t { kHoldCourse, kFollowing, kStopped };
const char* to_string(AutopilotMode m) noexcept;

struct AutopilotCommand {
  AutopilotMode mode = AutopilotMode::kHoldCourse;
  double heading_rad = 0.0;       // compass heading to steer
  double speed_mps = 0.0;         // surge speed to hold
  double course_rad = 0.0;        // the course over ground wanted (heading + sideslip)
  double cross_track_m = 0.0;     // the autopilot's own estimate now (0 without a route line)
  bool has_line = false;          // a route line from a fix is known
};

// One piece of route guidance as the autopilot uses it (decoded from the bus, or computed by the
// dead-reckoning baseline against a taught track).
struct RouteFix {
  drivers::qnavcan::GuidanceState status = drivers::qnavcan::GuidanceState::kHoldCourse;
  double cross_track_m = 0.0;      // + vehicle to starboard of the route (direction of travel)
  double heading_error_rad = 0.0;  // vehicle heading - route heading
};

enum class AutopilotCounter : std::uint8_t { kFrames, kDecodeErrors, kFixes, kSteerFixes, kUnpairedStatus, kCount };
inline constexpr const char* kAutopilotCounterNames[] = {"frames", "decode_errors", "fixes", "steer_fixes", "unpaired_status"};

class RouteAutopilot {
 public:
  static constexpr std::size_t kHistory = 512;
  static constexpr double kHistoryStepS = 0.5;  // 256 s of history

  // Starts afresh: no route line, hold the heading of dr_pose, cruise.
  void reset(const RouteAutopilotConfig& config, std::int64_t t_ns, const Pose2& dr_pose) noexcept;
  // The vehicle's own dead reckoning (pose in its DR frame, compass heading) and the DVL's sideslip
  // (rad, + velocity to starboard of the heading) at t_ns. Non-finite values are ignored.
  void on_nav(std::int64_t t_ns, const Pose2& dr_pose, double sideslip_rad) noexcept;
  // A CAN frame off the bus at t_ns. ROUTE_GUIDANCE is held until its ROUTE_STATUS; a status with a
  // new TileSeq is one fix. Other ids: ignored (ok). Bad frames: the codec's error, counted.
  Status on_frame(const hal::CanFrame& frame, std::int64_t t_ns) noexcept;
  // One fix applied directly (the dead-reckoning baseline), taken as describing the vehicle
  // age_s before t_ns.
  void on_fix(const RouteFix& fix, std::int64_t t_ns, double age_s) noexcept;
  AutopilotCommand command() const noexcept;

  const CounterSet<AutopilotCounter>& counters() const noexcept { return counters_; }
  const RouteAutopilotConfig& config() const noexcept { return cfg_; }

 private:
  Pose2 pose_at(std::int64_t t_ns) const noexcept;
  RouteAutopilotConfig cfg_{};
  Pose2 pose_{};
  double sideslip_rad_ = 0.0;
  bool has_line_ = false, stopped_ = false, following_ = false;
  double chi_r_ = 0.0;     // route direction (DR frame)
  Vec2d line_pt_ = Vec2d::Zero();
  double chi_hold_ = 0.0;  // course held on HoldCourse
  double stop_heading_ = 0.0;
  bool have_guidance_ = false, have_seq_ = false;
  std::uint16_t last_seq_ = 0;
  drivers::qnavcan::RouteGuidance guidance_{};
  struct Hist {
    std::int64_t t_ns = 0;
    Pose2 pose{};
  };
  Hist hist_[kHistory];
  std::size_t hist_n_ = 0, hist_head_ = 0;  // head_ = next slot
  CounterSet<AutopilotCounter> counters_{kAutopilotCounterNames};
};

}  // namespace qnav::pipeline
