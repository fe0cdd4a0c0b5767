#include "drivers/stereo_sim/noise_model.hpp"

#include <cmath>

namespace qnav::sim {

double Pcg32::normal() noexcept {
  const double u1 = uniform();
  const double u2 = uniform();
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * kPi * u2);
}

NoiseModel::NoiseModel(const NoiseConfig& config, std::uint64_t seed) noexcept : config_(config), rng_(seed) {
  bias_ = gauss3(config_.sigma_b_rad);
}

Vec3d NoiseModel::gauss3(double sigma) noexcept {
  const double a = rng_.normal(), b = rng_.normal(), c = rng_.normal();
  return Vec3d(a, b, c) * sigma;
}

void NoiseModel::advance_to(double time_s) noexcept {
  if (!(time_s > time_s_)) return;
  time_s_ = time_s;
  const long ticks = static_cast<long>(std::floor(time_s_ / config_.stability_period_s + 1e-9));
  const long per_bias = static_cast<long>(std::lround(config_.bias_period_s / config_.stability_period_s));
  long guard = 0;
  while (stability_ticks_ < ticks && guard++ < 1000000) {  // bounded: one iteration per 10 s elapsed
    ++stability_ticks_;
    if (per_bias > 0 && stability_ticks_ > 1 && (stability_ticks_ - 1) % per_bias == 0) {  // new bias period (eq. 10, i)
      ++bias_ticks_;
      bias_ = gauss3(config_.sigma_b_rad);
      walk_ = Vec3d::Zero();
    }
    walk_ += gauss3(config_.sigma_s_rad);
    drift_ += bias_ + walk_;
  }
}

Mat3d NoiseModel::measure_attitude(const Mat3d& world_R_sensor) noexcept {
  const Vec3d theta = drift_ + gauss3(config_.sigma_m_rad);
  const double a = theta.norm();
  const Mat3d E = a > 0.0 ? Mat3d(Eigen::AngleAxisd(a, theta / a).toRotationMatrix()) : Mat3d::Identity();
  return world_R_sensor * E;
}

void NoiseModel::calibrate() noexcept {
  drift_ = Vec3d::Zero();
  walk_ = Vec3d::Zero();
}

}  // namespace qnav::sim
