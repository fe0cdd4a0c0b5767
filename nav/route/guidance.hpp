// Guidance: from the estimated node and the registration to it, what the autopilot needs.
//  - the vehicle's position in the node's tile frame is T.apply(0) (T: sensed tile -> node tile,
//    the sensed tile's origin is the vehicle's position at the tile centre): along-track offset and
//    cross-track offset, signed in the direction of travel (reverse passes flip both);
//  - side: which side of the route the vehicle lies on (starboard / port of the route's direction
//    of travel, on_route inside the dead band) -- the paper's Fig. 10 determination -- decided only
//    when the cross-track offset is clear of the dead band by side_n_sigma of its uncertainty
//    (cross_track_sigma_m); otherwise kUnknown;
//  - heading error: vehicle heading minus the route's heading in the direction of travel;
//  - steering: a look-ahead waypoint lookahead_nodes ahead on the route (the paper's future-work
//    control strategy) expressed as a bearing relative to the vehicle heading and a commanded
//    compass heading.
// Status kTracking: the filter is confident and the registration to the estimated node (or a
// neighbour) has at least min_inliers inliers.
// Status kDeadReckoned: confident, no such registration now, but one within dead_reckon_max_m of
// travel: the vehicle's route-frame pose at that fix is carried forward by the dead-reckoned motion
// since (nav pose of the fix tile -> nav pose of this tile), and the offsets are taken against the
// estimated node. Cross-track error then grows with the heading error of the dead reckoning.
// Status kRouteEnd: tracking or dead-reckoned, but past the last node in the direction of travel
// (the look-ahead node is the estimated node and the vehicle is ahead of it): offsets and side are
// reported, the commanded heading is the current heading (no turn back to the last waypoint).
// Otherwise the paper's default strategy: hold course (commanded heading = last good command, or the
// current heading), status kHoldCourse, side kUnknown -- except that a registration with at least
// unconfident_min_inliers inliers (0 = off) still gives the offsets and the side while the filter is
// not yet confident (the status stays kHoldCourse and nothing is steered on it, but the operator
// learns which side of the route the vehicle is on; that registration is also a fix for dead
// reckoning), and that a confident filter beyond dead_reckon_max_m of travel from the last fix but
// within dead_reckon_side_max_m still reports the dead-reckoned offsets and side (status kHoldCourse:
// too far to steer on, not too far to know the side when the offset is large).
// Verification of a registration against dead reckoning (verify_gate_m > 0): with a fix less than
// dead_reckon_side_max_m of travel back, a registration whose vehicle position (route frame) lies
// more than verify_gate_m + verify_n_sigma x sigma from where dead reckoning from that fix puts it
// (sigma: the registration's cross-track sigma and the dead-reckoned one, root-sum-square) is a
// wrong transform until a second registration confirms it: it is not steered on, gives no side and
// is no fix (the offsets are dead-reckoned from the last fix as if it had not registered;
// GuidanceOutput::registration_rejected). The next registration that disagrees with dead reckoning
// is accepted when it agrees, by the same gate, with the rejected one carried forward by the
// dead-reckoned motion (then it was the last fix that was wrong, and the vehicle recovers after one
// tile). A registration that agrees with dead reckoning clears the rejected one.
// Cross-track uncertainty: from the registration's covariance; dead-reckoned, the fix's plus
// dead_reckon_heading_sigma_rad x the distance travelled since the fix (the heading error of the
// dead reckoning turns travel into cross-track error). Pure function of its inputs + the held
// command and fix; O(1), no heap.
#pragma once

#include <cstdint>

#include "nav/core/geometry.hpp"
#include "nav/core/status.hpp"
#include "nav/route/registration.hpp"
#include "nav/route/route_filter.hpp"
#include "nav/route/route_types.hpp"

