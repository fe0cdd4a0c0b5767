#include "nav/motion/rigid3d.hpp"

#include <Eigen/LU>
#include <Eigen/SVD>
#include <cmath>

namespace qnav::motion {

namespace {

using Vec6d = Eigen::Matrix<double, 6, 1>;

Mat3d skew(const Vec3d& v) noexcept {
  Mat3d m;
  m << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return m;
}

Status check_inputs(Span<const Vec3d> prev, Span<const Vec3d> cur, Span<const double> weights) noexcept {
  if (prev.size() != cur.size()) return Status(StatusCode::kInvalidArgument, "point sets differ in size");
  if (prev.size() > kMaxRigidPoints) return Status(StatusCode::kInvalidArgument, "too many points");
  if (!weights.empty() && weights.size() != prev.size())
    return Status(StatusCode::kInvalidArgument, "weights differ in size from points");
  for (std::size_t i = 0; i < prev.size(); ++i) {
    if (!prev[i].allFinite() || !cur[i].allFinite()) return Status(StatusCode::kInvalidArgument, "non-finite point");
    if (!weights.empty() && !(std::isfinite(weights[i]) && weights[i] >= 0.0))
      return Status(StatusCode::kInvalidArgument, "weight negative or non-finite");
  }
  return Status::ok();
}

double weight_at(Span<const double> w, std::size_t i) noexcept { return w.empty() ? 1.0 : w[i]; }

// Residual statistics and covariance for a given pose.
Status finish(Span<const Vec3d> prev, Span<const Vec3d> cur, Span<const double> weights, bool six_d,
              double sigma_floor_m, RigidEstimate& e) noexcept {
  const std::size_t n = prev.size();
  double wsum = 0.0, r2 = 0.0;
  Mat6d jtj = Mat6d::Zero();
  std::size_t used = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double w = weight_at(weights, i);
    if (w <= 0.0) continue;
    ++used;
    const Vec3d rc = e.pose.R * cur[i];
    const Vec3d r = prev[i] - (rc + e.pose.t);
    r2 += w * r.squaredNorm();
    wsum += w;
    if (!six_d) continue;  // the 3D covariance needs no information matrix
    Eigen::Matrix<double, 3, 6> J;
    J.leftCols<3>() = skew(rc);
    J.rightCols<3>() = -Mat3d::Identity();
    jtj += w * J.transpose() * J;
  }
  if (wsum <= 0.0) return Status(StatusCode::kDegenerate, "all weights zero");
  const double dof = six_d ? 3.0 * static_cast<double>(used) - 6.0 : 3.0 * static_cast<double>(used) - 3.0;
  double s2 = dof > 0.0 ? r2 / dof * (static_cast<double>(used) / wsum) : 0.0;
  if (s2 < sigma_floor_m * sigma_floor_m) s2 = sigma_floor_m * sigma_floor_m;
  e.rms_residual_m = std::sqrt(r2 / wsum);
  e.points = n;
  e.covariance = Mat6d::Zero();
  if (six_d) {
    Eigen::FullPivLU<Mat6d> lu(jtj);
    if (!lu.isInvertible()) return Status(StatusCode::kDegenerate, "singular 6D information matrix");
    e.covariance = s2 * lu.inverse();
  } else {
    e.covariance.bottomRightCorner<3, 3>() = (s2 / wsum) * Mat3d::Identity();
  }
  if (!e.covariance.allFinite() || !e.pose.is_finite()) return Status(StatusCode::kDegenerate, "non-finite estimate");
  return Status::ok();
}

}  // namespace

Vec3d rotation_log(const Mat3d& R) noexcept {
  const Eigen::AngleAxisd aa(R);
  return aa.axis() * aa.angle();
}

Mat3d rotation_exp(const Vec3d& w) noexcept {
  const double a = w.norm();
  if (a < 1e-12) return Mat3d::Identity() + skew(w);
  return Eigen::AngleAxisd(a, w / a).toRotationMatrix();
}

Result<RigidEstimate> estimate_rigid_6d(Span<const Vec3d> prev, Span<const Vec3d> cur, Span<const double> weights,
                                        double sigma_floor_m) noexcept {
  QNAV_RETURN_IF_ERROR(check_inputs(prev, cur, weights));
  const std::size_t n = prev.size();
  double wsum = 0.0;
  std::size_t used = 0;
  Vec3d cp = Vec3d::Zero(), cc = Vec3d::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    const double w = weight_at(weights, i);
    if (w > 0.0) ++used;
    wsum += w;
    cp += w * prev[i];
    cc += w * cur[i];
  }
  if (used < 3 || wsum <= 0.0) return Status(StatusCode::kDegenerate, "6D motion needs 3 weighted points");
  cp /= wsum;
  cc /= wsum;
  Mat3d H = Mat3d::Zero();
  for (std::size_t i = 0; i < n; ++i) H += weight_at(weights, i) * (cur[i] - cc) * (prev[i] - cp).transpose();
  Eigen::JacobiSVD<Mat3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Vec3d sv = svd.singularValues();
  if (!(sv(0) > 0.0) || !(sv(1) > 1e-9 * sv(0)))
    return Status(StatusCode::kDegenerate, "points coincident or collinear");
  const Mat3d U = svd.matrixU();
  const Mat3d V = svd.matrixV();
  Mat3d D = Mat3d::Identity();
  if ((V * U.transpose()).determinant() < 0.0) D(2, 2) = -1.0;  // reflection fix
  RigidEstimate e;
  e.pose.R = V * D * U.transpose();
  e.pose.t = cp - e.pose.R * cc;
  e.inliers = used;
  QNAV_RETURN_IF_ERROR(finish(prev, cur, weights, true, sigma_floor_m, e));
  return e;
}

