// Fundamental matrix by the normalised 8-point algorithm (Hartley 1997), for the underwater paper's
// outlier rejection (matches between two downward-camera frames; robust fits in
// nav/match/robust_two_view.hpp).
//   x_b^T F x_a = 0 for corresponding image points x_a (first image) and x_b (second), in pixels.
// Steps: Hartley-normalise each image's points; accumulate the 9 x 9 normal matrix of the linear
// constraints; F' = eigenvector of its smallest eigenvalue; rank 2 enforced by zeroing F''s smallest
// singular value (3 x 3 SVD); F = T_b^T F' T_a; scaled to |F|_F = 1 with its largest-magnitude
// entry positive (one sign on every target).
// Degenerate input -> a Status, never a matrix: fewer than 8 pairs, points coinciding or collinear in
// either image (kDegenerate); NaN / inf or mismatched lengths (kInvalidArgument). When every point
// lies on one plane of the scene (a flat seabed), F is not unique: the pairs fix only a family
// [e]x H. The fit still satisfies every pair and is returned with unique = false (usable as an
// epipolar outlier filter, not as motion); see robust_two_view.hpp. The flag sees exact
// degeneracy only: noise lifts the ratio (measured: exact plane 3e-17, plane with 0.5 px noise and
// 40 % outliers 1e-5, general scene 4e-4), so it is no model selection between F and H.
// Cost O(n) + one 9 x 9 eigen-solve and one 3 x 3 SVD; no heap (fixed-size Eigen only).
#pragma once

#include <cstdint>

#include "nav/core/geometry.hpp"
#include "nav/core/span.hpp"
#include "nav/core/status.hpp"

namespace qnav::motion {

constexpr std::uint32_t kFundamentalMinPairs = 8;

struct FundamentalFit {
  Mat3d F = Mat3d::Zero();       // x_b^T F x_a = 0, rank 2, |F|_F = 1
  std::uint32_t used = 0;        // pairs used
  double rms_sampson_px = 0.0;   // root-mean-square Sampson distance over the used pairs
  double unique_ratio = 0.0;     // 2nd-smallest / largest eigenvalue of the normalised system
  bool unique = false;           // unique_ratio above kMinUniqueRatio (not a planar / ambiguous set)
};

// Squared Sampson distance (first-order geometric error, px^2) of the pair (a, b) under F;
// +inf when the epipolar lines vanish.
double sampson_distance_sq(const Mat3d& F, const Vec2d& a, const Vec2d& b) noexcept;

// Fit over the pairs a[i] <-> b[i] with mask[i] != 0 (all pairs when mask is empty).
Result<FundamentalFit> fit_fundamental_8point(Span<const Vec2d> a, Span<const Vec2d> b,
                                              Span<const std::uint8_t> mask = Span<const std::uint8_t>()) noexcept;
// Fit over the pairs listed in indices (each < a.size(); the minimal-sample path of RANSAC).
Result<FundamentalFit> fit_fundamental_8point_indexed(Span<const Vec2d> a, Span<const Vec2d> b,
                                                      Span<const std::uint32_t> indices) noexcept;

}  // namespace qnav::motion
