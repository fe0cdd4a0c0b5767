// The Mars paper's noise model (Souvannavong et al. sec. 5.2) as a reusable, deterministic generator.
//   Odometry: T' = (1 + n_t) T (constant relative error: wheel slip along the motion).
//   Attitude: error vector (3 axes, sensor frame) theta = theta_m + sum_i sum_j (theta_b_i + sum_k theta_s_k)
//     theta_m ~ N(0, sigma_m) fresh at each measurement; every 10 s (bias-stability period) the drift
//     grows by the current bias theta_b plus the random walk sum theta_s (theta_s ~ N(0, sigma_s) per
//     10 s, restarted each 100 s); every 100 s a new bias theta_b ~ N(0, sigma_b) is drawn (eq. 10).
//   calibrate(): an absolute reference (gravity, sun) zeroes the accumulated drift and random walk.
// Presets: small (sigma_m 0.1 deg, sigma_b 0.01 deg, sigma_s 0.01 deg, n_t 10 %), moderate (x2).
// Deterministic (own PCG32 + Box-Muller, seeded): the same seed gives the same sequence everywhere.
// O(1) per call, no heap.
#pragma once

#include <cstdint>

#include "nav/core/geometry.hpp"

namespace qnav::sim {

// PCG32 (O'Neill), portable and deterministic.
class Pcg32 {
 public:
  explicit Pcg32(std::uint64_t seed = 1) noexcept { reseed(seed); }
  void reseed(std::uint64_t seed) noexcept {
    state_ = 0;
    next();
    state_ += seed;
    next();
  }
  std::uint32_t next() noexcept {
    const std::uint64_t old = state_;
    state_ = old * 6364136223846793005ULL + 1442695040888963407ULL;
    const std::uint32_t xorshifted = static_cast<std::uint32_t>(((old >> 18u) ^ old) >> 27u);
    const std::uint32_t rot = static_cast<std::uint32_t>(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((32u - rot) & 31u));
  }
  double uniform() noexcept { return (static_cast<double>(next()) + 0.5) / 4294967296.0; }  // (0, 1)
  double uniform(double lo, double hi) noexcept { return lo + (hi - lo) * uniform(); }
  double normal() noexcept;  // N(0, 1), Box-Muller

 private:
  std::uint64_t state_ = 0;
};

struct NoiseConfig {
  double sigma_m_rad = deg_to_rad(0.1);
  double sigma_b_rad = deg_to_rad(0.01);
  double sigma_s_rad = deg_to_rad(0.01);
  double bias_period_s = 100.0;
  double stability_period_s = 10.0;
  double translation_noise = 0.10;  // n_t
  static NoiseConfig small() noexcept { return NoiseConfig{}; }
  static NoiseConfig moderate() noexcept {
    NoiseConfig c;
    c.sigma_m_rad *= 2.0;
    c.sigma_b_rad *= 2.0;
    c.sigma_s_rad *= 2.0;
    c.translation_noise *= 2.0;
    return c;
  }
  static NoiseConfig none() noexcept {
    NoiseConfig c;
    c.sigma_m_rad = c.sigma_b_rad = c.sigma_s_rad = 0.0;
    c.translation_noise = 0.0;
    return c;
  }
};

class NoiseModel {
 public:
  NoiseModel(const NoiseConfig& config, std::uint64_t seed) noexcept;
  // Advances the sensor clock to time_s (monotonic), updating bias and drift at each elapsed period.
  void advance_to(double time_s) noexcept;
  // Measured attitude for a true attitude world_R_sensor at the current time: R_true * exp(theta).
  Mat3d measure_attitude(const Mat3d& world_R_sensor) noexcept;
  // Odometry translation with the constant relative error.
  Vec3d measure_translation(const Vec3d& t_true) const noexcept { return (1.0 + config_.translation_noise) * t_true; }
  void calibrate() noexcept;
  Vec3d drift_rad() const noexcept { return drift_; }
  const NoiseConfig& config() const noexcept { return config_; }

 private:
  Vec3d gauss3(double sigma) noexcept;
  NoiseConfig config_;
  Pcg32 rng_;
  double time_s_ = 0.0;
  long stability_ticks_ = 0;
  long bias_ticks_ = 0;
  Vec3d bias_ = Vec3d::Zero();
  Vec3d walk_ = Vec3d::Zero();
  Vec3d drift_ = Vec3d::Zero();
};

}  // namespace qnav::sim
