#include "nav/motion/homography.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <cmath>
#include <limits>

#include "nav/motion/hartley.hpp"

namespace qnav::motion {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kMinW = 1e-12;               // |w| below this (relative): maps to infinity
constexpr double kMinDetNormalised = 1e-8;    // |det H'| / |H'|_F^3 below this: singular
constexpr double kMinTriangleSine = 1e-4;     // 4-point samples: |sin| of a triple's angle

using Vec8d = Eigen::Matrix<double, 8, 1>;
using Mat8d = Eigen::Matrix<double, 8, 8>;

Mat3d scale_homography(const Mat3d& h) noexcept {
  const double n = h.norm();
  if (std::abs(h(2, 2)) > 1e-12 * n) return h / h(2, 2);
  return h / n;
}

bool is_singular(const Mat3d& h) noexcept {
  const double n = h.norm();
  if (!(n > 0.0) || !h.allFinite()) return true;
  return !(std::abs(h.determinant()) / (n * n * n) > kMinDetNormalised);
}

double cross2(const Vec2d& u, const Vec2d& v) noexcept { return u.x() * v.y() - u.y() * v.x(); }

// Sign of the triangle (p, q, r): +1 / -1, 0 when the points are (nearly) collinear.
int triangle_sign(const Vec2d& p, const Vec2d& q, const Vec2d& r) noexcept {
  const Vec2d u = q - p, v = r - p;
  const double c = cross2(u, v);
  const double scale = u.norm() * v.norm();
  if (!(std::abs(c) > kMinTriangleSine * scale)) return 0;
  return c > 0.0 ? 1 : -1;
}

// each(f) calls f(i) for every used pair index, in the same order on every call.
template <typename Each>
Result<HomographyFit> dlt_impl(Span<const Vec2d> src, Span<const Vec2d> dst, Each each) noexcept {
  std::uint32_t count = 0;
  bool finite = true;
  each([&](std::size_t i) {
    ++count;
    finite = finite && src[i].allFinite() && dst[i].allFinite();
  });
  if (!finite) return Status(StatusCode::kInvalidArgument, "homography: point not finite");
  if (count < kHomographyMinPairs) return Status(StatusCode::kDegenerate, "homography: fewer than 4 pairs");
  HartleyNormalisation ns, nd;
  double spread_s = 0.0, spread_d = 0.0;
  const bool ok_s = hartley_normalisation([&](auto f) { each([&](std::size_t i) { f(src[i]); }); }, ns, spread_s);
  const bool ok_d = hartley_normalisation([&](auto f) { each([&](std::size_t i) { f(dst[i]); }); }, nd, spread_d);
  if (!ok_s || !ok_d) return Status(StatusCode::kDegenerate, "homography: points coincide");
  if (spread_s < kMinSpreadRatio || spread_d < kMinSpreadRatio)
    return Status(StatusCode::kDegenerate, "homography: points collinear in an image");

  Mat9d ata = Mat9d::Zero();
  each([&](std::size_t i) {
    const Vec2d p = ns.apply(src[i]), q = nd.apply(dst[i]);
    Vec9d r1, r2;
    r1 << 0.0, 0.0, 0.0, -p.x(), -p.y(), -1.0, q.y() * p.x(), q.y() * p.y(), q.y();
    r2 << p.x(), p.y(), 1.0, 0.0, 0.0, 0.0, -q.x() * p.x(), -q.x() * p.y(), -q.x();
    ata.noalias() += r1 * r1.transpose();
    ata.noalias() += r2 * r2.transpose();
  });
  const NullVector9 nv = smallest_eigenvector9(ata);
  if (!nv.ok) return Status(StatusCode::kDegenerate, "homography: eigen-solve failed");
  if (!(nv.unique_ratio > kMinUniqueRatio)) return Status(StatusCode::kDegenerate, "homography: pairs do not fix a unique H");
  Mat3d hn;
  hn << nv.h(0), nv.h(1), nv.h(2), nv.h(3), nv.h(4), nv.h(5), nv.h(6), nv.h(7), nv.h(8);
  if (is_singular(hn)) return Status(StatusCode::kDegenerate, "homography: singular H");
  const Mat3d h = scale_homography(nd.inverse_matrix() * hn * ns.matrix());
  if (!h.allFinite()) return Status(StatusCode::kDegenerate, "homography: singular H");
  HomographyFit fit;
  fit.H = h;
  fit.used = count;
  const Mat3d hinv = h.inverse();
  double sse = 0.0;
  each([&](std::size_t i) { sse += symmetric_transfer_error_sq(h, hinv, src[i], dst[i]); });
  fit.rms_transfer_px = std::sqrt(sse / (2.0 * count));
  return fit;
}

}  // namespace

