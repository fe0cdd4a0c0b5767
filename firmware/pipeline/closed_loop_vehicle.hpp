// ClosedLoopVehicle: a simulated vehicle that flies the commands of an autopilot. Dynamics: surge
// speed with an acceleration limit, a heading loop on the COMPASS heading with yaw-rate and
// yaw-acceleration limits, and an unmodelled water current added to the velocity over ground; the
// TRUE pose is integrated per step. Sensors: a compass (true heading + bias + white noise) and a
// bottom-tracking DVL (body velocity over ground x (1 + scale error) + white noise) with dropouts
// (seeded: start every ~dropout_every_s on average, last dropout_min_s..dropout_max_s) during which
// dead reckoning runs on the commanded speed through the water, so the current carries the vehicle
// where dead reckoning does not see it. Dead reckoning: pipeline::DeadReckoner on those samples.
// Memory: the members only; no heap. Time: O(1) per step. Deterministic for a seed.
#pragma once

#include <cstdint>

#include "firmware/pipeline/dead_reckoner.hpp"
#include "nav/core/geometry.hpp"

namespace qnav::pipeline {

struct VehicleDynamicsConfig {
  double yaw_rate_max_radps = 0.10;    // 5.7 deg/s
  double yaw_accel_max_radps2 = 0.05;  // 2.9 deg/s^2
  double heading_gain_per_s = 0.5;     // yaw-rate demand per rad of compass heading error
  double surge_accel_max_mps2 = 0.2;
  Vec2d current_ne = Vec2d::Zero();  // water current (north, east), m/s, unknown to the vehicle
};

struct DriftConfig {
  double heading_bias_rad = 0.0;  // compass: true + bias + noise
  double heading_noise_rad = 0.002;
  double dvl_scale_error = 0.0;  // DVL: (1 + e) x true
  double dvl_noise_mps = 0.01;
  double dropout_every_s = 600.0;  // mean time between DVL dropouts (0 = none)
  double dropout_min_s = 10.0, dropout_max_s = 40.0;
  std::uint64_t seed = 1;
};

class ClosedLoopVehicle {
 public:
  // truth: the true start pose; dr_start: where dead reckoning starts (its frame), heading from the
  // compass; speed_mps: initial surge speed.
  void reset(const VehicleDynamicsConfig& dyn, const DriftConfig& drift, const Pose2& truth, const Pose2& dr_start,
             double speed_mps, std::int64_t t_ns) noexcept;
  // Flies dt_s towards the commanded compass heading and surge speed, then samples the sensors.
  void step(double dt_s, double heading_cmd_rad, double speed_cmd_mps) noexcept;

  std::int64_t t_ns() const noexcept { return t_ns_; }
  const Pose2& truth() const noexcept { return truth_; }
  Pose2 dr_pose() const noexcept { return dr_.pose_at(t_ns_); }
  double dr_distance_m() const noexcept { return dr_.distance_m(); }
  double compass_rad() const noexcept { return compass_; }
  // Sideslip the DVL sees (atan2(starboard, forward)); the last good value during a dropout.
  double sideslip_rad() const noexcept { return sideslip_; }
  bool dvl_lost() const noexcept { return dropout_left_s_ > 0.0; }
  double travelled_m() const noexcept { return travelled_m_; }  // true path length
  double speed_mps() const noexcept { return u_; }
  double dropout_total_s() const noexcept { return dropout_total_s_; }

 private:
  double uniform() noexcept;
  double gauss() noexcept;
  void sample_sensors(double dt_s, double speed_cmd_mps) noexcept;
  VehicleDynamicsConfig dyn_{};
  DriftConfig drift_{};
  DeadReckoner dr_{1.0};
  Pose2 truth_{};
  double u_ = 0.0, r_ = 0.0;
  double compass_ = 0.0, sideslip_ = 0.0;
  double dropout_left_s_ = 0.0, dropout_total_s_ = 0.0;
  double travelled_m_ = 0.0;
  std::int64_t t_ns_ = 0;
  std::uint64_t rng_ = 1;
};

}  // namespace qnav::pipeline
