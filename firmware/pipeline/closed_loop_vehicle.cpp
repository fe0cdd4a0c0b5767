#include "firmware/pipeline/closed_loop_vehicle.hpp"

#include <algorithm>
#include <cmath>

namespace qnav::pipeline {

double ClosedLoopVehicle::uniform() noexcept {
  rng_ ^= rng_ << 13;
  rng_ ^= rng_ >> 7;
  rng_ ^= rng_ << 17;
  return (static_cast<double>(rng_ >> 11) + 0.5) * (1.0 / 9007199254740992.0);
}
double ClosedLoopVehicle::gauss() noexcept {
  const double u1 = uniform(), u2 = uniform();
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * kPi * u2);
}

void ClosedLoopVehicle::reset(const VehicleDynamicsConfig& dyn, const DriftConfig& drift, const Pose2& truth,
                              const Pose2& dr_start, double speed_mps, std::int64_t t_ns) noexcept {
  dyn_ = dyn;
  drift_ = drift;
  truth_ = truth;
  u_ = speed_mps;
  r_ = 0.0;
  dropout_left_s_ = dropout_total_s_ = travelled_m_ = 0.0;
  t_ns_ = t_ns;
  rng_ = drift.seed * 0x9E3779B97F4A7C15ULL + 0x2545F4914F6CDD1DULL;
  if (rng_ == 0) rng_ = 1;
  dr_.clear();
  dr_.reset(dr_start);
  sideslip_ = 0.0;
  sample_sensors(0.0, speed_mps);
}

void ClosedLoopVehicle::step(double dt_s, double heading_cmd_rad, double speed_cmd_mps) noexcept {
  // Heading loop on the compass: yaw-rate demand, limited, reached under the yaw-acceleration limit.
  const double err = std::isfinite(heading_cmd_rad) ? wrap_angle_rad(heading_cmd_rad - compass_) : 0.0;
  const double r_cmd = std::clamp(dyn_.heading_gain_per_s * err, -dyn_.yaw_rate_max_radps, dyn_.yaw_rate_max_radps);
  const double dr_max = dyn_.yaw_accel_max_radps2 * dt_s;
  r_ += std::clamp(r_cmd - r_, -dr_max, dr_max);
  const double du_max = dyn_.surge_accel_max_mps2 * dt_s;
  const double u_cmd = std::isfinite(speed_cmd_mps) ? std::max(0.0, speed_cmd_mps) : 0.0;
  u_ += std::clamp(u_cmd - u_, -du_max, du_max);
  // Integrate the true pose (midpoint heading) with the current.
  const double h_mid = truth_.heading_rad + 0.5 * r_ * dt_s;
  const double vn = u_ * std::cos(h_mid) + dyn_.current_ne.x(), ve = u_ * std::sin(h_mid) + dyn_.current_ne.y();
  truth_.x_m += vn * dt_s;
  truth_.y_m += ve * dt_s;
  truth_.heading_rad = wrap_angle_rad(truth_.heading_rad + r_ * dt_s);
  travelled_m_ += std::hypot(vn, ve) * dt_s;
  t_ns_ += static_cast<std::int64_t>(std::llround(dt_s * 1e9));
  sample_sensors(dt_s, u_cmd);
}

void ClosedLoopVehicle::sample_sensors(double dt_s, double speed_cmd_mps) noexcept {
  compass_ = wrap_angle_rad(truth_.heading_rad + drift_.heading_bias_rad + drift_.heading_noise_rad * gauss());
  dr_.on_heading(t_ns_, compass_);
  // DVL dropouts: a Poisson start, a uniform length.
  if (dropout_left_s_ > 0.0) {
    dropout_left_s_ -= dt_s;
    dropout_total_s_ += dt_s;
  } else if (drift_.dropout_every_s > 0.0 && dt_s > 0.0 && uniform() < dt_s / drift_.dropout_every_s) {
    dropout_left_s_ = drift_.dropout_min_s + (drift_.dropout_max_s - drift_.dropout_min_s) * uniform();
  }
  double fwd, stbd;
  if (dropout_left_s_ > 0.0) {
    // No bottom lock: dead reckoning on the commanded speed through the water (the current unseen).
    fwd = speed_cmd_mps;
    stbd = 0.0;
  } else {
    const Vec2d v(u_ * std::cos(truth_.heading_rad) + dyn_.current_ne.x(),
                  u_ * std::sin(truth_.heading_rad) + dyn_.current_ne.y());
    const double c = std::cos(truth_.heading_rad), s = std::sin(truth_.heading_rad);
    const double k = 1.0 + drift_.dvl_scale_error;
    fwd = k * (c * v.x() + s * v.y()) + drift_.dvl_noise_mps * gauss();
    stbd = k * (-s * v.x() + c * v.y()) + drift_.dvl_noise_mps * gauss();
    if (std::hypot(fwd, stbd) > 0.2) sideslip_ = std::atan2(stbd, fwd);
  }
  dr_.on_velocity(t_ns_, fwd, stbd);
}

}  // namespace qnav::pipeline