bool apply_homography(const Mat3d& H, const Vec2d& p, Vec2d& out) noexcept {
  const Vec3d u = H * Vec3d(p.x(), p.y(), 1.0);
  const double scale = std::abs(u.x()) + std::abs(u.y());
  if (!(std::abs(u.z()) > kMinW * (1.0 + scale))) return false;
  out = Vec2d(u.x() / u.z(), u.y() / u.z());
  return out.allFinite();
}

double symmetric_transfer_error_sq(const Mat3d& H, const Mat3d& Hinv, const Vec2d& src, const Vec2d& dst) noexcept {
  Vec2d f, b;
  if (!apply_homography(H, src, f) || !apply_homography(Hinv, dst, b)) return kInf;
  return (f - dst).squaredNorm() + (b - src).squaredNorm();
}

Result<HomographyFit> fit_homography_dlt(Span<const Vec2d> src, Span<const Vec2d> dst, Span<const std::uint8_t> mask) noexcept {
  if (src.size() != dst.size()) return Status(StatusCode::kInvalidArgument, "homography: point sets differ in length");
  if (!mask.empty() && mask.size() != src.size()) return Status(StatusCode::kInvalidArgument, "homography: mask length differs");
  std::uint32_t count = 0;
  std::uint32_t first4[4] = {0, 0, 0, 0};
  for (std::size_t i = 0; i < src.size(); ++i)
    if (mask.empty() || mask[i] != 0) {
      if (count < 4) first4[count] = static_cast<std::uint32_t>(i);
      ++count;
    }
  if (count == 4) return fit_homography_dlt_indexed(src, dst, Span<const std::uint32_t>(first4, 4));
  return dlt_impl(src, dst, [&](auto f) {
    for (std::size_t i = 0; i < src.size(); ++i)
      if (mask.empty() || mask[i] != 0) f(i);
  });
}

Result<HomographyFit> fit_homography_dlt_indexed(Span<const Vec2d> src, Span<const Vec2d> dst,
                                                 Span<const std::uint32_t> indices) noexcept {
  if (src.size() != dst.size()) return Status(StatusCode::kInvalidArgument, "homography: point sets differ in length");
  for (std::size_t k = 0; k < indices.size(); ++k)
    if (indices[k] >= src.size()) return Status(StatusCode::kOutOfRange, "homography: index out of range");
  if (indices.size() == 4) {
    for (std::size_t k = 0; k < 4; ++k)
      if (!src[indices[k]].allFinite() || !dst[indices[k]].allFinite())
        return Status(StatusCode::kInvalidArgument, "homography: point not finite");
    static constexpr int kTriples[4][3] = {{0, 1, 2}, {0, 1, 3}, {0, 2, 3}, {1, 2, 3}};
    for (const auto& t : kTriples) {
      const int ss = triangle_sign(src[indices[t[0]]], src[indices[t[1]]], src[indices[t[2]]]);
      const int sd = triangle_sign(dst[indices[t[0]]], dst[indices[t[1]]], dst[indices[t[2]]]);
      if (ss == 0 || sd == 0) return Status(StatusCode::kDegenerate, "homography: three of four points collinear");
      if (ss != sd) return Status(StatusCode::kDegenerate, "homography: sample orientation flips between images");
    }
  }
  return dlt_impl(src, dst, [&](auto f) {
    for (std::size_t k = 0; k < indices.size(); ++k) f(static_cast<std::size_t>(indices[k]));
  });
}

