// Vehicle trajectories for the side-scan simulator: a route polyline flown forwards or in reverse,
// with a lateral offset, at constant speed and ping rate; TRUE poses (for rendering pings) and
// dead-reckoned NAV poses (heading + speed with seeded bias/noise, what the vehicle believes).
// Frames: north/east metres, compass heading (sonar_types.hpp). lateral_offset_m is measured to the
// RIGHT of the route's taught (forward) direction, whichever way the pass is flown, so a forward pass
// at +5 m and a reverse pass at +5 m fly the same line.
// With zero noise the nav pose equals the true pose exactly. Deterministic for a given seed.
// Cost: O(1) per ping (amortised segment walk); no heap (waypoints in a FixedVector).
#pragma once

#include <cstdint>

#include "nav/core/fixed_vector.hpp"
#include "nav/core/geometry.hpp"
#include "nav/core/status.hpp"

namespace qnav::sidescan {

struct TrajectoryConfig {
  FixedVector<Vec2d, 64> waypoints_ne;  // route polyline (north, east), >= 2 points
  double speed_mps = 1.5;
  double ping_rate_hz = 10.0;
  double altitude_m = 8.0;
  double lateral_offset_m = 0.0;        // + = right of the route's forward direction
  bool reverse = false;                 // fly from the last waypoint to the first
  double start_along_m = 0.0;           // skip this much route at the start of the pass
  // True motion disturbance: heading wobble (random walk, rad per sqrt(s)), bounded by max_yaw_rad.
  double yaw_walk_rad_per_sqrt_s = 0.0;
  double max_yaw_rad = 0.05;
  // Dead-reckoning errors.
  double heading_bias_rad = 0.0;
  double heading_noise_rad = 0.0;       // white, per ping
  double speed_scale_error = 0.0;       // measured = true * (1 + e)
  double speed_noise_mps = 0.0;         // white, per ping
  std::uint64_t seed = 7;
  std::uint64_t start_stamp_ns = 0;
};

struct TrajectorySample {
  std::uint32_t index = 0;     // ping index within the pass
  std::uint64_t stamp_ns = 0;
  Pose2 truth;                 // true pose (north, east, compass heading)
  Pose2 nav;                   // dead-reckoned pose
  double along_route_m = 0.0;  // distance from the route's FIRST waypoint along the route
  float altitude_m = 0.0f;
};

class Trajectory {
 public:
  Status init(const TrajectoryConfig& config) noexcept;
  // Next ping's poses; false at the end of the route.
  bool next(TrajectorySample& out) noexcept;
  double route_length_m() const noexcept { return length_m_; }
  // Point and forward direction of the route (no offset) at distance s from the first waypoint.
  void route_at(double s, Vec2d& point_ne, double& heading_rad) const noexcept;
  std::uint32_t pings_total() const noexcept;

 private:
  double gauss() noexcept;
  TrajectoryConfig cfg_{};
  FixedVector<double, 64> cum_;  // cumulative length at each waypoint
  double length_m_ = 0.0;
  std::uint32_t index_ = 0;
  std::uint64_t rng_ = 0;
  double yaw_ = 0.0;
  Pose2 nav_{};
  Pose2 prev_truth_{};
  bool started_ = false;
};

}  // namespace qnav::sidescan