Result<RigidEstimate> estimate_translation_3d(Span<const Vec3d> prev, Span<const Vec3d> cur, const Mat3d& R,
                                              Span<const double> weights, double sigma_floor_m) noexcept {
  QNAV_RETURN_IF_ERROR(check_inputs(prev, cur, weights));
  if (!R.allFinite() || !((R.transpose() * R - Mat3d::Identity()).cwiseAbs().maxCoeff() < 1e-6) ||
      !(R.determinant() > 0.0))
    return Status(StatusCode::kInvalidArgument, "attitude is not a rotation");
  double wsum = 0.0;
  std::size_t used = 0;
  Vec3d t = Vec3d::Zero();
  for (std::size_t i = 0; i < prev.size(); ++i) {
    const double w = weight_at(weights, i);
    if (w > 0.0) ++used;
    wsum += w;
    t += w * (prev[i] - R * cur[i]);
  }
  if (used < 1 || wsum <= 0.0) return Status(StatusCode::kDegenerate, "3D motion needs a weighted point");
  RigidEstimate e;
  e.pose.R = R;
  e.pose.t = t / wsum;
  e.inliers = used;
  QNAV_RETURN_IF_ERROR(finish(prev, cur, weights, false, sigma_floor_m, e));
  return e;
}

namespace {

template <typename Solve>
Result<RigidEstimate> irls(Span<const Vec3d> prev, Span<const Vec3d> cur, const RigidEstimate& initial,
                           const IrlsConfig& config, Span<double> w, Span<const double> base, Solve solve) noexcept {
  if (w.size() != prev.size() || prev.size() != cur.size() || (!base.empty() && base.size() != prev.size()))
    return Status(StatusCode::kInvalidArgument, "IRLS scratch size differs from points");
  if (!(config.huber_m > 0.0) || !(config.inlier_m > 0.0) || config.iterations > 100)
    return Status(StatusCode::kInvalidArgument, "IRLS config out of range");
  RigidEstimate e = initial;
  for (std::size_t it = 0; it < config.iterations; ++it) {
    for (std::size_t i = 0; i < prev.size(); ++i) {
      const double r = (prev[i] - e.pose.apply(cur[i])).norm();
      w[i] = std::isfinite(r) ? (r <= config.huber_m ? 1.0 : config.huber_m / r) : 0.0;
      if (!base.empty()) w[i] *= base[i];
    }
    Result<RigidEstimate> next = solve(Span<const double>(w.data(), w.size()));
    if (!next) return next.status();
    e = next.value();
  }
  std::size_t inl = 0;
  for (std::size_t i = 0; i < prev.size(); ++i)
    if ((prev[i] - e.pose.apply(cur[i])).norm() < config.inlier_m) ++inl;
  e.inliers = inl;
  return e;
}

}  // namespace

Result<RigidEstimate> refine_irls_6d(Span<const Vec3d> prev, Span<const Vec3d> cur, const RigidEstimate& initial,
                                     const IrlsConfig& config, Span<double> weights_scratch,
                                     Span<const double> base_weights) noexcept {
  return irls(prev, cur, initial, config, weights_scratch, base_weights,
              [&](Span<const double> w) { return estimate_rigid_6d(prev, cur, w); });
}

Result<RigidEstimate> refine_irls_3d(Span<const Vec3d> prev, Span<const Vec3d> cur, const RigidEstimate& initial,
                                     const IrlsConfig& config, Span<double> weights_scratch,
                                     Span<const double> base_weights) noexcept {
  const Mat3d R = initial.pose.R;
  return irls(prev, cur, initial, config, weights_scratch, base_weights,
              [&](Span<const double> w) { return estimate_translation_3d(prev, cur, R, w); });
}

namespace {

Mat3d stereo_cov(const Vec3d& p, const StereoPointModel& m) noexcept {
  const double z = std::fabs(p.z());
  const double n = p.norm();
  const Vec3d u = n > 0.0 ? Vec3d(p / n) : Vec3d::UnitZ();
  double sr = m.ray_sigma_per_z2 * z * z, sl = m.lateral_sigma_per_z * z;
  if (sr < m.min_sigma_m) sr = m.min_sigma_m;
  if (sl < m.min_sigma_m) sl = m.min_sigma_m;
  const Mat3d uu = u * u.transpose();
  return sr * sr * uu + sl * sl * (Mat3d::Identity() - uu);
}

}  // namespace

