#include "nav/route/guidance.hpp"

#include <cmath>

namespace qnav::route {

const char* to_string(GuidanceStatus s) noexcept {
  switch (s) {
    case GuidanceStatus::kTracking: return "tracking";
    case GuidanceStatus::kDeadReckoned: return "dead_reckoned";
    case GuidanceStatus::kRouteEnd: return "route_end";
    case GuidanceStatus::kHoldCourse: break;
  }
  return "hold_course";
}
const char* to_string(RouteSide s) noexcept {
  switch (s) {
    case RouteSide::kPort: return "port";
    case RouteSide::kStarboard: return "starboard";
    case RouteSide::kOnRoute: break;
  }
  return "on_route";
}

GuidanceOutput Guidance::compute(bool confident, RouteDirection direction, const NodeMeta& node, const NodeMeta& ahead,
                                 const RegistrationResult& reg, double vehicle_heading_rad, const Pose2& sensed_nav_pose) noexcept {
  GuidanceOutput g;
  g.node = node.index;
  const bool finite_heading = std::isfinite(vehicle_heading_rad);
  const bool registered = reg.ok && reg.inliers >= config_.min_inliers && reg.sensed_to_node.is_finite();
  const bool nav_ok = sensed_nav_pose.is_finite();
  bool dead_reckon = false;
  if (confident && !registered && finite_heading && have_fix_ && nav_ok && config_.dead_reckon_max_m > 0.0) {
    const double travelled = (sensed_nav_pose.translation() - fix_nav_.translation()).norm();
    dead_reckon = travelled <= config_.dead_reckon_max_m;
  }
  if (!confident || !finite_heading || (!registered && !dead_reckon)) {
    g.status = GuidanceStatus::kHoldCourse;
    g.commanded_heading_rad = have_command_ ? last_command_rad_ : (finite_heading ? wrap_angle_rad(vehicle_heading_rad) : 0.0);
    return g;
  }
  // Vehicle pose in the route frame: from the registration, or carried from the last fix.
  const Pose2 vehicle = registered ? node.pose.compose(reg.sensed_to_node) : fix_route_.compose(fix_nav_.inverse().compose(sensed_nav_pose));
  const Pose2 in_node = node.pose.inverse().compose(vehicle);
  const double sign = direction == RouteDirection::kForward ? 1.0 : -1.0;
  g.along_track_m = sign * in_node.x_m;
  g.cross_track_m = sign * in_node.y_m;
  g.side = g.cross_track_m > config_.side_deadband_m ? RouteSide::kStarboard
           : (g.cross_track_m < -config_.side_deadband_m ? RouteSide::kPort : RouteSide::kOnRoute);
  g.heading_error_rad = wrap_angle_rad(in_node.heading_rad + (direction == RouteDirection::kForward ? 0.0 : kPi));
  g.waypoint_ne = ahead.pose.translation();
  const Vec2d rel = vehicle.inverse().apply(g.waypoint_ne);
  g.waypoint_bearing_rad = std::atan2(rel.y(), rel.x());
  g.commanded_heading_rad = wrap_angle_rad(vehicle_heading_rad + g.waypoint_bearing_rad);
  g.status = registered ? GuidanceStatus::kTracking : GuidanceStatus::kDeadReckoned;
  if (ahead.index == node.index && g.along_track_m > 0.0) {  // past the route's end
    g.status = GuidanceStatus::kRouteEnd;
    g.waypoint_bearing_rad = 0.0;
    g.commanded_heading_rad = wrap_angle_rad(vehicle_heading_rad);
  }
  if (registered && nav_ok) {
    have_fix_ = true;
    fix_route_ = vehicle;
    fix_nav_ = sensed_nav_pose;
  }
  have_command_ = true;
  last_command_rad_ = g.commanded_heading_rad;
  return g;
}

}  // namespace qnav::route
