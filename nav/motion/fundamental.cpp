#include "nav/motion/fundamental.hpp"

#include <Eigen/SVD>
#include <cmath>
#include <limits>

#include "nav/motion/hartley.hpp"

namespace qnav::motion {

double sampson_distance_sq(const Mat3d& F, const Vec2d& a, const Vec2d& b) noexcept {
  const Vec3d xa(a.x(), a.y(), 1.0), xb(b.x(), b.y(), 1.0);
  const Vec3d fa = F * xa;
  const Vec3d fb = F.transpose() * xb;
  const double e = xb.dot(fa);
  const double den = fa.x() * fa.x() + fa.y() * fa.y() + fb.x() * fb.x() + fb.y() * fb.y();
  if (!(den > 0.0)) return std::numeric_limits<double>::infinity();
  return e * e / den;
}

namespace {

// each(f) calls f(i) for every used pair index i, in the same order on every call.
template <typename Each>
Result<FundamentalFit> fit_impl(Span<const Vec2d> a, Span<const Vec2d> b, Each each) noexcept {
  std::uint32_t count = 0;
  bool finite = true;
  each([&](std::size_t i) {
    ++count;
    finite = finite && a[i].allFinite() && b[i].allFinite();
  });
  if (!finite) return Status(StatusCode::kInvalidArgument, "fundamental: point not finite");
  if (count < kFundamentalMinPairs) return Status(StatusCode::kDegenerate, "fundamental: fewer than 8 pairs");
  HartleyNormalisation na, nb;
  double spread_a = 0.0, spread_b = 0.0;
  const bool norm_a = hartley_normalisation([&](auto f) { each([&](std::size_t i) { f(a[i]); }); }, na, spread_a);
  const bool norm_b = hartley_normalisation([&](auto f) { each([&](std::size_t i) { f(b[i]); }); }, nb, spread_b);
  if (!norm_a || !norm_b) return Status(StatusCode::kDegenerate, "fundamental: points coincide");
  if (spread_a < kMinSpreadRatio || spread_b < kMinSpreadRatio)
    return Status(StatusCode::kDegenerate, "fundamental: points collinear in an image");

  Mat9d ata = Mat9d::Zero();
  each([&](std::size_t i) {
    const Vec2d p = na.apply(a[i]), q = nb.apply(b[i]);
    Vec9d r;
    r << q.x() * p.x(), q.x() * p.y(), q.x(), q.y() * p.x(), q.y() * p.y(), q.y(), p.x(), p.y(), 1.0;
    ata.noalias() += r * r.transpose();
  });
  const NullVector9 nv = smallest_eigenvector9(ata);
  if (!nv.ok) return Status(StatusCode::kDegenerate, "fundamental: eigen-solve failed");
  Mat3d fn;
  fn << nv.h(0), nv.h(1), nv.h(2), nv.h(3), nv.h(4), nv.h(5), nv.h(6), nv.h(7), nv.h(8);
  // Rank 2: zero the smallest singular value.
  Eigen::JacobiSVD<Mat3d> svd(fn, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Vec3d s = svd.singularValues();
  s(2) = 0.0;
  fn = svd.matrixU() * s.asDiagonal() * svd.matrixV().transpose();
  Mat3d F = nb.matrix().transpose() * fn * na.matrix();
  const double norm = F.norm();
  if (!(norm > 0.0) || !F.allFinite()) return Status(StatusCode::kDegenerate, "fundamental: null solution");
  F /= norm;
  Eigen::Index r = 0, c = 0;
  F.cwiseAbs().maxCoeff(&r, &c);
  if (F(r, c) < 0.0) F = -F;

  FundamentalFit fit;
  fit.F = F;
  fit.used = count;
  fit.unique_ratio = nv.unique_ratio;
  fit.unique = nv.unique_ratio > kMinUniqueRatio;
  double sse = 0.0;
  each([&](std::size_t i) { sse += sampson_distance_sq(F, a[i], b[i]); });
  fit.rms_sampson_px = std::sqrt(sse / static_cast<double>(count));
  return fit;
}

}  // namespace

Result<FundamentalFit> fit_fundamental_8point(Span<const Vec2d> a, Span<const Vec2d> b, Span<const std::uint8_t> mask) noexcept {
  if (a.size() != b.size()) return Status(StatusCode::kInvalidArgument, "fundamental: point sets differ in length");
  if (!mask.empty() && mask.size() != a.size()) return Status(StatusCode::kInvalidArgument, "fundamental: mask length differs");
  return fit_impl(a, b, [&](auto f) {
    for (std::size_t i = 0; i < a.size(); ++i)
      if (mask.empty() || mask[i] != 0) f(i);
  });
}

Result<FundamentalFit> fit_fundamental_8point_indexed(Span<const Vec2d> a, Span<const Vec2d> b,
                                                      Span<const std::uint32_t> indices) noexcept {
  if (a.size() != b.size()) return Status(StatusCode::kInvalidArgument, "fundamental: point sets differ in length");
  for (std::size_t k = 0; k < indices.size(); ++k)
    if (indices[k] >= a.size()) return Status(StatusCode::kOutOfRange, "fundamental: index out of range");
  return fit_impl(a, b, [&](auto f) {
    for (std::size_t k = 0; k < indices.size(); ++k) f(static_cast<std::size_t>(indices[k]));
  });
}

}  // namespace qnav::motion