Result<RigidEstimate> refine_rigid_6d_stereo(Span<const Vec3d> prev, Span<const Vec3d> cur, const RigidEstimate& initial,
                                             const StereoPointModel& model, std::size_t iterations,
                                             double huber_k) noexcept {
  QNAV_RETURN_IF_ERROR(check_inputs(prev, cur, Span<const double>()));
  if (!(model.ray_sigma_per_z2 >= 0.0) || !(model.lateral_sigma_per_z >= 0.0) || !(model.min_sigma_m > 0.0) ||
      !std::isfinite(model.ray_sigma_per_z2) || !std::isfinite(model.lateral_sigma_per_z) ||
      !std::isfinite(model.min_sigma_m) || iterations > 20 || !(huber_k > 0.0) || !initial.pose.is_finite())
    return Status(StatusCode::kInvalidArgument, "stereo 6D refinement: model or initial pose out of range");
  const std::size_t n = prev.size();
  if (n < 3) return Status(StatusCode::kDegenerate, "6D motion needs 3 points");
  RigidEstimate e = initial;
  Mat6d H = Mat6d::Zero();
  double chi2 = 0.0, r2 = 0.0;
  std::size_t used = 0;
  // iterations solves, then one pass to evaluate the final pose.
  for (std::size_t it = 0; it <= iterations; ++it) {
    H = Mat6d::Zero();
    Vec6d g = Vec6d::Zero();
    chi2 = 0.0;
    r2 = 0.0;
    used = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const Vec3d rc = e.pose.R * cur[i];
      const Vec3d r = prev[i] - (rc + e.pose.t);
      // Covariances at the fused landmark X (the maximum-likelihood point given both measurements), not at
      // the measurements: X is uncorrelated with the residual, a measurement is not (a covariance taken
      // at a noisy point weights the points measured nearer more and biases the rotation). X itself
      // needs a covariance: the one at the measurements, once.
      const Mat3d Sc0 = e.pose.R * stereo_cov(cur[i], model) * e.pose.R.transpose();
      const Mat3d S0 = stereo_cov(prev[i], model) + Sc0;
      Mat3d Sc = Sc0, S = S0;
      if (model.fused_linearisation) {
        const Vec3d x0 = rc + e.pose.t + Sc0 * S0.ldlt().solve(r);
        Sc = e.pose.R * stereo_cov(e.pose.R.transpose() * (x0 - e.pose.t), model) * e.pose.R.transpose();
        S = stereo_cov(x0, model) + Sc;
      }
      const Mat3d W = S.inverse();
      const double d2 = r.dot(W * r);
      if (!std::isfinite(d2)) continue;
      const double d = std::sqrt(d2);
      const double hw = d <= huber_k ? 1.0 : huber_k / d;
      // Rotation Jacobian at the fused point X = (R c + t) + Sc W r (the maximum-likelihood position of the
      // landmark given both measurements), not at the noisy R c: with anisotropic covariances whose axes
      // differ between the frames, skew(R c) is correlated with r and the stationary point is biased
      // (errors in variables; on the Mars yard +0.004 deg per step about x from unbiased noise). With X
      // the gradient is that of the likelihood with the landmark eliminated (envelope theorem).
      const Vec3d x_lin = model.fused_linearisation ? Vec3d(rc + e.pose.t + Sc * (W * r)) : Vec3d(rc + e.pose.t);
      Eigen::Matrix<double, 3, 6> J;
      J.leftCols<3>() = skew(x_lin - e.pose.t);
      J.rightCols<3>() = -Mat3d::Identity();
      H += hw * J.transpose() * W * J;
      g += hw * J.transpose() * W * r;
      chi2 += hw * d2;
      r2 += r.squaredNorm();
      ++used;
    }
    if (used < 3) return Status(StatusCode::kDegenerate, "6D motion needs 3 finite points");
    if (it == iterations) break;
    Eigen::FullPivLU<Mat6d> lu(H);
    if (!lu.isInvertible()) return Status(StatusCode::kDegenerate, "singular 6D information matrix");
    const Vec6d dx = -lu.solve(g);
    if (!dx.allFinite()) return Status(StatusCode::kDegenerate, "non-finite 6D update");
    e.pose.R = rotation_exp(dx.head<3>()) * e.pose.R;
    e.pose.t += dx.tail<3>();
  }
  Eigen::FullPivLU<Mat6d> lu(H);
  if (!lu.isInvertible()) return Status(StatusCode::kDegenerate, "singular 6D information matrix");
  const double dof = 3.0 * static_cast<double>(used) - 6.0;
  const double scale = dof > 0.0 && chi2 / dof > 1.0 ? chi2 / dof : 1.0;
  e.covariance = scale * lu.inverse();
  e.rms_residual_m = std::sqrt(r2 / static_cast<double>(used));
  e.points = n;
  if (!e.covariance.allFinite() || !e.pose.is_finite()) return Status(StatusCode::kDegenerate, "non-finite estimate");
  return e;
}

}  // namespace qnav::motion
