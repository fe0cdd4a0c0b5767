// Rigid 2D fit (rotation + translation, no scale) between corresponding point sets, closed form:
// with centroids cs, cd and cross-covariance H = sum (s - cs)(d - cd)^T, the least-squares rotation
// angle is atan2(Hxy - Hyx, Hxx + Hyy) and t = cd - R cs (the 2D case of Arun / Umeyama; no SVD,
// no iteration). Returns the pose P with dst ~= P.apply(src).
// An optional mask (same length, non-zero = use) selects the pairs. Needs >= 2 pairs with spread;
// fewer, NaN input or coincident points -> kInvalidArgument / kDegenerate.
// Cost O(n), no heap. Header-only (inline) so nav/match's RANSAC can use it without a link dependency.
#pragma once

#include <cmath>
#include <cstdint>

#include "nav/core/geometry.hpp"
#include "nav/core/span.hpp"
#include "nav/core/status.hpp"

namespace qnav::motion {

struct Rigid2dFit {
  Pose2 pose;                          // dst ~= pose.apply(src)
  Mat3d covariance = Mat3d::Zero();    // of (x_m, y_m, heading_rad), from the residual spread
  double rms_m = 0.0;                  // root-mean-square residual over the used pairs
  std::uint32_t used = 0;              // pairs used
};


inline Result<Rigid2dFit> fit_rigid2d(Span<const Vec2d> src, Span<const Vec2d> dst,
                                      Span<const std::uint8_t> mask = Span<const std::uint8_t>()) noexcept {
  if (src.size() != dst.size()) return Status(StatusCode::kInvalidArgument, "rigid2d: point sets differ in length");
  if (!mask.empty() && mask.size() != src.size()) return Status(StatusCode::kInvalidArgument, "rigid2d: mask length differs");
  Vec2d cs = Vec2d::Zero(), cd = Vec2d::Zero();
  std::uint32_t n = 0;
  for (std::size_t i = 0; i < src.size(); ++i) {
    if (!mask.empty() && mask[i] == 0) continue;
    if (!src[i].allFinite() || !dst[i].allFinite()) return Status(StatusCode::kInvalidArgument, "rigid2d: point not finite");
    cs += src[i];
    cd += dst[i];
    ++n;
  }
  if (n < 2) return Status(StatusCode::kDegenerate, "rigid2d: fewer than 2 pairs");
  cs /= n;
  cd /= n;
  double hxx = 0, hxy = 0, hyx = 0, hyy = 0, spread = 0;
  for (std::size_t i = 0; i < src.size(); ++i) {
    if (!mask.empty() && mask[i] == 0) continue;
    const Vec2d a = src[i] - cs, b = dst[i] - cd;
    hxx += a.x() * b.x();
    hxy += a.x() * b.y();
    hyx += a.y() * b.x();
    hyy += a.y() * b.y();
    spread += a.squaredNorm();
  }
  if (spread < 1e-12) return Status(StatusCode::kDegenerate, "rigid2d: source points coincide");
  const double theta = std::atan2(hxy - hyx, hxx + hyy);
  Rigid2dFit fit;
  fit.pose.heading_rad = wrap_angle_rad(theta);
  const Mat2d r = fit.pose.rotation();
  const Vec2d t = cd - r * cs;
  fit.pose.x_m = t.x();
  fit.pose.y_m = t.y();
  // Residuals and a Gauss-Newton covariance sigma^2 (J^T J)^-1, J_i = [I | dR/dtheta s_i].
  Mat2d dr;
  dr << -r(1, 0), -r(0, 0), r(0, 0), -r(1, 0);  // d/dtheta [c -s; s c] = [-s -c; c -s]
  Mat3d jtj = Mat3d::Zero();
  double sse = 0.0;
  for (std::size_t i = 0; i < src.size(); ++i) {
    if (!mask.empty() && mask[i] == 0) continue;
    sse += (fit.pose.apply(src[i]) - dst[i]).squaredNorm();
    Eigen::Matrix<double, 2, 3> j;
    j.leftCols<2>().setIdentity();
    j.col(2) = dr * src[i];
    jtj += j.transpose() * j;
  }
  fit.used = n;
  fit.rms_m = std::sqrt(sse / n);
  const double dof = 2.0 * n > 3.0 ? 2.0 * n - 3.0 : 1.0;
  const double sigma2 = sse / dof;
  if (std::abs(jtj.determinant()) > 1e-12) fit.covariance = sigma2 * jtj.inverse();
  else fit.covariance = Mat3d::Identity() * 1e6;
  return fit;
}

// Exact transform from two pairs (the minimal sample): rotation from the two difference vectors,
// translation from their midpoint. kDegenerate when either pair's points nearly coincide.
inline Result<Pose2> rigid2d_from_two(const Vec2d& s0, const Vec2d& s1, const Vec2d& d0, const Vec2d& d1,
                               double min_separation_m) noexcept {
  const Vec2d a = s1 - s0, b = d1 - d0;
  const double min2 = min_separation_m * min_separation_m;
  if (!(a.squaredNorm() > min2) || !(b.squaredNorm() > min2)) return Status(StatusCode::kDegenerate, "rigid2d: sample points coincide");
  const double theta = std::atan2(b.y(), b.x()) - std::atan2(a.y(), a.x());
  Pose2 p;
  p.heading_rad = wrap_angle_rad(theta);
  const Vec2d t = 0.5 * (d0 + d1) - p.rotation() * (0.5 * (s0 + s1));
  p.x_m = t.x();
  p.y_m = t.y();
  return p;
}

}  // namespace qnav::motion
