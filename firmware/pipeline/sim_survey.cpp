#include "firmware/pipeline/sim_survey.hpp"

#include <cmath>

#include "firmware/pipeline/route_defaults.hpp"

namespace qnav::pipeline {

Status SimSurvey::init(double length_m, std::uint64_t seed) {
  if (!(length_m >= 200.0 && length_m <= 50000.0)) return Status(StatusCode::kOutOfRange, "sim survey: length_m outside [200, 50000]");
  sonar = default_route_sonar_config();
  QNAV_RETURN_IF_ERROR(seabed.init(default_route_seabed_config(seed)));
  const double l = length_m;
  route.waypoints_ne.clear();
  QNAV_RETURN_IF_ERROR(route.waypoints_ne.push_back(Vec2d(0.0, 0.0)));
  QNAV_RETURN_IF_ERROR(route.waypoints_ne.push_back(Vec2d(0.35 * l, 0.08 * l)));
  QNAV_RETURN_IF_ERROR(route.waypoints_ne.push_back(Vec2d(0.68 * l, 0.05 * l)));
  QNAV_RETURN_IF_ERROR(route.waypoints_ne.push_back(Vec2d(0.98 * l, 0.22 * l)));
  route.speed_mps = 1.5;
  route.ping_rate_hz = 5.0;
  route.altitude_m = 8.0;
  route.seed = teach_pass_seed(seed);
  // Dead reckoning as a DVL + compass would give it.
  route.heading_bias_rad = 0.004;
  route.heading_noise_rad = 0.002;
  route.speed_scale_error = 0.005;
  route.speed_noise_mps = 0.01;
  route.yaw_walk_rad_per_sqrt_s = 0.002;
  route.max_yaw_rad = 0.03;
  const double r = static_cast<double>(sonar.slant_range_m);
  const double g = std::sqrt(r * r - route.altitude_m * route.altitude_m);
  swath_m = 2.0 * g;
  return Status::ok();
}

sidescan::SideScanSimConfig SimSurvey::sonar_for(std::uint64_t seed) const {
  sidescan::SideScanSimConfig s = sonar;
  s.seed = 0x9E3779B9ull * (seed + 1);
  return s;
}
sidescan::TrajectoryConfig SimSurvey::pass(double lateral_m, bool reverse, std::uint64_t seed) const {
  sidescan::TrajectoryConfig t = route;
  t.lateral_offset_m = lateral_m;
  t.reverse = reverse;
  t.seed = seed;
  t.heading_bias_rad = reverse ? -0.003 : 0.004;
  return t;
}

}  // namespace qnav::pipeline
