#include "nav/route/guidance.hpp"

#include <cmath>

namespace qnav::route {

const char* to_string(GuidanceStatus s) noexcept { return s == GuidanceStatus::kTracking ? "tracking" : "hold_course"; }
const char* to_string(RouteSide s) noexcept {
  switch (s) {
    case RouteSide::kPort: return "port";
    case RouteSide::kStarboard: return "starboard";
    case RouteSide::kOnRoute: break;
  }
  return "on_route";
}

GuidanceOutput Guidance::compute(bool confident, RouteDirection direction, const NodeMeta& node, const NodeMeta& ahead,
                                 const RegistrationResult& reg, double vehicle_heading_rad) noexcept {
  GuidanceOutput g;
  g.node = node.index;
  const bool finite_heading = std::isfinite(vehicle_heading_rad);
  if (!confident || !reg.ok || reg.inliers < config_.min_inliers || !reg.sensed_to_node.is_finite() || !finite_heading) {
    g.status = GuidanceStatus::kHoldCourse;
    g.commanded_heading_rad = have_command_ ? last_command_rad_ : (finite_heading ? wrap_angle_rad(vehicle_heading_rad) : 0.0);
    return g;
  }
  const double sign = direction == RouteDirection::kForward ? 1.0 : -1.0;
  g.along_track_m = sign * reg.sensed_to_node.x_m;
  g.cross_track_m = sign * reg.sensed_to_node.y_m;
  g.side = g.cross_track_m > config_.side_deadband_m ? RouteSide::kStarboard
           : (g.cross_track_m < -config_.side_deadband_m ? RouteSide::kPort : RouteSide::kOnRoute);
  g.heading_error_rad = wrap_angle_rad(reg.sensed_to_node.heading_rad + (direction == RouteDirection::kForward ? 0.0 : kPi));
  // Vehicle pose in the route frame, from the node pose and the registration.
  const Pose2 vehicle = node.pose.compose(reg.sensed_to_node);
  g.waypoint_ne = ahead.pose.translation();
  const Vec2d rel = vehicle.inverse().apply(g.waypoint_ne);
  g.waypoint_bearing_rad = std::atan2(rel.y(), rel.x());
  g.commanded_heading_rad = wrap_angle_rad(vehicle_heading_rad + g.waypoint_bearing_rad);
  g.status = GuidanceStatus::kTracking;
  have_command_ = true;
  last_command_rad_ = g.commanded_heading_rad;
  return g;
}

}  // namespace qnav::route
