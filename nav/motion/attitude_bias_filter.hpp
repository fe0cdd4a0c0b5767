// AttitudeBiasFilter: online estimate of an absolute attitude sensor's drift from visual-odometry rotations
// (beyond Souvannavong et al.: the paper's 3D-VME takes the orientation from the sensor and inherits its
// drift; here the per-step rotation of 6D-VME, which has small noise but random-walks when integrated, and
// the sensor, which is absolute but drifts, are fused).
//
// Models (right perturbations, sensor frame = camera frame; small angles):
//   sensor      A_k = R_k exp(D_k + m_k)        m_k ~ N(0, sensor_sigma^2 I) white, D_k the drift
//   drift       D_k = D_{k-1} + r_{k-1} dt + w_D    w_D ~ N(0, drift_walk^2 dt I)
//               r_k = r_{k-1} + w_r                 w_r ~ N(0, rate_walk^2 dt I)   (drift rate = bias)
//   VO step     dR_vo = R_{k-1}^T R_k exp(v_k)  v_k ~ N(0, Q_vo) (6D-VME covariance, scaled and floored)
// Error-state Kalman filter, state x = [e, D, r] (9): the orientation estimate Rh = R exp(e) is propagated
// by the VO step (e_k = dR_vo^T e_{k-1} + v_k) or, without a visual step, by the sensor increment
// A_{k-1}^T A_k (Q_e = 2 sensor_sigma^2 + drift); each sensor sample is the measurement
//   y = log(Rh^T A) - Dh = (D - Dh) - e + m,   H = [-I, I, 0],   R = sensor_sigma^2 I,
// after which e is injected (Rh <- Rh exp(-e_hat)) and reset. corrected() = Rh is the estimate of R_k.
// Observability: only D - e is measured; the split between the drift and the VO's own random walk comes
// from their models (the drift has a persistent rate, the VO error does not), so the estimate is as good
// as Q_vo and the drift model are honest. Nothing absolute is observed: over long runs the error still
// grows (as the VO's rotation random walk), only slower than the sensor's drift.
//
// Rejections (counted, state untouched): non-finite / non-rotation inputs, dt <= 0 or > max_dt_s, a VO
// step whose disagreement with the sensor increment exceeds gate_sigma (predict falls back to the sensor
// increment), an innovation beyond gate_sigma (Mahalanobis, 3 dof). Restarts from the sensor (counted):
// kMaxGatedInRow gated innovations in a row, or a drift / drift rate beyond max_drift_rad /
// max_drift_rate_rad_s (a biased VO would otherwise be absorbed as sensor drift). Covariance is
// symmetrised and its diagonal bounded (max_sigma_rad), so it stays finite on any input sequence.
// Cost: O(1) (9x9 fixed-size products, one 3x3 inverse) per call; no heap; no I/O.
#pragma once

#include <cstdint>

#include "nav/core/counters.hpp"
#include "nav/core/geometry.hpp"
#include "nav/core/status.hpp"

namespace qnav::motion {

struct AttitudeBiasConfig {
  double sensor_sigma_rad = deg_to_rad(0.1);        // white noise of one attitude sample, per axis
  double initial_drift_sigma_rad = deg_to_rad(0.01);  // drift at the first sample (after calibration)
  // Drift-rate (bias) uncertainty at start and its random walk. Defaults: the paper's small noise model
  // (sec. 5.2: every 10 s the drift grows by a bias ~N(0, 0.01 deg) redrawn every 100 s plus a random
  // walk of 0.01 deg per 10 s): rate sigma 0.01 deg / 10 s; rate walk (0.01 deg / 10 s) per sqrt(10 s)
  // plus the bias redraw (0.01 deg / 10 s) per sqrt(100 s).
  double initial_rate_sigma_rad_s = deg_to_rad(0.001);
  double rate_walk_rad_s_sqrt_s = deg_to_rad(0.000332);
  double drift_walk_rad_sqrt_s = deg_to_rad(0.0045);  // the drift's steps every 10 s (0.01-0.03 deg)
  double vo_sigma_scale = 1.0;                      // multiplies the 6D-VME rotation sigma
  double vo_sigma_floor_rad = deg_to_rad(0.005);    // per-axis floor of a VO step rotation sigma
  double gate_sigma = 5.0;                          // innovation / VO-vs-sensor gate (sigmas)
  double max_dt_s = 600.0;                          // a longer gap between samples is rejected
  double max_sigma_rad = deg_to_rad(30.0);          // bound on every state sigma
  // Plausibility of the estimate: a drift rate or drift beyond these (per axis) means the VO and the sensor
  // disagree in a way the drift model does not explain (e.g. a biased VO): restart from the sensor.
  // Default rate: 5 sigma of the small model's rate after one bias period (bias 0.001 deg/s plus the
  // walk's sqrt(10) * 0.001 deg/s).
  double max_drift_rate_rad_s = deg_to_rad(0.016);
  double max_drift_rad = deg_to_rad(10.0);
};

enum class AttitudeBiasCounter : std::uint8_t {
  kBadAttitude,   // non-finite or non-rotation sensor sample
  kBadVoStep,     // non-finite VO rotation or covariance
  kBadDt,         // dt <= 0, non-finite or > max_dt_s
  kVoGated,       // VO step disagrees with the sensor increment beyond the gate (sensor increment used)
  kInnovationGated,  // sensor sample beyond the gate (not fused)
  kImplausibleDrift,  // drift or drift rate beyond its maximum: restarted from the sensor
  kRestarts,      // restarted from the sensor (kMaxGatedInRow gated samples in a row, or implausible drift)
  kCount
};

class AttitudeBiasFilter {
 public:
  using Vec9 = Eigen::Matrix<double, 9, 1>;
  using Mat9 = Eigen::Matrix<double, 9, 9>;

