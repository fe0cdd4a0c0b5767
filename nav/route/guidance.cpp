#include "nav/route/guidance.hpp"

#include <cmath>
#include <limits>

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
    case RouteSide::kOnRoute: return "on_route";
    case RouteSide::kUnknown: break;
  }
  return "unknown";
}

RouteSide Guidance::decide_side(double cross_track_m, double sigma_m) const noexcept {
  if (!std::isfinite(cross_track_m) || !std::isfinite(sigma_m)) return RouteSide::kUnknown;
  const double margin = config_.side_n_sigma * sigma_m;
  if (cross_track_m > config_.side_deadband_m + margin) return RouteSide::kStarboard;
  if (cross_track_m < -(config_.side_deadband_m + margin)) return RouteSide::kPort;
  if (std::abs(cross_track_m) + margin <= config_.side_deadband_m) return RouteSide::kOnRoute;
  return RouteSide::kUnknown;
}

const char* to_string(OffsetSource s) noexcept {
  switch (s) {
    case OffsetSource::kRegistration: return "registration";
    case OffsetSource::kDeadReckoning: return "dead_reckoning";
    case OffsetSource::kNone: break;
  }
  return "none";
}

bool Guidance::agrees(const Pose2& vehicle, double reg_sigma_m, const Pose2& fix_route, const Pose2& fix_nav, double fix_sigma_m,
                      const Pose2& sensed_nav_pose) const noexcept {
  const double travelled = (sensed_nav_pose.translation() - fix_nav.translation()).norm();
  const Pose2 dr = fix_route.compose(fix_nav.inverse().compose(sensed_nav_pose));
  const double dr_sigma = fix_sigma_m + config_.dead_reckon_heading_sigma_rad * travelled;
  const double sigma = std::sqrt(reg_sigma_m * reg_sigma_m + dr_sigma * dr_sigma);
  return (vehicle.translation() - dr.translation()).norm() <= config_.verify_gate_m + config_.verify_n_sigma * sigma;
}

GuidanceOutput Guidance::compute(bool confident, RouteDirection direction, const NodeMeta& node, const NodeMeta& ahead,
                                 const RegistrationResult& reg, double vehicle_heading_rad, const Pose2& sensed_nav_pose) noexcept {
  GuidanceOutput g;
  g.node = node.index;
  const bool finite_heading = std::isfinite(vehicle_heading_rad);
  bool reg_usable = reg.ok && reg.sensed_to_node.is_finite();
  const bool nav_ok = sensed_nav_pose.is_finite();
  // Verification against dead reckoning from the last fix (a wrong transform is rejected until a
  // second registration confirms it).
  // Only a registration guidance would use is verified: steered on, or strong enough for the side.
  const bool would_use = (confident && reg.inliers >= config_.min_inliers) ||
                         (config_.unconfident_min_inliers > 0 && reg.inliers >= config_.unconfident_min_inliers);
  if (reg_usable && would_use && config_.verify_gate_m > 0.0 && nav_ok) {
    const Pose2 vehicle = node.pose.compose(reg.sensed_to_node);
    const double var = reg.covariance(1, 1);
    const double reg_sigma = std::isfinite(var) && var > 0.0 ? std::sqrt(var) : 0.0;
    const bool fix_recent = have_fix_ && (sensed_nav_pose.translation() - fix_nav_.translation()).norm() <= config_.dead_reckon_side_max_m;
    const bool pending_recent = have_pending_ && (sensed_nav_pose.translation() - pending_nav_.translation()).norm() <= config_.dead_reckon_side_max_m;
    if (!fix_recent || agrees(vehicle, reg_sigma, fix_route_, fix_nav_, fix_sigma_m_, sensed_nav_pose)) {
      have_pending_ = false;
    } else if (pending_recent && agrees(vehicle, reg_sigma, pending_route_, pending_nav_, pending_sigma_m_, sensed_nav_pose)) {
      have_pending_ = false;  // confirmed: the last fix was the wrong one
    } else {
      have_pending_ = true;
      pending_route_ = vehicle;
      pending_nav_ = sensed_nav_pose;
      pending_sigma_m_ = reg_sigma;
      reg_usable = false;
      g.registration_rejected = true;
    }
  }
  const bool registered = reg_usable && reg.inliers >= config_.min_inliers;
  // Dead reckoning from the last fix (the node estimate must be trusted: confident filter).
  const bool can_dead_reckon = confident && !registered && have_fix_ && nav_ok;
  const double travelled = can_dead_reckon ? (sensed_nav_pose.translation() - fix_nav_.translation()).norm() : 0.0;
  const bool dead_reckon = can_dead_reckon && finite_heading && config_.dead_reckon_max_m > 0.0 && travelled <= config_.dead_reckon_max_m;
  const bool steer = confident && finite_heading && (registered || dead_reckon);
  // Not steered on, but enough to say which side of the route the vehicle is on: a strong
  // registration while the filter is not yet confident, or dead reckoning a little further.
  const bool strong_reg = reg_usable && config_.unconfident_min_inliers > 0 && reg.inliers >= config_.unconfident_min_inliers;
  const bool side_reg = !steer && strong_reg;
  const bool side_dr = !steer && !side_reg && can_dead_reckon && travelled <= config_.dead_reckon_side_max_m;
  const double held = have_command_ ? last_command_rad_ : (finite_heading ? wrap_angle_rad(vehicle_heading_rad) : 0.0);
  if (!steer && !side_reg && !side_dr) {
    g.status = GuidanceStatus::kHoldCourse;
    g.commanded_heading_rad = held;
    return g;
  }
  // Vehicle pose in the route frame: from the registration, or carried from the last fix.
  const bool from_reg = registered || side_reg;
  g.offsets = from_reg ? OffsetSource::kRegistration : OffsetSource::kDeadReckoning;
  const Pose2 vehicle = from_reg ? node.pose.compose(reg.sensed_to_node) : fix_route_.compose(fix_nav_.inverse().compose(sensed_nav_pose));
  const Pose2 in_node = node.pose.inverse().compose(vehicle);
  const double sign = direction == RouteDirection::kForward ? 1.0 : -1.0;
  g.along_track_m = sign * in_node.x_m;
  g.cross_track_m = sign * in_node.y_m;
  // From a registration, in_node's translation is the registration's: its y variance is the
  // cross-track variance (a broken covariance gives an infinite sigma: no side, no fix).
  const double var = reg.covariance(1, 1);
  g.cross_track_sigma_m = !from_reg           ? fix_sigma_m_ + config_.dead_reckon_heading_sigma_rad * travelled
                          : std::isfinite(var) ? std::sqrt(var > 0.0 ? var : 0.0)
                                               : std::numeric_limits<double>::infinity();
  g.side = decide_side(g.cross_track_m, g.cross_track_sigma_m);
  g.heading_error_rad = wrap_angle_rad(in_node.heading_rad + (direction == RouteDirection::kForward ? 0.0 : kPi));
  if (from_reg && nav_ok && std::isfinite(g.cross_track_sigma_m)) {
    have_fix_ = true;
    fix_route_ = vehicle;
    fix_nav_ = sensed_nav_pose;
    fix_sigma_m_ = g.cross_track_sigma_m;
  }
  if (!steer) {
    g.status = GuidanceStatus::kHoldCourse;
    g.commanded_heading_rad = held;
    return g;
  }
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
  have_command_ = true;
  last_command_rad_ = g.commanded_heading_rad;
  return g;
}

}  // namespace qnav::route
