// Robust two-view fits over putative image matches a[i] <-> b[i] (pixels), for the underwater
// paper's frame-to-frame registration:
//  - robust_fundamental: RANSAC or LMedS over minimal 8-pair samples (normalised 8-point,
//    nav/motion/fundamental.hpp), residual = Sampson distance;
//  - robust_fundamental_both: the paper's rule: run RANSAC and LMedS, keep the matches BOTH accept,
//    refit F on them;
//  - robust_homography: RANSAC or LMedS over minimal 4-pair samples (normalised DLT; samples with
//    collinear triples or a mirrored quadrilateral are skipped), residual = symmetric transfer error;
//    then DLT on the inliers, Levenberg-Marquardt refinement (nav/motion/homography.hpp), inliers
//    re-marked with the refined H.
// Both methods draw samples with the seeded DeterministicRng of ransac.hpp (Floyd's algorithm: K
// distinct indices from exactly K draws), so the same input, configuration and seed give the same
// answer on every target. RANSAC keeps the hypothesis with most residuals <= threshold (ties: lower
// sum of inlier residuals) and stops early once the standard bound log(1-p) / log(1-w^K) is met;
// LMedS keeps the smallest median squared residual, and its inliers are the pairs within
// 2.5 x 1.4826 (1 + 5 / (n - K)) sqrt(median), floored at min_threshold_px; above max_threshold_px
// the median pair is itself an outlier (LMedS breaks down past 50 % outliers): kNotFound. That
// threshold over-estimates sigma when many pairs are outliers, so LMedS then takes one reweighting
// step (Rousseeuw & Leroy): refit on its inliers, sigma from their median residual, re-mark.
// The final fit is refined on the inliers and the inliers re-marked with it (kept only if it does not
// lose support).
// Bounds: at most max_iterations hypotheses, each O(n) (LMedS: + O(n) nth_element); n <= 65535.
// No heap: the caller passes mask_out (n bytes) and scratch (n doubles; robust_fundamental_both also
// a second n-byte mask).
#pragma once

#include <cstdint>

#include "nav/core/geometry.hpp"
#include "nav/core/span.hpp"
#include "nav/core/status.hpp"
#include "nav/match/ransac.hpp"
#include "nav/motion/fundamental.hpp"
#include "nav/motion/homography.hpp"

namespace qnav::match {

struct RobustTwoViewConfig {
  RobustMethod method = RobustMethod::kRansac;
  std::uint32_t max_iterations = 1000;  // hypotheses (minimal samples) drawn at most
  double inlier_threshold_px = 2.0;     // RANSAC: residual (Sampson / symmetric transfer) bound,
                                        // ~ 3 sigma of 0.5 px keypoint noise in both images
  double min_threshold_px = 0.5;        // LMedS: floor of the derived threshold (noise-free data)
  double max_threshold_px = 8.0;        // LMedS: a derived threshold above this -> kNotFound (no
                                        // consensus: the median pair is an outlier)
  double confidence = 0.999;            // RANSAC early exit
  std::uint32_t min_inliers = 12;       // fewer -> kNotFound
  std::uint64_t seed = 0x51A7u;
  motion::HomographyRefineConfig refine{};  // robust_homography's final LM refinement
};

struct RobustFundamental {
  motion::FundamentalFit fit;    // refit on the inliers
  std::uint32_t inliers = 0;
  std::uint32_t iterations = 0;  // hypotheses drawn
  double threshold_px = 0.0;     // the inlier threshold used (LMedS: derived)
};

// mask_out and scratch must hold a.size() elements.
Result<RobustFundamental> robust_fundamental(Span<const Vec2d> a, Span<const Vec2d> b, const RobustTwoViewConfig& config,
                                             Span<std::uint8_t> mask_out, Span<double> scratch) noexcept;

struct FundamentalConsensus {
  RobustFundamental ransac;      // RANSAC alone (its inlier count and threshold)
  RobustFundamental lmeds;       // LMedS alone
  motion::FundamentalFit fit;    // F refit on the matches both accept
  std::uint32_t inliers = 0;     // matches both accept (mask_out)
};

// RANSAC with ransac_config (its method field is ignored) and LMedS with lmeds_config; mask_out = the
// matches both accept. mask_scratch (a.size() bytes) holds the LMedS mask during the call.
// Either method failing, or fewer than max(min_inliers) common matches, -> its status / kNotFound.
Result<FundamentalConsensus> robust_fundamental_both(Span<const Vec2d> a, Span<const Vec2d> b,
                                                     const RobustTwoViewConfig& ransac_config,
                                                     const RobustTwoViewConfig& lmeds_config, Span<std::uint8_t> mask_out,
                                                     Span<std::uint8_t> mask_scratch, Span<double> scratch) noexcept;

struct RobustHomography {
  motion::HomographyFit fit;     // DLT on the inliers, LM-refined
  std::uint32_t inliers = 0;
  std::uint32_t iterations = 0;  // hypotheses drawn
  std::uint32_t refine_iterations = 0;
  double threshold_px = 0.0;     // symmetric transfer threshold used (per image, px)
};

// src[i] <-> dst[i]; mask_out and scratch must hold src.size() elements. The threshold applies to
// sqrt((forward^2 + backward^2) / 2), so it reads as a per-image pixel distance.
Result<RobustHomography> robust_homography(Span<const Vec2d> src, Span<const Vec2d> dst, const RobustTwoViewConfig& config,
                                           Span<std::uint8_t> mask_out, Span<double> scratch) noexcept;

}  // namespace qnav::match