  AttitudeBiasFilter() noexcept = default;
  // Errors: kInvalidArgument (a sigma negative / non-finite, gate or max_dt not positive).
  Status init(const AttitudeBiasConfig& config) noexcept;
  // Forget everything; the next sample restarts the filter (Rh = A, D = 0).
  void reset() noexcept;
  // The sensor was just recalibrated against an absolute reference (an absolute fix): the next sample
  // restarts the filter (orientation = sample, drift and drift rate zero with their initial variances).
  // The rate (the bias, which a recalibration does not remove) is dropped on purpose: between frequent
  // fixes it is learned mostly from the VO's random walk.
  void recalibrated() noexcept;
  static constexpr std::uint32_t kMaxGatedInRow = 3;
  // One frame: the sensor's absolute attitude world_R_sensor, the time since the previous frame, and the
  // VO rotation of the step (dR_vo = prev_R_cur, cov_right = covariance of its right-perturbation rotation
  // vector) when has_vo (a good visual step). The first call (or after reset) only initialises.
  // Returns kInvalidArgument if the sample was rejected (counted); the estimate is then unchanged.
  Status update(const Mat3d& world_R_sensor, double dt_s, bool has_vo, const Mat3d& dR_vo,
                const Mat3d& cov_vo_right) noexcept;

  bool initialised() const noexcept { return initialised_; }
  const Mat3d& corrected() const noexcept { return R_hat_; }  // estimate of world_R_sensor (filtered)
  // The last sample with the estimated drift removed, A exp(-D_hat): keeps the sensor's white noise white
  // (harmless to dead reckoning, where a correlated error bends the path) and removes the drift.
  Mat3d corrected_sample() const noexcept { return A_prev_ * rotation_exp_small(-drift_); }
  const Vec3d& drift_rad() const noexcept { return drift_; }  // D_hat
  const Vec3d& drift_rate_rad_s() const noexcept { return rate_; }
  const Mat9& covariance() const noexcept { return P_; }
  std::uint32_t updates() const noexcept { return updates_; }
  std::uint32_t vo_steps() const noexcept { return vo_steps_; }
  const CounterSet<AttitudeBiasCounter>& counters() const noexcept { return counters_; }
  static const char* const kCounterNames[static_cast<std::size_t>(AttitudeBiasCounter::kCount)];

 private:
  void bound_covariance() noexcept;
  static Mat3d rotation_exp_small(const Vec3d& w) noexcept;
  AttitudeBiasConfig config_;
  bool ready_ = false;
  bool initialised_ = false;
  bool recalibrated_ = false;
  Mat3d R_hat_ = Mat3d::Identity();
  Mat3d A_prev_ = Mat3d::Identity();
  Vec3d drift_ = Vec3d::Zero();
  Vec3d rate_ = Vec3d::Zero();
  Mat9 P_ = Mat9::Zero();
  std::uint32_t gated_in_row_ = 0;
  std::uint32_t updates_ = 0;
  std::uint32_t vo_steps_ = 0;
  CounterSet<AttitudeBiasCounter> counters_{kCounterNames};
};

}  // namespace qnav::motion
