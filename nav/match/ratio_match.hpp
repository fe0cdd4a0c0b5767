// Nearest-neighbour matching of oriented gradient descriptors (nav/vision/descriptor.hpp) with
// Lowe's ratio test, as the underwater paper matches SIFT keypoints between frames.
// For each query descriptor q, over its candidate train descriptors: nearest t1 at L2 distance d1,
// second nearest at d2. q <-> t1 is kept when
//    d1 < max_ratio * d2   (Lowe 2004; a query with a single candidate passes only if accept_single)
//    d1 <= max_distance
//    and, when mutual is set, q is also the nearest query of t1 among the queries that considered it.
// Candidates: every train descriptor (match), or, when a prediction of each query's position in
// the train image exists (e.g. through the previous homography), the train descriptors within
// search_radius_px of it (match_predicted), found through a uniform grid over the train positions
// (train[j].x, .y) and capped at max_candidates per query (cells visited row by row; a cap reached
// is counted).
// Distances are summed in a fixed order with an early exit once a partial sum exceeds every bound it
// could still change, so results equal the brute-force ones bit for bit on a given target.
// Bounds: queries beyond max_query and train descriptors beyond max_train are ignored (counted);
// output holds at most one match per query, ordered by query index.
// Cost: match O(nq nt 128); match_predicted O(nt + cells + nq min(max_candidates, local density) 128).
// Memory: init() takes every buffer from an Arena (arena_bytes); the match calls never allocate.
#pragma once

#include <cstddef>
#include <cstdint>

#include "nav/core/arena.hpp"
#include "nav/core/counters.hpp"
#include "nav/core/fixed_vector.hpp"
#include "nav/core/geometry.hpp"
#include "nav/core/span.hpp"
#include "nav/core/status.hpp"
#include "nav/vision/descriptor.hpp"

namespace qnav::match {

struct RatioMatchConfig {
  std::size_t max_query = 512;       // query descriptors considered (<= 65535)
  std::size_t max_train = 512;       // train descriptors considered (<= 65535)
  float max_ratio = 0.8f;            // Lowe's ratio d1 / d2, in (0, 1]
  float max_distance = 2.0f;         // L2 ceiling on d1 (unit descriptors: distances lie in [0, 2])
  bool mutual = false;               // also require t1's nearest query to be q
  bool accept_single = false;        // a query with exactly one candidate passes the ratio test
  float search_radius_px = 24.0f;    // match_predicted: candidate radius around the prediction
  std::size_t max_candidates = 64;   // match_predicted: train descriptors compared per query, at most
  std::size_t grid_side = 32;        // match_predicted: grid cells per side, at most (<= 256)
};

struct DescriptorMatch {
  std::uint16_t query = 0;  // index in the query span
  std::uint16_t train = 0;  // index in the train span
  float distance = 0.0f;    // d1 (L2)
  float ratio = 0.0f;       // d1 / d2 (0 when the query had a single candidate)
};

// What the last call decided, per query (not errors; those are the counters).
struct RatioMatchStats {
  std::uint32_t queries = 0;           // valid queries considered
  std::uint32_t matched = 0;
  std::uint32_t no_candidate = 0;
  std::uint32_t ratio_rejected = 0;    // includes single candidates when accept_single is off
  std::uint32_t distance_rejected = 0;
  std::uint32_t mutual_rejected = 0;
  std::uint64_t distances = 0;         // descriptor distances started (a measure of the work)
};

enum class RatioMatchCounter : std::uint8_t {
  kQueryIgnored,        // beyond max_query
  kTrainIgnored,        // beyond max_train
  kInvalidDescriptor,   // valid == false or a non-finite position (train, predicted mode)
  kBadPrediction,       // a non-finite predicted position
  kCandidatesCapped,    // a query reached max_candidates
  kOutputFull,          // the output vector filled up
  kCount
};
inline constexpr const char* kRatioMatchCounterNames[] = {"query_ignored",   "train_ignored", "invalid_descriptor",
                                                          "bad_prediction",  "candidates_capped", "output_full"};

class RatioMatcher {
 public:
  RatioMatcher() noexcept : counters_(kRatioMatchCounterNames) {}
  Status init(const RatioMatchConfig& config, Arena& arena) noexcept;
  static std::size_t arena_bytes(const RatioMatchConfig& config) noexcept;

  // Every train descriptor is a candidate of every query. out is cleared first; a full out returns
  // kCapacityExceeded with the matches that fitted.
  Status match(Span<const vision::OrientedDescriptor> query, Span<const vision::OrientedDescriptor> train,
               BoundedVector<DescriptorMatch>& out) noexcept;
  // predicted_px[i]: query i's predicted position in the train image (same length as query).
  Status match_predicted(Span<const vision::OrientedDescriptor> query, Span<const Vec2d> predicted_px,
                         Span<const vision::OrientedDescriptor> train, BoundedVector<DescriptorMatch>& out) noexcept;

  const RatioMatchConfig& config() const noexcept { return config_; }
  const RatioMatchStats& last_stats() const noexcept { return stats_; }
  const CounterSet<RatioMatchCounter>& counters() const noexcept { return counters_; }

 private:
  // Nearest and second nearest of one query; -1 = none.
  struct Best {
    std::int32_t t1 = -1;
    float d1 = 0.0f, d2 = 0.0f;  // squared
    bool has2 = false;
  };
  void consider(std::uint32_t qi, const vision::OrientedDescriptor& q, std::uint32_t ti,
                const vision::OrientedDescriptor& t, Best& best) noexcept;
  Status finish(std::size_t nq, BoundedVector<DescriptorMatch>& out) noexcept;
  void reset_train(std::size_t nt) noexcept;
  void clamp_sizes(std::size_t& nq, std::size_t& nt) noexcept;

  RatioMatchConfig config_{};
  bool ready_ = false;
  Span<std::int32_t> q_t1_;     // per query: nearest train (-1 none)
  Span<float> q_d1_, q_d2_;     // squared distances
  Span<std::uint8_t> q_has2_;
  Span<std::int32_t> t_q1_;     // per train: nearest query (mutual)
  Span<float> t_d1_;
  Span<std::uint32_t> cell_start_;  // grid: cells + 1 offsets into cell_items_
  Span<std::uint16_t> cell_items_;
  RatioMatchStats stats_{};
  CounterSet<RatioMatchCounter> counters_;
};

}  // namespace qnav::match
