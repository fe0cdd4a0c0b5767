#include "nav/match/robust_two_view.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>

namespace qnav::match {

namespace {

// K distinct indices in [0, n) from exactly K draws (Floyd's algorithm), n >= K.
template <std::size_t K>
void draw_sample(DeterministicRng& rng, std::uint32_t n, std::uint32_t (&s)[K]) noexcept {
  std::size_t m = 0;
  for (std::uint32_t j = n - static_cast<std::uint32_t>(K); j < n; ++j) {
    const std::uint32_t t = rng.below(j + 1);
    bool seen = false;
    for (std::size_t k = 0; k < m; ++k) seen = seen || s[k] == t;
    s[m++] = seen ? j : t;
  }
}

Status check_inputs(Span<const Vec2d> a, Span<const Vec2d> b, const RobustTwoViewConfig& c, std::size_t mask_len,
                    std::size_t scratch_len, std::uint32_t sample_size, const char* /*who*/) noexcept {
  const std::size_t n = a.size();
  if (b.size() != n) return Status(StatusCode::kInvalidArgument, "robust two-view: point sets differ in length");
  if (n > 65535) return Status(StatusCode::kInvalidArgument, "robust two-view: more than 65535 pairs");
  if (mask_len < n || scratch_len < n) return Status(StatusCode::kCapacityExceeded, "robust two-view: buffers too small");
  if (c.max_iterations == 0 || !(c.inlier_threshold_px > 0.0) || !(c.min_threshold_px > 0.0) ||
      !(c.max_threshold_px >= c.min_threshold_px) ||
      !(c.confidence > 0.0 && c.confidence < 1.0) || c.min_inliers < sample_size)
    return Status(StatusCode::kInvalidArgument, "robust two-view: bad configuration");
  if (n < sample_size || n < c.min_inliers) return Status(StatusCode::kNotFound, "robust two-view: too few matches");
  for (std::size_t i = 0; i < n; ++i)
    if (!a[i].allFinite() || !b[i].allFinite()) return Status(StatusCode::kInvalidArgument, "robust two-view: point not finite");
  return Status::ok();
}

struct LoopResult {
  bool have = false;
  std::uint32_t iterations = 0;
  double best_median_sq = 0.0;  // LMedS
};

// The hypothesis loop shared by F and H. fit(sample) -> Result<Model>; res_sq(model, i) -> px^2.
template <std::size_t K, typename Model, typename Fit, typename Res>
LoopResult hypothesis_loop(const RobustTwoViewConfig& c, std::uint32_t n, Fit fit, Res res_sq, Span<double> scratch,
                           Model& best) noexcept {
  DeterministicRng rng(c.seed);
  LoopResult out;
  std::uint32_t best_count = 0;
  double best_sum = 0.0;
  std::uint32_t needed = c.max_iterations;
  const double thr2 = c.inlier_threshold_px * c.inlier_threshold_px;
  const std::size_t mid = n / 2;
  std::uint32_t sample[K];
  std::uint32_t it = 0;
  for (; it < needed; ++it) {
    draw_sample(rng, n, sample);
    const Result<Model> h = fit(Span<const std::uint32_t>(sample, K));
    if (!h) continue;
    if (c.method == RobustMethod::kRansac) {
      std::uint32_t count = 0;
      double sum = 0.0;
      for (std::uint32_t i = 0; i < n; ++i) {
        const double r = res_sq(*h, i);
        if (r <= thr2) {
          ++count;
          sum += r;
        }
      }
      if (count > best_count || (count == best_count && out.have && sum < best_sum)) {
        const bool more = count > best_count;
        best_count = count;
        best_sum = sum;
        best = *h;
        out.have = true;
        if (more) {
          // Samples needed for `confidence` that one is all-inlier: log(1 - p) / log(1 - w^K).
          const double w = static_cast<double>(count) / static_cast<double>(n);
          const double denom = std::log(1.0 - std::pow(w, static_cast<double>(K)));
          if (denom < -1e-12) {
            const double k = std::log(1.0 - c.confidence) / denom;
            if (k >= 0.0 && k < static_cast<double>(needed)) needed = static_cast<std::uint32_t>(k) + 1;
          }
        }
      }
    } else {
      for (std::uint32_t i = 0; i < n; ++i) scratch[i] = res_sq(*h, i);
      std::nth_element(scratch.begin(), scratch.begin() + mid, scratch.begin() + n);
      const double med = scratch[mid];
      if (!out.have || med < out.best_median_sq) {
        out.best_median_sq = med;
        best = *h;
        out.have = true;
      }
    }
  }
  out.iterations = it;
  return out;
}

double lmeds_threshold(const RobustTwoViewConfig& c, double median_sq, std::uint32_t n, std::uint32_t k) noexcept {
  const double sigma = 1.4826 * (1.0 + (n > k ? 5.0 / static_cast<double>(n - k) : 5.0)) * std::sqrt(median_sq);
  return std::max(2.5 * sigma, c.min_threshold_px);
}

template <typename Res>
std::uint32_t mark(std::uint32_t n, Res res_sq, double thr2, Span<std::uint8_t> mask) noexcept {
  std::uint32_t count = 0;
  for (std::uint32_t i = 0; i < n; ++i) {
    const bool in = res_sq(i) <= thr2;
    mask[i] = in ? 1 : 0;
    count += in ? 1u : 0u;
  }
  return count;
}

// LMedS's threshold comes from the median of ALL residuals, which over-estimates sigma when many
// pairs are outliers (with 40 % outliers the median is the inliers' 83rd percentile), and from a
// minimal-sample model. One reweighting step (Rousseeuw & Leroy): refit on the LMedS inliers, take
// sigma = 1.4826 sqrt(median squared residual) over those inliers under the refit, threshold
// 2.5 sigma within [min_threshold_px, the LMedS threshold], re-mark. Kept when min_inliers remain.
template <typename Model, typename Refit, typename Res>
void lmeds_reweight(const RobustTwoViewConfig& c, std::uint32_t n, Refit refit, Res res, Model& best, double& thr,
                    std::uint32_t& count, Span<std::uint8_t> mask, Span<double> scratch) noexcept {
  const Result<Model> m = refit(Span<const std::uint8_t>(mask.data(), n));
  if (!m) return;
  std::uint32_t k = 0;
  for (std::uint32_t i = 0; i < n; ++i)
    if (mask[i] != 0) scratch[k++] = res(*m, i);
  if (k == 0) return;
  std::nth_element(scratch.begin(), scratch.begin() + k / 2, scratch.begin() + k);
  const double sigma = 1.4826 * std::sqrt(scratch[k / 2]);
  const double t = std::min(std::max(2.5 * sigma, c.min_threshold_px), thr);
  const std::uint32_t count2 = mark(n, [&](std::uint32_t i) { return res(*m, i); }, t * t, mask);
  if (count2 >= c.min_inliers) {
    best = *m;
    thr = t;
    count = count2;
  } else {
    mark(n, [&](std::uint32_t i) { return res(best, i); }, thr * thr, mask);
  }
}

}  // namespace

Result<RobustFundamental> robust_fundamental(Span<const Vec2d> a, Span<const Vec2d> b, const RobustTwoViewConfig& c,
                                             Span<std::uint8_t> mask_out, Span<double> scratch) noexcept {
  QNAV_RETURN_IF_ERROR(check_inputs(a, b, c, mask_out.size(), scratch.size(), motion::kFundamentalMinPairs, "fundamental"));
  const std::uint32_t n = static_cast<std::uint32_t>(a.size());
  auto res = [&](const motion::FundamentalFit& f, std::uint32_t i) { return motion::sampson_distance_sq(f.F, a[i], b[i]); };
  motion::FundamentalFit best;
  const LoopResult loop = hypothesis_loop<motion::kFundamentalMinPairs>(
      c, n, [&](Span<const std::uint32_t> s) { return motion::fit_fundamental_8point_indexed(a, b, s); }, res, scratch, best);
  if (!loop.have) return Status(StatusCode::kDegenerate, "robust fundamental: every sample degenerate");
  RobustFundamental out;
  out.iterations = loop.iterations;
  out.threshold_px = c.method == RobustMethod::kLmeds ? lmeds_threshold(c, loop.best_median_sq, n, motion::kFundamentalMinPairs)
                                                      : c.inlier_threshold_px;
  if (c.method == RobustMethod::kLmeds && !(out.threshold_px <= c.max_threshold_px))
    return Status(StatusCode::kNotFound, "robust fundamental: LMedS median residual too large (over half outliers)");
  std::uint32_t count =
      mark(n, [&](std::uint32_t i) { return res(best, i); }, out.threshold_px * out.threshold_px, mask_out);
  if (count < c.min_inliers) return Status(StatusCode::kNotFound, "robust fundamental: too few inliers");
  auto refit_on = [&](Span<const std::uint8_t> m) { return motion::fit_fundamental_8point(a, b, m); };
  if (c.method == RobustMethod::kLmeds) lmeds_reweight(c, n, refit_on, res, best, out.threshold_px, count, mask_out, scratch);
  const double thr2 = out.threshold_px * out.threshold_px;
  // Refit on the inliers; keep the refit when it does not lose support; the mask is the final F's.
  Result<motion::FundamentalFit> refit = refit_on(Span<const std::uint8_t>(mask_out.data(), n));
  if (refit) {
    const std::uint32_t count2 = mark(n, [&](std::uint32_t i) { return res(*refit, i); }, thr2, mask_out);
    if (count2 >= count) {
      Result<motion::FundamentalFit> refit2 = refit_on(Span<const std::uint8_t>(mask_out.data(), n));
      best = refit2 ? *refit2 : *refit;
    }
  }
  count = mark(n, [&](std::uint32_t i) { return res(best, i); }, thr2, mask_out);
  if (count < c.min_inliers) return Status(StatusCode::kNotFound, "robust fundamental: too few inliers");
  double sse = 0.0;
  for (std::uint32_t i = 0; i < n; ++i)
    if (mask_out[i] != 0) sse += res(best, i);
  best.used = count;
  best.rms_sampson_px = std::sqrt(sse / static_cast<double>(count));
  out.fit = best;
  out.inliers = count;
  return out;
}

Result<FundamentalConsensus> robust_fundamental_both(Span<const Vec2d> a, Span<const Vec2d> b,
                                                     const RobustTwoViewConfig& ransac_config,
                                                     const RobustTwoViewConfig& lmeds_config, Span<std::uint8_t> mask_out,
                                                     Span<std::uint8_t> mask_scratch, Span<double> scratch) noexcept {
  if (mask_scratch.size() < a.size()) return Status(StatusCode::kCapacityExceeded, "robust two-view: buffers too small");
  RobustTwoViewConfig rc = ransac_config;
  rc.method = RobustMethod::kRansac;
  RobustTwoViewConfig lc = lmeds_config;
  lc.method = RobustMethod::kLmeds;
  Result<RobustFundamental> r = robust_fundamental(a, b, rc, mask_out, scratch);
  if (!r) return r.status();
  Result<RobustFundamental> l = robust_fundamental(a, b, lc, mask_scratch, scratch);
  if (!l) return l.status();
  const std::size_t n = a.size();
  std::uint32_t count = 0;
  for (std::size_t i = 0; i < n; ++i) {
    mask_out[i] = (mask_out[i] != 0 && mask_scratch[i] != 0) ? 1 : 0;
    count += mask_out[i];
  }
  if (count < std::max(rc.min_inliers, lc.min_inliers)) return Status(StatusCode::kNotFound, "robust fundamental: too few common inliers");
  Result<motion::FundamentalFit> fit = motion::fit_fundamental_8point(a, b, Span<const std::uint8_t>(mask_out.data(), n));
  if (!fit) return fit.status();
  FundamentalConsensus out;
  out.ransac = *r;
  out.lmeds = *l;
  out.fit = *fit;
  out.inliers = count;
  return out;
}

Result<RobustHomography> robust_homography(Span<const Vec2d> src, Span<const Vec2d> dst, const RobustTwoViewConfig& c,
                                           Span<std::uint8_t> mask_out, Span<double> scratch) noexcept {
  QNAV_RETURN_IF_ERROR(check_inputs(src, dst, c, mask_out.size(), scratch.size(), motion::kHomographyMinPairs, "homography"));
  const std::uint32_t n = static_cast<std::uint32_t>(src.size());
  struct Model {
    Mat3d H = Mat3d::Identity();
    Mat3d Hinv = Mat3d::Identity();
  };
  // Half the symmetric transfer error: a per-image squared distance.
  auto res = [&](const Model& m, std::uint32_t i) { return 0.5 * motion::symmetric_transfer_error_sq(m.H, m.Hinv, src[i], dst[i]); };
  auto model_of = [](const Mat3d& h) {
    Model m;
    m.H = h;
    m.Hinv = h.inverse();
    return m;
  };
  Model best;
  const LoopResult loop = hypothesis_loop<motion::kHomographyMinPairs>(
      c, n,
      [&](Span<const std::uint32_t> s) -> Result<Model> {
        Result<motion::HomographyFit> f = motion::fit_homography_dlt_indexed(src, dst, s);
        if (!f) return f.status();
        return model_of(f->H);
      },
      res, scratch, best);
  if (!loop.have) return Status(StatusCode::kDegenerate, "robust homography: every sample degenerate");
  RobustHomography out;
  out.iterations = loop.iterations;
  out.threshold_px = c.method == RobustMethod::kLmeds ? lmeds_threshold(c, loop.best_median_sq, n, motion::kHomographyMinPairs)
                                                      : c.inlier_threshold_px;
  if (c.method == RobustMethod::kLmeds && !(out.threshold_px <= c.max_threshold_px))
    return Status(StatusCode::kNotFound, "robust homography: LMedS median residual too large (over half outliers)");
  std::uint32_t count =
      mark(n, [&](std::uint32_t i) { return res(best, i); }, out.threshold_px * out.threshold_px, mask_out);
  if (count < c.min_inliers) return Status(StatusCode::kNotFound, "robust homography: too few inliers");
  if (c.method == RobustMethod::kLmeds) {
    auto refit_on = [&](Span<const std::uint8_t> m) -> Result<Model> {
      Result<motion::HomographyFit> f = motion::fit_homography_dlt(src, dst, m);
      if (!f) return f.status();
      return model_of(f->H);
    };
    lmeds_reweight(c, n, refit_on, res, best, out.threshold_px, count, mask_out, scratch);
  }
  const double thr2 = out.threshold_px * out.threshold_px;
  // DLT on the inliers, LM refinement, re-mark; keep it when it does not lose support.
  Result<motion::HomographyFit> dlt = motion::fit_homography_dlt(src, dst, Span<const std::uint8_t>(mask_out.data(), n));
  Mat3d start = dlt ? dlt->H : best.H;
  Result<motion::HomographyRefinement> ref =
      motion::refine_homography(src, dst, start, Span<const std::uint8_t>(mask_out.data(), n), c.refine);
  motion::HomographyFit fit;
  if (ref) {
    const Model m = model_of(ref->fit.H);
    const std::uint32_t count2 = mark(n, [&](std::uint32_t i) { return res(m, i); }, thr2, mask_out);
    if (count2 >= count) {
      // One more refinement on the final inlier set.
      Result<motion::HomographyRefinement> ref2 =
          motion::refine_homography(src, dst, m.H, Span<const std::uint8_t>(mask_out.data(), n), c.refine);
      fit = ref2 ? ref2->fit : ref->fit;
      out.refine_iterations = ref->iterations + (ref2 ? ref2->iterations : 0u);
      const Model m2 = model_of(fit.H);
      count = mark(n, [&](std::uint32_t i) { return res(m2, i); }, thr2, mask_out);
    } else {
      count = mark(n, [&](std::uint32_t i) { return res(best, i); }, thr2, mask_out);
      fit.H = best.H;
      fit.used = count;
    }
  } else {
    fit.H = best.H;
    fit.used = count;
  }
  if (count < c.min_inliers) return Status(StatusCode::kNotFound, "robust homography: too few inliers");
  // Report the RMS over the final inliers.
  const Model mf = model_of(fit.H);
  double sse = 0.0;
  for (std::uint32_t i = 0; i < n; ++i)
    if (mask_out[i] != 0) sse += res(mf, i);
  fit.used = count;
  fit.rms_transfer_px = std::sqrt(sse / static_cast<double>(count));
  out.fit = fit;
  out.inliers = count;
  return out;
}

}  // namespace qnav::match