namespace qnav::route {

enum class GuidanceStatus : std::uint8_t { kTracking, kHoldCourse, kDeadReckoned, kRouteEnd };
enum class RouteSide : std::int8_t { kPort = -1, kOnRoute = 0, kStarboard = 1, kUnknown = 2 };
enum class OffsetSource : std::uint8_t { kNone, kRegistration, kDeadReckoning };  // where the offsets came from
const char* to_string(GuidanceStatus s) noexcept;
const char* to_string(RouteSide s) noexcept;
const char* to_string(OffsetSource s) noexcept;

struct GuidanceConfig {
  double lookahead_nodes = 2.0;
  double side_deadband_m = 0.5;
  std::uint32_t min_inliers = 0;  // a registration with fewer inliers is not steered on (hold course)
  double dead_reckon_max_m = 0.0;  // travel after the last fix still steered on dead reckoning; 0 = never
  double dead_reckon_side_max_m = 0.0;  // ... over which, holding course, the dead-reckoned offsets and side are still reported
  double dead_reckon_heading_sigma_rad = 0.01;  // heading error of the dead reckoning (cross-track sigma growth per metre)
  std::uint32_t unconfident_min_inliers = 0;    // side from a registration this strong before the filter is confident; 0 = off
  double side_n_sigma = 2.0;                    // side decided when |cross-track| is this many sigma clear of the dead band
  double verify_gate_m = 0.0;   // a registration this far (+ verify_n_sigma sigma) from dead reckoning needs confirming; 0 = off
  double verify_n_sigma = 3.0;
};

struct GuidanceOutput {
  GuidanceStatus status = GuidanceStatus::kHoldCourse;
  std::uint32_t node = 0;
  double along_track_m = 0.0;      // + ahead of the node in the direction of travel
  double cross_track_m = 0.0;      // + vehicle to starboard of the route
  double cross_track_sigma_m = 0.0;  // 1-sigma uncertainty of cross_track_m (0 when no offsets are reported)
  OffsetSource offsets = OffsetSource::kNone;  // kNone: offsets, side and heading error not known (all 0 / kUnknown)
  RouteSide side = RouteSide::kUnknown;
  double heading_error_rad = 0.0;  // vehicle heading - route heading (direction of travel)
  Vec2d waypoint_ne = Vec2d::Zero();  // look-ahead waypoint, route frame (north, east)
  double waypoint_bearing_rad = 0.0;  // relative to the vehicle heading, + to starboard
  double commanded_heading_rad = 0.0; // compass
  bool registration_rejected = false;  // the registration disagreed with dead reckoning from the last fix (not used)
};

class Guidance {
 public:
  explicit Guidance(const GuidanceConfig& c = GuidanceConfig{}) noexcept : config_(c) {}
  // node/ahead: the estimated node and the look-ahead node's metadata (route frame poses);
  // vehicle_heading_rad: compass heading now. reg: registration of the sensed tile to `node`.
  // sensed_nav_pose: the sensed tile's pose in the pass's dead-reckoned frame (for kDeadReckoned).
  GuidanceOutput compute(bool confident, RouteDirection direction, const NodeMeta& node, const NodeMeta& ahead,
                         const RegistrationResult& reg, double vehicle_heading_rad, const Pose2& sensed_nav_pose = Pose2{}) noexcept;
  void reset() noexcept {
    have_command_ = false;
    have_fix_ = false;
    have_pending_ = false;
  }

 private:
  RouteSide decide_side(double cross_track_m, double sigma_m) const noexcept;
  // Whether a registration putting the vehicle at `vehicle` (route frame, cross-track sigma reg_sigma_m)
  // agrees with a fix (route pose, nav pose, sigma) carried to sensed_nav_pose by dead reckoning.
  bool agrees(const Pose2& vehicle, double reg_sigma_m, const Pose2& fix_route, const Pose2& fix_nav, double fix_sigma_m,
              const Pose2& sensed_nav_pose) const noexcept;
  GuidanceConfig config_;
  bool have_command_ = false;
  double last_command_rad_ = 0.0;
  bool have_fix_ = false;
  Pose2 fix_route_{};  // vehicle pose in the route frame at the last registration used
  Pose2 fix_nav_{};    // the same instant in the pass's dead-reckoned frame
  double fix_sigma_m_ = 0.0;  // cross-track sigma at the fix
  bool have_pending_ = false;  // a registration rejected by the verification, awaiting confirmation
  Pose2 pending_route_{};
  Pose2 pending_nav_{};
  double pending_sigma_m_ = 0.0;
};

}  // namespace qnav::route
