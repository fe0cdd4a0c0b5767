// fc-matching in 2D (Mars VO paper's geometric fc-matching, brought down to the plane for the route
// registration): matches two keypoint sets A (sensed tile) and B (reference node) whose relative
// rotation dtheta (B frame from A frame, known from the heading sensor) is known and whose
// translation is not.
//   1. candidates: each a keeps its best max_candidates_per_point b by appearance (ZNCC of the int8
//      patch descriptors) with ZNCC >= min_appearance.
//   2. continuous score of candidate c = (a, b): S(c) = sum over the other keypoints a' of the best
//      compatibility with one of their candidates (a', b'), b' != b:
//        f = exp(-0.5 (dd / sigma_dist_m)^2) * exp(-0.5 (dphi / sigma_phi)^2)
//      dd = | |a' - a| - |b' - b| |  (distances preserved),
//      dphi = angle between R(dtheta)(a' - a) and (b' - b)  (directions preserved),
//      sigma_phi = sigma_dir_rad + sigma_dist_m / |a' - a| (short baselines give loose directions);
//      then the appearance term: S *= (1 - w) + w * max(0, zncc(a, b)).
//   3. greedy one-to-one selection by decreasing S while S >= min_support.
// The output are putative matches for RANSAC / LMedS (nav/match/ransac.hpp).
// Bounds: points beyond max_points are ignored (counted); candidates <= max_points *
// max_candidates_per_point; the scoring visits only candidate pairs whose implied translations lie
// within the gate's largest radius (same scores as visiting every pair); descriptors of at most max_descriptor_bytes (longer: kBadInput); cost
// O(nA nB D) appearance + O(C^2) scoring, C candidates. With SIMD (SSE2, NEON) the appearance dot
// products run on int16 copies of the descriptors (widened once per call; a 16-bit multiply-add the
// compiler vectorises on x86 and ARM, the same integer sums as int8), with a fixed-length loop for
// 64-byte descriptors; without SIMD (LEON3, armhf VFP) on the int8 descriptors, two rows of A
// against four of B per pass (the same integer sums), and for 64-byte descriptors pruned: the last 12
// terms of a pair only when a Cauchy-Schwarz bound on them lets it join a's list (the same lists,
// bit for bit; FcMatch2dConfig::force_scalar_kernels takes this path on any build, for the tests).
// Memory: init() takes all buffers from an Arena (2 * max_points * max_descriptor_bytes int16 of
// them for the widened descriptors; per candidate 4 doubles + 1 uint32 of translation-ordered copies
// for the scoring's neighbour scan; two rows of dot products, one of ZNCCs; 12 floats per point for the
// pruned path's bound factors); match() never allocates.
#pragma once

#include <cstddef>
#include <cstdint>

#include "nav/core/arena.hpp"
#include "nav/core/counters.hpp"
#include "nav/core/fixed_vector.hpp"
#include "nav/core/geometry.hpp"
#include "nav/core/span.hpp"
#include "nav/core/status.hpp"

namespace qnav::match {

// Zero-mean normalised cross-correlation of two int8 descriptors of n bytes; 0 when either is flat.
float zncc_i8(const std::int8_t* a, const std::int8_t* b, std::size_t n) noexcept;

// A 2D keypoint set: positions (metres, the set's own frame) and descriptors (desc_bytes each,
// concatenated, same order).
struct KeypointSet2d {
  Span<const Vec2d> position_m;
  Span<const std::int8_t> descriptors;
  std::size_t desc_bytes = 0;
};

struct Match2d {
  std::uint16_t a = 0;  // index in A
  std::uint16_t b = 0;  // index in B
  float score = 0.0f;
  float appearance = 0.0f;  // ZNCC
};

struct FcMatch2dConfig {
  std::size_t max_points = 128;           // per set
  std::size_t max_candidates_per_point = 4;
  float min_appearance = 0.25f;           // ZNCC floor for a candidate
  double sigma_dist_m = 1.0;              // keypoint position noise (both sets), metres
  double sigma_dir_rad = 0.05;            // heading noise between the two sets
  float appearance_weight = 0.5f;         // w in [0, 1]
  float min_support = 1.5f;               // score floor for a match
  std::size_t max_descriptor_bytes = 64;  // longest descriptor match() accepts (the route's 8 x 8)
  bool force_scalar_kernels = false;      // tests: the no-SIMD (LEON3) appearance kernels on any build
};

enum class FcMatchCounter : std::uint8_t { kPointsIgnored, kBadInput, kCount };
inline constexpr const char* kFcMatchCounterNames[] = {"points_ignored", "bad_input"};

class FcMatcher2d {
 public:
  FcMatcher2d() noexcept : counters_(kFcMatchCounterNames) {}
  Status init(const FcMatch2dConfig& config, Arena& arena) noexcept;
  static std::size_t arena_bytes(const FcMatch2dConfig& config) noexcept;

  // Matches A against B given dtheta_rad (B frame = R(dtheta) * A frame + t). out is cleared first.
  Status match(const KeypointSet2d& a, const KeypointSet2d& b, double dtheta_rad, BoundedVector<Match2d>& out) noexcept;

  const FcMatch2dConfig& config() const noexcept { return config_; }
  const CounterSet<FcMatchCounter>& counters() const noexcept { return counters_; }

 private:
  struct Candidate {
    std::uint16_t a = 0;
    std::uint16_t b = 0;
    float appearance = 0.0f;
    float score = 0.0f;
  };
  std::size_t appearance_candidates(const KeypointSet2d& a, const KeypointSet2d& b, std::size_t na, std::size_t nb) noexcept;
  std::size_t appearance_pruned(const KeypointSet2d& a, const KeypointSet2d& b, std::size_t na, std::size_t nb) noexcept;
  void translation_gate(const KeypointSet2d& a, const KeypointSet2d& b, std::size_t na, std::size_t nb,
                        double& gate_radius_m, double& abs_max_m) const noexcept;
  FcMatch2dConfig config_{};
  bool ready_ = false;
  Span<Candidate> cand_;
  Span<std::uint32_t> first_;   // per a: first candidate index (cand_ is grouped by a)
  Span<std::uint32_t> order_;   // candidate order: by implied translation x (scoring), then for the greedy pass
  Span<std::uint32_t> near_;    // one candidate's neighbours in translation (scoring)
  Span<Vec2d> translation_;     // per candidate (a, b): b - R(dtheta) a
  // The candidates in translation order, streamed by the scoring's neighbour scan: t.x, t.y, the
  // position of a, a's index, the candidate index.
  Span<double> sorted_tx_, sorted_ty_, sorted_ax_, sorted_ay_;
  Span<std::uint32_t> sorted_a_;
  Span<std::uint8_t> used_a_;
  Span<std::uint8_t> used_b_;
  Span<float> stats_a_, stats_b_;  // per descriptor: sum, 1 / sqrt(n var)
  Span<std::int16_t> wide_a_, wide_b_;  // descriptors widened to int16 (max_points x max_descriptor_bytes)
  Span<std::int32_t> dot_row_;  // two rows of a's dot products with every b (appearance)
  Span<float> z_row_;           // one a's ZNCC with every b (-inf for a flat b)
  Span<float> sum_b_, inv_b_;   // stats_b_ split in two arrays (a loop over b that vectorises)
  Span<float> bound_;           // pruned path (no SIMD): 4 bound factors per a, 8 floats per b
  CounterSet<FcMatchCounter> counters_;
};

}  // namespace qnav::match
