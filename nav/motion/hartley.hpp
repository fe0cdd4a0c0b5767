// Shared pieces of the normalised two-view linear solvers (fundamental.hpp, homography.hpp):
//  - HartleyNormalisation: translates a 2D point set to its centroid and scales it so the mean
//    distance from the origin is sqrt(2) (Hartley 1997), the conditioning step that makes the
//    8-point and DLT solutions usable in double precision;
//  - smallest_eigenvector9: the unit vector minimising |A h| given the accumulated 9 x 9 normal
//    matrix A^T A (fixed-size self-adjoint eigen-solve, as OpenCV's kernels do), with the ratio
//    of the second-smallest to the largest eigenvalue, which tells whether the solution is unique
//    (a ratio near 0 means a null space of dimension >= 2: too few distinct constraints).
//  - spread_ratio: smallest / largest eigenvalue of a normalised point set's 2 x 2 scatter; near 0
//    when the points are collinear (or coincide).
// Header-only, no heap (fixed-size Eigen), O(n) per normalisation, O(1) per solve.
#pragma once

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "nav/core/geometry.hpp"

namespace qnav::motion {

using Vec9d = Eigen::Matrix<double, 9, 1>;
using Mat9d = Eigen::Matrix<double, 9, 9>;

// Eigenvalue ratios below these mean "degenerate" (scale-free: the inputs are normalised first).
constexpr double kMinSpreadRatio = 1e-6;     // point scatter: smallest / largest eigenvalue (collinear)
constexpr double kMinUniqueRatio = 1e-10;    // A^T A: second-smallest / largest eigenvalue

struct HartleyNormalisation {
  Vec2d centroid = Vec2d::Zero();
  double scale = 1.0;  // normalised = scale * (p - centroid)

  Vec2d apply(const Vec2d& p) const noexcept { return scale * (p - centroid); }
  // The 3 x 3 matrix T with T [p; 1] = [apply(p); 1].
  Mat3d matrix() const noexcept {
    Mat3d t;
    t << scale, 0.0, -scale * centroid.x(), 0.0, scale, -scale * centroid.y(), 0.0, 0.0, 1.0;
    return t;
  }
  Mat3d inverse_matrix() const noexcept {
    Mat3d t;
    const double is = 1.0 / scale;
    t << is, 0.0, centroid.x(), 0.0, is, centroid.y(), 0.0, 0.0, 1.0;
    return t;
  }
};

// Builds the normalisation of a point set visited by each(f), which calls f(const Vec2d&) once per
// point, in the same order on every call. Returns false when the set is empty or its points
// coincide (mean distance ~ 0). spread_ratio: see above.
template <typename Each>
bool hartley_normalisation(Each each, HartleyNormalisation& out, double& spread_ratio) noexcept {
  Vec2d c = Vec2d::Zero();
  std::uint32_t count = 0;
  each([&](const Vec2d& p) {
    c += p;
    ++count;
  });
  if (count == 0) return false;
  c /= static_cast<double>(count);
  double mean_dist = 0.0;
  double sxx = 0.0, sxy = 0.0, syy = 0.0;
  each([&](const Vec2d& p) {
    const Vec2d d = p - c;
    mean_dist += d.norm();
    sxx += d.x() * d.x();
    sxy += d.x() * d.y();
    syy += d.y() * d.y();
  });
  mean_dist /= static_cast<double>(count);
  if (!(mean_dist > 1e-12 * (1.0 + c.norm()))) return false;
  out.centroid = c;
  out.scale = std::sqrt(2.0) / mean_dist;
  // Eigenvalues of [[sxx sxy][sxy syy]] in closed form.
  const double tr = sxx + syy;
  const double det = sxx * syy - sxy * sxy;
  const double disc = std::sqrt(std::max(0.0, 0.25 * tr * tr - det));
  const double lmax = 0.5 * tr + disc;
  const double lmin = std::max(0.0, 0.5 * tr - disc);
  spread_ratio = lmax > 0.0 ? lmin / lmax : 0.0;
  return true;
}

struct NullVector9 {
  Vec9d h = Vec9d::Zero();
  double unique_ratio = 0.0;  // lambda_2 / lambda_9 (ascending order)
  bool ok = false;            // the solve produced a finite vector
};

inline NullVector9 smallest_eigenvector9(const Mat9d& ata) noexcept {
  NullVector9 out;
  Eigen::SelfAdjointEigenSolver<Mat9d> es(ata);
  if (es.info() != Eigen::Success) return out;
  const auto& ev = es.eigenvalues();  // ascending
  out.h = es.eigenvectors().col(0);
  out.unique_ratio = ev(8) > 0.0 ? ev(1) / ev(8) : 0.0;
  out.ok = out.h.allFinite() && ev(8) > 0.0;
  return out;
}

}  // namespace qnav::motion
