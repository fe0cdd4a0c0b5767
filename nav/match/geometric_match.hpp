// Geometric matching of 3D landmark sets between two stereo acquisitions, given the rotation R from the
// attitude sensor (Souvannavong et al., "Visual odometry for autonomous localization on Mars", sec. 3.2).
//
// Convention: a landmark seen at t-1 (prev) and t (cur) satisfies  M_p = R * M_c + T, where (R, T) is the
// pose of the current left camera in the previous left camera frame. R comes from the attitude sensor;
// T from odometry is only a prior used to gate candidate pairs.
//
// Algorithm (per round):
//   1. candidates: pair (p, c) when |M_p - (R M_c + T_prior)| < gate (gate = n_sigma * sqrt(sigma_T^2 +
//      sigma_p^2 + sigma_c^2), capped at max_gate_m), keeping at most max_candidates_per_landmark nearest.
//   2. matching score S(p, c) = sum over other prev landmarks p' of max over their candidates (p', c') of
//      f(M_p M_p', R M_c M_c') with f = fb (eq. 5, binary) or fc (eq. 7, continuous); per-pair thresholds
//      eps_n = n_sigma * sqrt(sum of the four sigmas^2) + eps_n_floor_m and
//      eps_p = 1 - cos(n_sigma * attitude_sigma_rad + eps_n / |M_p M_p'|). The paper's |cos| is replaced
//      by the signed cosine: with R known, an anti-parallel vector is a mismatch. Optional appearance
//      term (fc only): S *= (1 - w) + w * max(0, ncc(descriptors)).
//   3. potential matches: each prev keeps its best candidate, each cur keeps its best prev (one-to-one),
//      support >= min_support.
//   4. consistency (eq. 6): the binary compatibility of every pair of potential matches is tabulated; the
//      least consistent match (fewest compatible, ties -> lowest continuous consistency) is removed until
//      every remaining match is compatible with all others.
// Fast matching (sec. 3.2.3): rounds over growing prefixes of both sets (landmarks must be given in
// decreasing Harris score), batch_size more corners per round, stopping once min_matches consistent
// matches are found. Rounds recompute the prefix (cost of the last round dominates).
//
// Bounds: prev/cur beyond max_landmarks are ignored (counted); candidates <= max_landmarks *
// max_candidates_per_landmark; potential matches <= max_matches. Worst-case cost per round
// O(n_p n_c) gating + O(N_cand^2) scoring + O(m^2) consistency; N_cand^2 is the term that the gate keeps
// small. Memory: all buffers allocated once in create() (see working_set_bytes()); match() never allocates.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>

#include "nav/core/counters.hpp"
#include "nav/core/geometry.hpp"
#include "nav/core/span.hpp"
#include "nav/core/status.hpp"

namespace qnav::match {

constexpr std::size_t kAppearanceDims = 9;

// One 3D landmark in the left camera frame of its acquisition (x right, y down, z forward, metres).
struct Landmark3 {
  Vec3d position_m = Vec3d::Zero();
  double sigma_m = 0.01;   // 1-sigma isotropic position uncertainty (depth dominated)
  double score = 0.0;      // detector score (Harris); sets are given in decreasing score order
  float u_px = 0.0f;       // pixel in the left image (for plots and overlap tests)
  float v_px = 0.0f;
  bool has_appearance = false;
  float appearance[kAppearanceDims] = {};  // zero-mean unit-norm patch descriptor (optional)
};

enum class MatchScoreKind : std::uint8_t { kBinary, kContinuous };  // fb-matching, fc-matching

struct GeometricMatchConfig {
  std::size_t max_landmarks = 512;              // per set; more are ignored (counted)
  std::size_t max_candidates_per_landmark = 5;  // nearest candidates kept per prev landmark
  std::size_t max_matches = 256;                // potential matches entering the consistency pass
  MatchScoreKind score = MatchScoreKind::kContinuous;
  double n_sigma = 3.0;
  double eps_n_floor_m = 0.003;
  double attitude_sigma_rad = 0.0035;  // ~0.2 deg: relative attitude uncertainty between acquisitions
  double min_vector_m = 0.02;          // pairs closer than this only use the length constraint
  double max_gate_m = 0.5;             // upper bound of the candidate gate radius
  double f_max = 2.0;                  // eq. 7 (> 1)
  double appearance_weight = 0.0;      // 0 = pure geometry; (0,1] = fc appearance term
  double min_support = 2.0;            // minimum matching score of a potential match
  bool fast = false;                   // fast matching (batches in Harris order)
  std::size_t batch_size = 60;
  std::size_t min_matches = 24;  // fast matching stops when this many consistent matches exist
};

// Motion prior: R (attitude) is trusted; T is odometry with 1-sigma uncertainty translation_sigma_m.
// Without a translation prior set translation_sigma_m to the largest plausible step (gate grows).
struct MotionPrior {
  Mat3d R_prev_cur = Mat3d::Identity();
  Vec3d t_prev_cur_m = Vec3d::Zero();
  double translation_sigma_m = 0.03;
};

struct Match {
  std::uint16_t prev = 0;
  std::uint16_t cur = 0;
  float score = 0.0f;        // matching score S (eq. 4)
  float consistency = 0.0f;  // continuous consistency score over the final set (eq. 6)
};

struct MatchStats {
  std::size_t rounds = 0;
  std::size_t prev_used = 0;
  std::size_t cur_used = 0;
  std::size_t candidates = 0;
  std::size_t pair_evaluations = 0;
  std::size_t potential_matches = 0;
  std::size_t removed_by_consistency = 0;
  std::size_t matches = 0;
};

enum class MatchCounter : std::uint8_t {
  kBadPrior,             // non-finite or non-orthonormal R, non-finite T, bad sigma
  kBadLandmark,          // non-finite position / sigma: landmark skipped
  kLandmarksTruncated,   // set larger than max_landmarks
  kCandidateCapHit,      // a landmark had more gated candidates than max_candidates_per_landmark
  kPotentialMatchesCapped,
  kTooFewMatches,        // fewer than 3 consistent matches at the end
  kCount
};

class GeometricMatcher {
 public:
  GeometricMatcher() = default;
  GeometricMatcher(GeometricMatcher&&) noexcept = default;
  GeometricMatcher& operator=(GeometricMatcher&&) noexcept = default;

