// RouteFilter: the route paper's discrete Bayes filter over node index (eq. 1-4).
//  - Belief starts uniform (eq. 1 with no data); apply_entry_prior() after reset() puts a share of it on
//    the pass's entry end (a pass that starts there: node 0 forwards, the last node in reverse).
//  - predict(): eq. 2 with one of two motion models, in the configured direction (forward: node
//    index increases; reverse: decreases):
//      kPaperEq5:  p(w_k | w_k-1) = exp(-n / sigma_w2) / beta, n = 0..max_advance_nodes transitions
//                  in the configured direction (no backward moves);
//      kOdometry:  the paper's future work: expected advance a = distance_m / node_spacing_m (DVL/INS
//                  distance against the stored spacing), p(n) ~ exp(-(n - a)^2 / 2 s^2),
//                  s = max(odometry_sigma_min_nodes, odometry_sigma_frac * a), n within a +/- 3 s.
//    An advance beyond max_advance_nodes is clamped to it (counted as a bad distance). The entry end is
//    open (a vehicle may join the route there): the virtual nodes before it carry min(entry belief, 1/N),
//    so a uniform belief stays uniform and a peak on the entry node moves on.
//    Mass pushed past the route's exit end is dropped and the belief renormalised; then a uniform floor
//    (kidnap_floor spread over all nodes) keeps every node reachable for a kidnapped vehicle.
//  - update(): eq. 3 with the measurement model of eq. 9 built from inlier counts S_i of the nodes
//    registered this step: L_i = inlier_floor + max(0, S_i - chance_inliers); nodes not registered
//    get L = inlier_floor, so one bad tile (all S small) leaves the belief as predicted instead of
//    zeroing the truth. measurement_probability() gives eq. 9's normalised p(z | w).
//  - select_nodes(): which nodes to register: the belief_registrations most probable nodes, plus
//    every wide_search_period updates wide_search_registrations nodes spread over the whole route
//    on a grid whose phase rotates by the golden ratio relative to the predicted motion (recovers a
//    lost or kidnapped vehicle; a grid fixed to the route could step in step with the vehicle). While searching (lost, not
//    confident, or no similarity near the estimate in the last update) the wide search runs every
//    update with all of max_registrations() but searching_belief_registrations belief nodes.
//  - lost: when for lost_after_updates confident updates no node within +/- 1 of the estimate shows similarity
//    (S > chance_inliers) but a node elsewhere does (S > chance_inliers and S >=
//    lost_evidence_inliers), lost_reset_mass of the belief is spread over
//    the route and, until a node near the estimate shows similarity again, select_nodes() is in the
//    searching mode above (searching_belief_registrations belief nodes, the rest of max_registrations()
//    on the wide search). Updates with no similarity anywhere are not evidence of being lost (the
//    belief runs on the motion model), but they make the wide search run every update.
//  - entropy (natural log, as the paper's Table I), argmax, mass within +/- 1 node of the argmax,
//    confidence flag (that mass >= confident_mass).
// Memory: 2 * max_nodes floats + max_nodes bytes from the Arena. Cost: predict O(N * taps), taps <=
// 2 * max_advance_nodes + 1; update O(N + m); select O(N * belief_registrations). No heap.
#pragma once

#include <cstddef>
#include <cstdint>

#include "nav/core/arena.hpp"
#include "nav/core/counters.hpp"
#include "nav/core/fixed_vector.hpp"
#include "nav/core/span.hpp"
#include "nav/core/status.hpp"