namespace {

// Free parameters: the 8 entries of H' other than H'(2,2) = 1, row-major.
Mat3d from_params(const Vec8d& p) noexcept {
  Mat3d h;
  h << p(0), p(1), p(2), p(3), p(4), p(5), p(6), p(7), 1.0;
  return h;
}

// The derivative of pi(u) (u homogeneous, 3-vector) with respect to u.
Eigen::Matrix<double, 2, 3> projection_jacobian(const Vec3d& u) noexcept {
  const double iw = 1.0 / u.z();
  Eigen::Matrix<double, 2, 3> j;
  j << iw, 0.0, -u.x() * iw * iw, 0.0, iw, -u.y() * iw * iw;
  return j;
}

struct NormalisedPairs {
  Span<const Vec2d> src, dst;
  Span<const std::uint8_t> mask;
  HartleyNormalisation ns, nd;
  bool used(std::size_t i) const noexcept { return mask.empty() || mask[i] != 0; }
};

// Cost (px^2) of H' on the normalised pairs: forward residuals in dst pixels (divide by nd.scale),
// backward in src pixels (divide by ns.scale). Accumulates J^T J and J^T r when jtj != nullptr.
double lm_cost(const NormalisedPairs& np, const Mat3d& hn, Mat8d* jtj, Vec8d* jtr) noexcept {
  Eigen::FullPivLU<Mat3d> lu(hn);
  if (!lu.isInvertible()) return kInf;
  const Mat3d hinv = lu.inverse();
  const double wf = 1.0 / np.nd.scale, wb = 1.0 / np.ns.scale;
  double cost = 0.0;
  if (jtj != nullptr) {
    jtj->setZero();
    jtr->setZero();
  }
  for (std::size_t i = 0; i < np.src.size(); ++i) {
    if (!np.used(i)) continue;
    const Vec2d s = np.ns.apply(np.src[i]), d = np.nd.apply(np.dst[i]);
    const Vec3d xs(s.x(), s.y(), 1.0), xd(d.x(), d.y(), 1.0);
    const Vec3d u = hn * xs;
    const Vec3d v = hinv * xd;
    if (!(std::abs(u.z()) > kMinW) || !(std::abs(v.z()) > kMinW)) return kInf;
    const Vec2d rf = wf * (u.head<2>() / u.z() - d);
    const Vec2d rb = wb * (v.head<2>() / v.z() - s);
    cost += rf.squaredNorm() + rb.squaredNorm();
    if (jtj == nullptr) continue;
    // d pi(H' xs) / d H'(r, c) = Pu[:, r] xs(c);  d pi(H'^-1 xd) / d H'(r, c) = -Pv Hinv[:, r] v(c).
    const Eigen::Matrix<double, 2, 3> pu = wf * projection_jacobian(u);
    const Eigen::Matrix<double, 2, 3> pvh = -wb * projection_jacobian(v) * hinv;
    Eigen::Matrix<double, 4, 8> j;
    for (int k = 0; k < 8; ++k) {
      const int r = k / 3, c = k % 3;
      j.block<2, 1>(0, k) = pu.col(r) * xs(c);
      j.block<2, 1>(2, k) = pvh.col(r) * v(c);
    }
    Eigen::Matrix<double, 4, 1> res;
    res << rf, rb;
    jtj->noalias() += j.transpose() * j;
    jtr->noalias() += j.transpose() * res;
  }
  return cost;
}

}  // namespace

