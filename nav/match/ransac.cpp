#include "nav/match/ransac.hpp"

#include <algorithm>
#include <cmath>

namespace qnav::match {

namespace {
std::uint32_t mark_inliers(Span<const Vec2d> src, Span<const Vec2d> dst, const Pose2& p, double thr2,
                           Span<std::uint8_t> mask) noexcept {
  std::uint32_t n = 0;
  for (std::size_t i = 0; i < src.size(); ++i) {
    const bool in = (p.apply(src[i]) - dst[i]).squaredNorm() <= thr2;
    mask[i] = in ? 1 : 0;
    n += in ? 1u : 0u;
  }
  return n;
}
}  // namespace

Result<RobustRigid2d> robust_rigid2d(Span<const Vec2d> src, Span<const Vec2d> dst, const RobustConfig& config,
                                     Span<std::uint8_t> mask_out, Span<double> scratch) noexcept {
  const std::size_t n = src.size();
  if (dst.size() != n) return Status(StatusCode::kInvalidArgument, "robust_rigid2d: point sets differ in length");
  if (mask_out.size() < n || scratch.size() < n) return Status(StatusCode::kCapacityExceeded, "robust_rigid2d: buffers too small");
  if (config.max_iterations == 0 || !(config.inlier_threshold_m > 0.0) || config.min_inliers < 2)
    return Status(StatusCode::kInvalidArgument, "robust_rigid2d: bad configuration");
  if (n < 2 || n < config.min_inliers) return Status(StatusCode::kNotFound, "robust_rigid2d: too few correspondences");
  for (std::size_t i = 0; i < n; ++i)
    if (!src[i].allFinite() || !dst[i].allFinite()) return Status(StatusCode::kInvalidArgument, "robust_rigid2d: point not finite");

  DeterministicRng rng(config.seed);
  const std::uint32_t nn = static_cast<std::uint32_t>(n);
  Pose2 best;
  bool have = false;
  std::uint32_t best_count = 0;
  double best_med = 0.0;
  std::uint32_t iters = 0;
  std::uint32_t needed = config.max_iterations;
  const double thr2 = config.inlier_threshold_m * config.inlier_threshold_m;
  const std::size_t mid = n / 2;
  for (; iters < needed; ++iters) {
    const std::uint32_t i0 = rng.below(nn);
    std::uint32_t i1 = rng.below(nn - 1);
    if (i1 >= i0) ++i1;
    const Result<Pose2> h = motion::rigid2d_from_two(src[i0], src[i1], dst[i0], dst[i1], config.min_sample_separation_m);
    if (!h) continue;
    if (config.method == RobustMethod::kRansac) {
      std::uint32_t c = 0;
      for (std::size_t i = 0; i < n; ++i) c += (h->apply(src[i]) - dst[i]).squaredNorm() <= thr2 ? 1u : 0u;
      if (c > best_count) {
        best_count = c;
        best = *h;
        have = true;
        // Samples needed for `confidence` that one is all-inlier: log(1-p) / log(1 - w^2).
        const double w = static_cast<double>(c) / static_cast<double>(n);
        const double denom = std::log(1.0 - w * w);
        if (denom < -1e-12) {
          const double k = std::log(1.0 - config.confidence) / denom;
          if (k >= 0.0 && k < static_cast<double>(needed)) needed = static_cast<std::uint32_t>(k) + 1;
        }
      }
    } else {
      for (std::size_t i = 0; i < n; ++i) scratch[i] = (h->apply(src[i]) - dst[i]).squaredNorm();
      std::nth_element(scratch.begin(), scratch.begin() + mid, scratch.begin() + n);
      const double med = scratch[mid];
      if (!have || med < best_med) {
        best_med = med;
        best = *h;
        have = true;
      }
    }
  }
  if (!have) return Status(StatusCode::kDegenerate, "robust_rigid2d: every sample degenerate");
  RobustRigid2d out;
  out.iterations = iters;
  double thr = config.inlier_threshold_m;
  if (config.method == RobustMethod::kLmeds) {
    const double sigma = 1.4826 * (1.0 + (n > 2 ? 5.0 / static_cast<double>(n - 2) : 5.0)) * std::sqrt(best_med);
    thr = std::max(2.5 * sigma, 1e-3);
  }
  out.threshold_m = thr;
  std::uint32_t count = mark_inliers(src, dst, best, thr * thr, mask_out);
  if (count < config.min_inliers) return Status(StatusCode::kNotFound, "robust_rigid2d: too few inliers");
  // Refit on inliers, then re-mark once with the refit pose (a refit never loses its own support much).
  Result<motion::Rigid2dFit> fit = motion::fit_rigid2d(src, dst, Span<const std::uint8_t>(mask_out.data(), n));
  if (!fit) return fit.status();
  const std::uint32_t count2 = mark_inliers(src, dst, fit->pose, thr * thr, mask_out);
  if (count2 >= count) {
    count = count2;
    Result<motion::Rigid2dFit> fit2 = motion::fit_rigid2d(src, dst, Span<const std::uint8_t>(mask_out.data(), n));
    if (fit2) fit = fit2;
  } else {
    count = mark_inliers(src, dst, best, thr * thr, mask_out);
  }
  if (count < config.min_inliers) return Status(StatusCode::kNotFound, "robust_rigid2d: too few inliers");
  out.fit = *fit;
  out.inliers = count;
  return out;
}

}  // namespace qnav::match