namespace qnav::route {

enum class RouteDirection : std::uint8_t { kForward, kReverse };
enum class MotionModel : std::uint8_t { kPaperEq5, kOdometry };
// Measurements of one update that the filter keeps for measurement_probability(); init() refuses a
// configuration whose max_registrations() exceeds it.
inline constexpr std::uint32_t kMaxMeasurementsKept = 64;

struct RouteFilterConfig {
  std::size_t max_nodes = 100000;
  RouteDirection direction = RouteDirection::kForward;
  MotionModel motion = MotionModel::kOdometry;
  double sigma_w2 = 1.0;               // eq. 5 variance (node transitions)
  int max_advance_nodes = 8;           // kernel support bound (taps <= 2 * this + 1)
  double odometry_sigma_frac = 0.25;
  double odometry_sigma_min_nodes = 0.35;
  double kidnap_floor = 1e-3;          // total mass spread uniformly after each prediction
  float inlier_floor = 1.0f;
  float chance_inliers = 3.0f;         // inlier count expected by chance on a wrong node
  std::uint32_t belief_registrations = 5;
  std::uint32_t wide_search_registrations = 8;
  std::uint32_t wide_search_period = 4;
  std::uint32_t searching_belief_registrations = 2;  // belief nodes while searching (rest -> wide search)
  std::uint32_t searching_registrations = 0;         // all registrations while searching; 0 = belief + wide
  // Most nodes select_nodes() returns in one update.
  std::uint32_t max_registrations() const noexcept {
    const std::uint32_t normal = belief_registrations + wide_search_registrations;
    return searching_registrations > normal ? searching_registrations : normal;
  }
  double confident_mass = 0.6;
  std::uint32_t lost_after_updates = 3;  // 0 = never declare lost
  double lost_reset_mass = 0.5;          // mass spread uniformly when lost
  float lost_evidence_inliers = 0.0f;    // similarity elsewhere that counts towards lost (and > chance)
};

struct NodeMeasurement {
  std::uint32_t node = 0;
  float inliers = 0.0f;  // the paper's similarity S (0 when registration failed)
};

enum class FilterCounter : std::uint8_t { kBadDistance, kBadMeasurement, kDegenerateBelief, kLostResets, kCount };
inline constexpr const char* kFilterCounterNames[] = {"bad_distance", "bad_measurement", "degenerate_belief", "lost_resets"};

class RouteFilter {
 public:
  RouteFilter() noexcept : counters_(kFilterCounterNames) {}
  static std::size_t arena_bytes(const RouteFilterConfig& c) noexcept { return c.max_nodes * (2 * sizeof(float) + 1) + 64; }
  Status init(const RouteFilterConfig& config, Arena& arena) noexcept;
  // Starts on a route of node_count nodes (1 < node_count <= max_nodes) with uniform belief.
  Status reset(std::uint32_t node_count, double node_spacing_m) noexcept;

  // Right after reset(): mass (0 <= mass < 1) of the belief on a half-Gaussian of sigma_nodes (> 0) from
  // the entry node of the configured direction (cut at 4 sigma), the rest uniform. A prior, not a fix:
  // with 0.5 and 1 node the belief within +/-1 of the entry is 0.49, under the confident mass 0.6. O(N).
  Status apply_entry_prior(double mass, double sigma_nodes) noexcept;
  // distance_m: distance travelled since the last update (used by kOdometry; must be finite, >= 0).
  Status predict(double distance_m) noexcept;
  Status update(Span<const NodeMeasurement> m) noexcept;
  // Writes the nodes to register this step into out (no duplicates); returns how many.
  std::size_t select_nodes(Span<std::uint32_t> out) noexcept;

  std::uint32_t node_count() const noexcept { return n_; }
  Span<const float> belief() const noexcept { return Span<const float>(bel_.data(), n_); }
  // Eq. 9 of the last update: p(z | w) normalised (written into out, size >= node_count()).
  Status measurement_probability(Span<float> out) const noexcept;
  std::uint32_t argmax() const noexcept { return argmax_; }
  float probability(std::uint32_t node) const noexcept { return node < n_ ? bel_[node] : 0.0f; }
  double mass_near_argmax() const noexcept { return mass_pm1_; }
  // Shannon entropy of the belief, nats, O(N) (computed on demand).
  double entropy() const noexcept;
  bool confident() const noexcept { return mass_pm1_ >= config_.confident_mass; }
  bool lost() const noexcept { return lost_; }
  const RouteFilterConfig& config() const noexcept { return config_; }
  // Direction and motion model can change between updates (a repeat pass in reverse; the paper's
  // eq. 5 model while the odometry source is lost). O(1); sizes are unchanged.
  void set_motion(RouteDirection direction, MotionModel motion) noexcept {
    config_.direction = direction;
    config_.motion = motion;
  }
  const CounterSet<FilterCounter>& counters() const noexcept { return counters_; }
  std::uint32_t updates() const noexcept { return updates_; }

 private:
  void summarise() noexcept;
  void summarise_at(std::uint32_t best) noexcept;
  Status normalise(Span<float> v) noexcept;
  RouteFilterConfig config_{};
  bool ready_ = false;
  std::uint32_t n_ = 0;
  double spacing_m_ = 1.0;
  Span<float> bel_;
  Span<float> tmp_;
  Span<std::uint8_t> mark_;
  FixedVector<NodeMeasurement, kMaxMeasurementsKept> last_m_;  // last update's measurements
  std::uint32_t updates_ = 0;
  std::uint32_t wide_phase_ = 0;
  double wide_shift_nodes_ = 0.0;  // predicted advance so far (mod N): the wide-search grid moves with it
  std::uint32_t selects_ = 0;
  std::uint32_t misses_ = 0;       // updates with similarity elsewhere but none near the estimate
  std::uint32_t unsupported_ = 0;  // updates without similarity near the estimate
  bool lost_ = false;
  std::uint32_t argmax_ = 0;
  double mass_pm1_ = 0.0;
  CounterSet<FilterCounter> counters_;
};

}  // namespace qnav::route
