#include "nav/motion/attitude_bias_filter.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>

#include "nav/motion/rigid3d.hpp"

namespace qnav::motion {

const char* const AttitudeBiasFilter::kCounterNames[static_cast<std::size_t>(AttitudeBiasCounter::kCount)] = {
    "attbias_bad_attitude", "attbias_bad_vo_step", "attbias_bad_dt", "attbias_vo_gated", "attbias_innovation_gated",
    "attbias_implausible_drift", "attbias_restarts"};

namespace {

bool is_rotation(const Mat3d& R) noexcept {
  return R.allFinite() && (R.transpose() * R - Mat3d::Identity()).cwiseAbs().maxCoeff() < 1e-6 && R.determinant() > 0.0;
}

bool sigma_ok(double s) noexcept { return std::isfinite(s) && s >= 0.0; }

}  // namespace

Status AttitudeBiasFilter::init(const AttitudeBiasConfig& c) noexcept {
  ready_ = false;
  if (!sigma_ok(c.sensor_sigma_rad) || !(c.sensor_sigma_rad > 0.0) || !sigma_ok(c.initial_drift_sigma_rad) ||
      !sigma_ok(c.initial_rate_sigma_rad_s) || !sigma_ok(c.rate_walk_rad_s_sqrt_s) || !sigma_ok(c.drift_walk_rad_sqrt_s) ||
      !(c.vo_sigma_scale > 0.0) || !std::isfinite(c.vo_sigma_scale) || !sigma_ok(c.vo_sigma_floor_rad) ||
      !(c.gate_sigma > 0.0) || !(c.max_dt_s > 0.0) || !(c.max_sigma_rad > 0.0) || !std::isfinite(c.max_sigma_rad) ||
      !std::isfinite(c.gate_sigma) || !std::isfinite(c.max_dt_s) || !(c.max_drift_rate_rad_s > 0.0) ||
      !(c.max_drift_rad > 0.0))
    return Status(StatusCode::kInvalidArgument, "attitude bias filter config out of range");
  config_ = c;
  ready_ = true;
  reset();
  return Status::ok();
}

void AttitudeBiasFilter::reset() noexcept {
  initialised_ = false;
  R_hat_ = Mat3d::Identity();
  A_prev_ = Mat3d::Identity();
  drift_ = Vec3d::Zero();
  rate_ = Vec3d::Zero();
  P_ = Mat9::Zero();
  gated_in_row_ = 0;
  recalibrated_ = false;
}

Mat3d AttitudeBiasFilter::rotation_exp_small(const Vec3d& w) noexcept { return rotation_exp(w); }

void AttitudeBiasFilter::bound_covariance() noexcept {
  P_ = 0.5 * (P_ + P_.transpose());
  const double max_var = config_.max_sigma_rad * config_.max_sigma_rad;
  for (int i = 0; i < 9; ++i) {
    const double lim = i >= 6 ? max_var / (config_.max_dt_s * config_.max_dt_s) : max_var;
    if (!(P_(i, i) <= lim)) {
      // Scale row and column so the correlation structure stays positive semi-definite.
      const double s = P_(i, i) > 0.0 ? std::sqrt(lim / P_(i, i)) : 0.0;
      P_.row(i) *= s;
      P_.col(i) *= s;
      P_(i, i) = lim;
    }
  }
}

void AttitudeBiasFilter::recalibrated() noexcept {
  if (!initialised_) return;
  recalibrated_ = true;
}

Status AttitudeBiasFilter::update(const Mat3d& A, double dt_s, bool has_vo, const Mat3d& dR_vo,
                                  const Mat3d& cov_vo_right) noexcept {
  if (!ready_) return Status(StatusCode::kNotReady, "AttitudeBiasFilter::update before init");
  if (!is_rotation(A)) {
    counters_.increment(AttitudeBiasCounter::kBadAttitude);
    return Status(StatusCode::kInvalidArgument, "attitude sample not a rotation");
  }
  const double m2 = config_.sensor_sigma_rad * config_.sensor_sigma_rad;
  if (recalibrated_ && initialised_) {
    // An absolute fix: a full restart from this sample (orientation = sample, drift and rate zero with
    // their initial variances). The rate is dropped too: between frequent fixes it is learned mostly from
    // the VO's random walk, and carrying it bent the recalibrated 100 m run (docs/vo.md).
    initialised_ = false;
  }
  if (!initialised_) {
    recalibrated_ = false;
    R_hat_ = A;
    A_prev_ = A;
    drift_ = Vec3d::Zero();
    rate_ = Vec3d::Zero();
    P_ = Mat9::Zero();
    P_.block<3, 3>(0, 0) = Mat3d::Identity() * m2;
    P_.block<3, 3>(3, 3) = Mat3d::Identity() * config_.initial_drift_sigma_rad * config_.initial_drift_sigma_rad;
    P_.block<3, 3>(6, 6) = Mat3d::Identity() * config_.initial_rate_sigma_rad_s * config_.initial_rate_sigma_rad_s;
    initialised_ = true;
    gated_in_row_ = 0;
    return Status::ok();
  }
  if (!(std::isfinite(dt_s) && dt_s > 0.0 && dt_s <= config_.max_dt_s)) {
    counters_.increment(AttitudeBiasCounter::kBadDt);
    return Status(StatusCode::kInvalidArgument, "attitude bias filter: dt out of range");
  }
  bool use_vo = has_vo;
  if (use_vo && (!is_rotation(dR_vo) || !cov_vo_right.allFinite())) {
    counters_.increment(AttitudeBiasCounter::kBadVoStep);
    use_vo = false;
  }
  // --- predict ---------------------------------------------------------------------------------------
  const Mat3d dA = A_prev_.transpose() * A;  // sensor increment (drift and white noise of both samples)
  const double q_d = config_.drift_walk_rad_sqrt_s * config_.drift_walk_rad_sqrt_s * dt_s;
  const double q_r = config_.rate_walk_rad_s_sqrt_s * config_.rate_walk_rad_s_sqrt_s * dt_s;
  Mat3d Q_vo = Mat3d::Zero();
  if (use_vo) {
    const double f2 = config_.vo_sigma_floor_rad * config_.vo_sigma_floor_rad;
    Q_vo = config_.vo_sigma_scale * config_.vo_sigma_scale * 0.5 * (cov_vo_right + cov_vo_right.transpose());
    for (int i = 0; i < 3; ++i) Q_vo(i, i) = std::max(Q_vo(i, i), 0.0) + f2;
    // Gate: the VO step against the sensor increment (their difference is the drift increment plus two
    // white samples plus the VO noise).
    const Vec3d d = rotation_log(dR_vo.transpose() * dA);
    const Vec3d rate_sigma(std::sqrt(P_(6, 6)), std::sqrt(P_(7, 7)), std::sqrt(P_(8, 8)));
    for (int i = 0; i < 3 && use_vo; ++i) {
      const double dd = d(i) - rate_(i) * dt_s;
      const double var = 2.0 * m2 + Q_vo(i, i) + q_d + (rate_sigma(i) * dt_s) * (rate_sigma(i) * dt_s);
      if (dd * dd > config_.gate_sigma * config_.gate_sigma * var) use_vo = false;
    }
    if (!use_vo) counters_.increment(AttitudeBiasCounter::kVoGated);
  }
  const Mat3d dR = use_vo ? dR_vo : dA;
  if (!use_vo) Q_vo = Mat3d::Identity() * (2.0 * m2 + q_d);
  Mat9 F = Mat9::Identity();
  F.block<3, 3>(0, 0) = dR.transpose();
  F.block<3, 3>(3, 6) = Mat3d::Identity() * dt_s;
  Mat9 Q = Mat9::Zero();
  Q.block<3, 3>(0, 0) = Q_vo;
  Q.block<3, 3>(3, 3) = Mat3d::Identity() * q_d;
  Q.block<3, 3>(6, 6) = Mat3d::Identity() * q_r;
  Mat3d R_pred = R_hat_ * dR;
  const Vec3d drift_pred = drift_ + rate_ * dt_s;
  Mat9 P_pred = F * P_ * F.transpose() + Q;
  // --- update with the absolute sample ------------------------------------------------------------
  const Vec3d y = rotation_log(R_pred.transpose() * A) - drift_pred;
  Eigen::Matrix<double, 3, 9> H = Eigen::Matrix<double, 3, 9>::Zero();
  H.block<3, 3>(0, 0) = -Mat3d::Identity();
  H.block<3, 3>(0, 3) = Mat3d::Identity();
  const Mat3d S = H * P_pred * H.transpose() + Mat3d::Identity() * m2;
  Eigen::FullPivLU<Mat3d> lu(S);
  A_prev_ = A;
  if (!lu.isInvertible() || !y.allFinite()) {
    counters_.increment(AttitudeBiasCounter::kInnovationGated);
    return Status(StatusCode::kInvalidArgument, "attitude bias filter: singular innovation");
  }
  const Mat3d S_inv = lu.inverse();
  const double d2 = y.dot(S_inv * y);
  R_hat_ = R_pred;
  drift_ = drift_pred;
  P_ = P_pred;
  if (use_vo) ++vo_steps_;
  if (!(d2 <= config_.gate_sigma * config_.gate_sigma)) {
    // Not fused: the prediction stands. A sensor that stays beyond the gate (it was reset, or the VO
    // went wrong) restarts the filter from it after max_gated_in_row samples.
    counters_.increment(AttitudeBiasCounter::kInnovationGated);
    if (++gated_in_row_ >= kMaxGatedInRow) {
      counters_.increment(AttitudeBiasCounter::kRestarts);
      initialised_ = false;
      return update(A, dt_s, false, dR_vo, cov_vo_right);
    }
    bound_covariance();
    return Status(StatusCode::kInvalidArgument, "attitude sample beyond the innovation gate");
  }
  gated_in_row_ = 0;
  const Eigen::Matrix<double, 9, 3> K = P_ * H.transpose() * S_inv;
  const Vec9 dx = K * y;
  R_hat_ = R_hat_ * rotation_exp(-dx.head<3>());
  drift_ += dx.segment<3>(3);
  rate_ += dx.tail<3>();
  const Mat9 IKH = Mat9::Identity() - K * H;
  P_ = IKH * P_ * IKH.transpose() + K * (Mat3d::Identity() * m2) * K.transpose();
  bound_covariance();
  ++updates_;
  if ((rate_.cwiseAbs().array() > config_.max_drift_rate_rad_s).any() ||
      (drift_.cwiseAbs().array() > config_.max_drift_rad).any()) {
    counters_.increment(AttitudeBiasCounter::kImplausibleDrift);
    counters_.increment(AttitudeBiasCounter::kRestarts);
    initialised_ = false;
    return update(A, dt_s, false, dR_vo, cov_vo_right);
  }
  return Status::ok();
}

}  // namespace qnav::motion