  // Validates the config and allocates every buffer (the only allocation).
  static Result<GeometricMatcher> create(const GeometricMatchConfig& config) noexcept;

  // Matches prev against cur. On success the returned span (valid until the next call) holds the
  // consistent matches (possibly fewer than 3: the caller decides). Errors: kInvalidArgument (bad prior,
  // matcher not created). Never allocates.
  Result<Span<const Match>> match(Span<const Landmark3> prev, Span<const Landmark3> cur,
                                  const MotionPrior& prior) noexcept;

  const MatchStats& stats() const noexcept { return stats_; }
  const CounterSet<MatchCounter>& counters() const noexcept { return counters_; }
  const GeometricMatchConfig& config() const noexcept { return config_; }
  GeometricMatchConfig& mutable_config() noexcept { return config_; }  // thresholds only, not capacities
  std::size_t working_set_bytes() const noexcept { return bytes_; }

  static const char* const kCounterNames[static_cast<std::size_t>(MatchCounter::kCount)];

 private:
  struct Candidate {
    std::uint16_t prev;
    std::uint16_t cur;
    double dist_m;
    double score;
  };
  struct Group {  // candidates of one prev landmark: [first, first + count)
    std::uint32_t first;
    std::uint32_t count;
    double max_sc2;  // the largest cur sigma^2 of its candidates (score_candidates' skip bound)
  };

  // Compatibility of (p, c) with (p2, c2): returns f (0 when incompatible); binary_ok tells fb.
  double compat(std::size_t p, std::size_t c, std::size_t p2, std::size_t c2, bool* binary_ok) const noexcept;
  void run_round(std::size_t np, std::size_t nc, const MotionPrior& prior) noexcept;
  // The steps of a round (geometric_match.cpp says what each does).
  void gather_candidates(std::size_t np, std::size_t nc, const MotionPrior& prior) noexcept;
  void score_candidates() noexcept;
  std::size_t select_potential(std::size_t nc) noexcept;
  std::size_t consistency_pass(std::size_t m) noexcept;

  GeometricMatchConfig config_;
  std::size_t bytes_ = 0;
  std::unique_ptr<Vec3d[]> prev_pos_;
  std::unique_ptr<Vec3d[]> cur_rot_;  // R * M_c
  std::unique_ptr<double[]> prev_sigma_;
  std::unique_ptr<double[]> cur_sigma_;
  std::unique_ptr<std::uint8_t[]> prev_ok_;
  std::unique_ptr<std::uint8_t[]> cur_ok_;
  std::unique_ptr<Candidate[]> cands_;
  std::unique_ptr<Group[]> groups_;
  std::unique_ptr<std::uint32_t[]> best_of_cur_;
  std::unique_ptr<Match[]> potential_;
  std::unique_ptr<std::uint64_t[]> compat_bits_;  // max_matches x max_matches bit matrix
  std::unique_ptr<std::uint16_t[]> compat_count_;
  std::unique_ptr<double[]> compat_sum_;
  std::unique_ptr<std::uint8_t[]> alive_;
  std::unique_ptr<Match[]> out_;
  std::size_t n_cands_ = 0;
  std::size_t n_groups_ = 0;
  std::size_t n_out_ = 0;
  std::size_t words_per_row_ = 0;
  Span<const Landmark3> prev_in_;
  Span<const Landmark3> cur_in_;
  MatchStats stats_;
  CounterSet<MatchCounter> counters_{kCounterNames};
};

}  // namespace qnav::match
