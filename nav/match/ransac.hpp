// Robust rigid 2D estimation over putative correspondences: RANSAC (Fischler & Bolles) or LMedS
// (least median of squares), both over minimal 2-pair samples drawn by a seeded deterministic RNG,
// so the same input and seed give the same answer on every target.
//  - RANSAC keeps the hypothesis with most pairs within inlier_threshold_m; stops early when the
//    standard confidence bound says enough samples were drawn.
//  - LMedS keeps the hypothesis with the smallest median squared residual; inliers are then pairs
//    within 2.5 x the robust sigma 1.4826 (1 + 5 / (n - 2)) sqrt(median) (no threshold to tune).
// Both refit the inliers by the closed-form rigid2d fit and report the inlier count (the route
// paper's similarity S), the pose, its covariance and the mask.
// Bounds: at most max_iterations hypotheses, each O(n) (LMedS: O(n) nth_element); n <= the caller's
// mask/scratch length. No heap: the caller passes mask (n bytes) and scratch (n doubles).
#pragma once

#include <cstdint>

#include "nav/core/geometry.hpp"
#include "nav/core/span.hpp"
#include "nav/core/status.hpp"
#include "nav/motion/rigid2d.hpp"

namespace qnav::match {

// SplitMix64: tiny, seedable, identical on every platform.
class DeterministicRng {
 public:
  explicit DeterministicRng(std::uint64_t seed) noexcept : state_(seed) {}
  std::uint64_t next() noexcept {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  // Uniform in [0, n), n > 0.
  std::uint32_t below(std::uint32_t n) noexcept { return static_cast<std::uint32_t>(next() % n); }
  // Uniform in [0, 1).
  double uniform() noexcept { return static_cast<double>(next() >> 11) * (1.0 / 9007199254740992.0); }

 private:
  std::uint64_t state_;
};

enum class RobustMethod : std::uint8_t { kRansac, kLmeds };

struct RobustConfig {
  RobustMethod method = RobustMethod::kRansac;
  std::uint32_t max_iterations = 200;
  double inlier_threshold_m = 1.0;     // RANSAC only
  double confidence = 0.999;           // RANSAC early exit
  double min_sample_separation_m = 0.5;
  std::uint32_t min_inliers = 3;       // fewer -> kNotFound (no transform)
  std::uint64_t seed = 0x51A7u;
};

struct RobustRigid2d {
  motion::Rigid2dFit fit;        // refit on the inliers
  std::uint32_t inliers = 0;
  std::uint32_t iterations = 0;  // hypotheses tried
  double threshold_m = 0.0;      // the inlier threshold used (LMedS: derived)
};

// src[i] <-> dst[i]; mask_out and scratch must hold src.size() elements.
Result<RobustRigid2d> robust_rigid2d(Span<const Vec2d> src, Span<const Vec2d> dst, const RobustConfig& config,
                                     Span<std::uint8_t> mask_out, Span<double> scratch) noexcept;

}  // namespace qnav::match
