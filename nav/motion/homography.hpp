// Plane-induced homography between two images (the underwater paper's frame-to-frame motion over a
// flat seabed, chained into a global pose by its eq. 2):  [x_dst; 1] ~ H [x_src; 1], pixels.
//  - fit_homography_dlt: normalised DLT (Hartley-normalise each image's points, accumulate the 9 x 9
//    normal matrix of the 2n linear constraints, h = eigenvector of its smallest eigenvalue,
//    H = T_dst^-1 H' T_src), over 4 or more pairs. H is scaled so H(2,2) = 1 (|H|_F = 1 when
//    H(2,2) ~ 0).
//  - refine_homography: Levenberg-Marquardt on the symmetric transfer error
//      sum_i |pi(H x_i) - x'_i|^2 + |pi(H^-1 x'_i) - x_i|^2
//    over the 8 free entries of H in the normalised coordinates (analytic Jacobian), bounded by
//    max_iterations; returns the initial and final RMS errors (px) and never returns a worse H.
// Degenerate input -> a Status, never a matrix: fewer than 4 pairs, points coinciding or all
// collinear in either image, three of four points collinear (kDegenerate); a pair set that does not
// fix a unique H (null space of dimension >= 2) or a singular result (kDegenerate); NaN / inf or
// mismatched lengths (kInvalidArgument).
// Cost: DLT O(n) + one 9 x 9 eigen-solve; refinement O(n) per iteration plus an 8 x 8 solve.
// No heap (fixed-size Eigen only).
#pragma once

#include <cstdint>

#include "nav/core/geometry.hpp"
#include "nav/core/span.hpp"
#include "nav/core/status.hpp"

namespace qnav::motion {

constexpr std::uint32_t kHomographyMinPairs = 4;

struct HomographyFit {
  Mat3d H = Mat3d::Identity();  // dst ~ H src
  std::uint32_t used = 0;       // pairs used
  double rms_transfer_px = 0.0; // sqrt(mean over pairs of (forward^2 + backward^2) / 2)
};

// Squared symmetric transfer error (px^2) of the pair under H and its inverse Hinv:
// |pi(H s) - d|^2 + |pi(Hinv d) - s|^2; +inf when a point maps to infinity.
double symmetric_transfer_error_sq(const Mat3d& H, const Mat3d& Hinv, const Vec2d& src, const Vec2d& dst) noexcept;
// pi(H p): the point mapped by H; false when it maps to (or near) infinity.
bool apply_homography(const Mat3d& H, const Vec2d& p, Vec2d& out) noexcept;

// DLT over the pairs src[i] <-> dst[i] with mask[i] != 0 (all pairs when mask is empty).
Result<HomographyFit> fit_homography_dlt(Span<const Vec2d> src, Span<const Vec2d> dst,
                                         Span<const std::uint8_t> mask = Span<const std::uint8_t>()) noexcept;
// DLT over the pairs listed in indices (the minimal-sample path of RANSAC). With exactly 4 pairs,
// any three collinear in either image is kDegenerate, and so is a sample whose quadrilaterals have
// different orientations in the two images (no real camera motion gives a mirrored plane).
Result<HomographyFit> fit_homography_dlt_indexed(Span<const Vec2d> src, Span<const Vec2d> dst,
                                                 Span<const std::uint32_t> indices) noexcept;

struct HomographyRefineConfig {
  std::uint32_t max_iterations = 20;    // LM steps tried (accepted or not)
  double initial_lambda = 1e-3;         // Marquardt damping, relative to diag(J^T J)
  double min_relative_decrease = 1e-10; // stop when the cost falls by less than this fraction
};

struct HomographyRefinement {
  HomographyFit fit;             // refined H, rms over the used pairs
  double initial_rms_px = 0.0;   // symmetric transfer RMS of the starting H
  std::uint32_t iterations = 0;  // LM steps taken
};

// Refines H0 on the pairs with mask[i] != 0 (all when empty). Needs >= 4 pairs and an invertible H0.
Result<HomographyRefinement> refine_homography(Span<const Vec2d> src, Span<const Vec2d> dst, const Mat3d& H0,
                                               Span<const std::uint8_t> mask = Span<const std::uint8_t>(),
                                               const HomographyRefineConfig& config = HomographyRefineConfig()) noexcept;

}  // namespace qnav::motion