Result<HomographyRefinement> refine_homography(Span<const Vec2d> src, Span<const Vec2d> dst, const Mat3d& H0,
                                               Span<const std::uint8_t> mask, const HomographyRefineConfig& config) noexcept {
  if (src.size() != dst.size()) return Status(StatusCode::kInvalidArgument, "homography refine: point sets differ in length");
  if (!mask.empty() && mask.size() != src.size()) return Status(StatusCode::kInvalidArgument, "homography refine: mask length differs");
  if (!H0.allFinite() || !(config.initial_lambda > 0.0) || !(config.min_relative_decrease >= 0.0))
    return Status(StatusCode::kInvalidArgument, "homography refine: bad H0 or configuration");
  NormalisedPairs np{src, dst, mask, {}, {}};
  std::uint32_t count = 0;
  for (std::size_t i = 0; i < src.size(); ++i) {
    if (!np.used(i)) continue;
    if (!src[i].allFinite() || !dst[i].allFinite()) return Status(StatusCode::kInvalidArgument, "homography refine: point not finite");
    ++count;
  }
  if (count < kHomographyMinPairs) return Status(StatusCode::kDegenerate, "homography refine: fewer than 4 pairs");
  double spread_s = 0.0, spread_d = 0.0;
  auto each_used = [&](Span<const Vec2d> pts) {
    return [&np, pts](auto f) {
      for (std::size_t i = 0; i < pts.size(); ++i)
        if (np.used(i)) f(pts[i]);
    };
  };
  if (!hartley_normalisation(each_used(src), np.ns, spread_s) || !hartley_normalisation(each_used(dst), np.nd, spread_d))
    return Status(StatusCode::kDegenerate, "homography refine: points coincide");
  Mat3d hn = np.nd.matrix() * H0 * np.ns.inverse_matrix();
  if (is_singular(hn)) return Status(StatusCode::kDegenerate, "homography refine: singular H0");
  if (!(std::abs(hn(2, 2)) > 1e-8 * hn.norm())) return Status(StatusCode::kDegenerate, "homography refine: H(2,2) ~ 0");
  hn /= hn(2, 2);
  Vec8d p;
  p << hn(0, 0), hn(0, 1), hn(0, 2), hn(1, 0), hn(1, 1), hn(1, 2), hn(2, 0), hn(2, 1);

  Mat8d jtj;
  Vec8d jtr;
  double cost = lm_cost(np, from_params(p), &jtj, &jtr);
  if (!std::isfinite(cost)) return Status(StatusCode::kDegenerate, "homography refine: H0 maps a point to infinity");
  HomographyRefinement out;
  out.initial_rms_px = std::sqrt(cost / (2.0 * count));
  double lambda = config.initial_lambda;
  std::uint32_t it = 0;
  for (; it < config.max_iterations; ++it) {
    Mat8d a = jtj;
    for (int k = 0; k < 8; ++k) a(k, k) += lambda * (jtj(k, k) > 1e-30 ? jtj(k, k) : 1e-30);
    const Eigen::LDLT<Mat8d> ldlt(a);
    if (ldlt.info() != Eigen::Success) break;
    const Vec8d step = ldlt.solve(-jtr);
    if (!step.allFinite()) break;
    const Vec8d cand = p + step;
    Mat8d jtj2;
    Vec8d jtr2;
    const double cost2 = lm_cost(np, from_params(cand), &jtj2, &jtr2);
    if (std::isfinite(cost2) && cost2 < cost) {
      const double decrease = (cost - cost2) / (cost > 0.0 ? cost : 1.0);
      p = cand;
      cost = cost2;
      jtj = jtj2;
      jtr = jtr2;
      lambda = lambda * 0.1 > 1e-12 ? lambda * 0.1 : 1e-12;
      if (decrease < config.min_relative_decrease) {
        ++it;
        break;
      }
    } else {
      lambda *= 10.0;
      if (lambda > 1e12) {
        ++it;
        break;
      }
    }
  }
  const Mat3d h = scale_homography(np.nd.inverse_matrix() * from_params(p) * np.ns.matrix());
  if (!h.allFinite() || is_singular(h)) return Status(StatusCode::kDegenerate, "homography refine: singular result");
  out.iterations = it;
  out.fit.H = h;
  out.fit.used = count;
  out.fit.rms_transfer_px = std::sqrt(cost / (2.0 * count));
  return out;
}

}  // namespace qnav::motion
