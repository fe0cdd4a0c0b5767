// RouteLocaliser: one repeat-mode update per sensed tile, in fixed memory and bounded time:
//   predict (motion model, distance travelled) -> select the nodes carrying belief (+ the periodic
//   wide search) -> fetch them through the NodeWindow -> register the sensed tile against each ->
//   update (eq. 9 from the inlier counts) -> guidance from the strongest registration among the argmax
//   node and its +/- 1 neighbours (a neighbour's carried into the argmax's frame through the node poses).
// Owns the filter, registrar, window and guidance; the NodeSource (route file / memory) and the route
// metadata index (per-node pose and along-track distance, for guidance) are the caller's.
// Experiences (issue 29, nav/route/experience.hpp; optional, attach_experiences()): each selected node
// is registered against its taught keypoints and its experiences, the measurement is the best match
// per node. Try-order: first the experience of the pass that gave the estimate its best match in the
// last update (the same view usually matches the next node too), else the taught keypoints; then the
// rest (taught, then the slots in order), in rounds over the selected nodes (belief nodes first) while
// the extra budget lasts, skipping nodes that already matched with >= enough_inliers.
// Bounds: registrations per update <= filter.max_registrations() (+1 when the argmax was not
// registered) + experience_registrations; memory: sum of the parts' arena_bytes() (+ the experience
// window, experience_window_slots x ~10 KB, when experiences_per_node > 0). No heap after init().
#pragma once

#include <cstddef>
#include <cstdint>

#include "nav/core/arena.hpp"
#include "nav/core/span.hpp"
#include "nav/core/status.hpp"
#include "nav/route/experience.hpp"
#include "nav/route/guidance.hpp"
#include "nav/route/node_window.hpp"
#include "nav/route/registration.hpp"
#include "nav/route/route_filter.hpp"
#include "nav/route/route_types.hpp"

namespace qnav::route {

struct LocaliserConfig {
  RouteFilterConfig filter;
  RegistrationConfig registration;
  GuidanceConfig guidance;
  std::size_t window_slots = 32;
  SensorKind sensor = SensorKind::kSideScan;  // must match the route's
  // Experiences: 0 = none (nothing allocated for them). Else up to this many per node are tried.
  std::size_t experiences_per_node = 0;
  std::size_t experience_window_slots = 32;    // decoded experiences cached (LRU)
  std::uint32_t experience_registrations = 0;  // extra registrations per update on experiences
  std::uint32_t enough_inliers = 12;           // a node matched this well is not tried further
};

struct LocaliserStep {
  std::uint32_t estimate = 0;       // argmax node
  float probability = 0.0f;         // belief at the estimate
  double mass_pm1 = 0.0;
  double entropy = 0.0;
  bool confident = false;
  std::uint32_t registrations = 0;
  std::uint32_t best_inliers = 0;   // of the registration used (the estimate's, or a neighbour's: via_neighbour)
  RegistrationResult registration;  // to the estimate
  bool via_neighbour = false;       // registration came from node estimate +/- 1 (composed through the node poses)
  GuidanceOutput guidance;
  std::uint32_t load_errors = 0;    // damaged records met this step (treated as no similarity)
  // Experiences: the record whose match is `registration` (kNoExperience: the taught keypoints),
  // and the registrations spent on experiences this step.
  std::uint32_t experience_record = kNoExperience;
  std::uint32_t experience_pass = 0;
  std::uint32_t experience_registrations = 0;
};

// kBadSensedTile: a sensed tile whose heading is not finite: not registered (the filter still predicts
// on the distance; guidance holds course).
enum class LocaliserCounter : std::uint8_t { kSensorMismatch, kEmptySensedTile, kLoadError, kBadSensedTile, kCount };
inline constexpr const char* kLocaliserCounterNames[] = {"sensor_mismatch", "empty_sensed_tile", "load_error", "bad_sensed_tile"};

// The spacing that turns a repeat's odometry (dead-reckoned metres) into nodes: the taught nodes' own
// dead-reckoned spacing, (along_m of the last node - the first) / (nodes - 1), in the same units as the
// odometry and with the same DVL scale; the header's nominal spacing when the nodes give none (fewer
// than 2, or along_m not increasing). The header's value is what the teacher expected (on qnavd's linux
// backend a fixed 60 m: it cannot know the vehicle's speed when the file is opened), not what was flown.
double odometry_node_spacing_m(const RouteParams& params, Span<const NodeMeta> meta) noexcept;

class RouteLocaliser {
 public:
  RouteLocaliser() noexcept : counters_(kLocaliserCounterNames) {}
  static std::size_t arena_bytes(const LocaliserConfig& c) noexcept;
  Status init(const LocaliserConfig& config, Arena& arena) noexcept;
  // Starts on a route: params from its header, meta = every node's metadata (index order),
  // source = where node records are loaded from. Rejects a sensor-kind mismatch and routes of < 2 nodes.
  Status start(const RouteParams& params, Span<const NodeMeta> meta, NodeSource& source) noexcept;
  // One update. sensed: keypoints of the new tile (meta.pose.heading_rad = compass heading);
  // distance_m: distance travelled since the previous tile (DVL/INS).
  Status step(const RouteNode& sensed, double distance_m, LocaliserStep& out) noexcept;
  // Registers against experiences too from now on: index = which records each node has, records =
  // where an experience record is loaded from (its NodeSource index is the record number). Both are
  // the caller's and outlive the repeat; nullptr detaches. Needs experiences_per_node > 0 at init
  // and index->per_node() <= it. O(1).
  Status attach_experiences(const ExperienceIndex* index, NodeSource* records) noexcept;

  // See RouteFilter::apply_entry_prior: right after start(), the pass starts at its entry end. O(N).
  Status apply_entry_prior(double mass, double sigma_nodes) noexcept {
    if (!started_) return Status(StatusCode::kNotReady, "localiser: start() first");
    return filter_.apply_entry_prior(mass, sigma_nodes);
  }
  // See RouteFilter::set_motion (guidance follows the direction too). O(1), no heap.
  void set_motion(RouteDirection direction, MotionModel motion) noexcept {
    config_.filter.direction = direction;
    config_.filter.motion = motion;
    filter_.set_motion(direction, motion);
  }
  // The node spacing the motion model divides odometry by (odometry_node_spacing_m), set by start().
  double node_spacing_m() const noexcept { return spacing_m_; }
  const RouteFilter& filter() const noexcept { return filter_; }
  const NodeWindow& window() const noexcept { return window_; }
  const Registrar& registrar() const noexcept { return registrar_; }
  const CounterSet<LocaliserCounter>& counters() const noexcept { return counters_; }
  // The (node, similarity) pairs the last step() registered, for diagnostics and logs.
  Span<const NodeMeasurement> last_measurements() const noexcept { return Span<const NodeMeasurement>(measurements_.data(), last_nm_); }

 private:
  LocaliserConfig config_{};
  bool ready_ = false;
  bool started_ = false;
  RouteFilter filter_;
  double spacing_m_ = 0.0;
  Registrar registrar_;
  NodeWindow window_;
  Guidance guidance_;
  Span<const NodeMeta> meta_;
  Span<std::uint32_t> selected_;
  Span<NodeMeasurement> measurements_;
  std::size_t last_nm_ = 0;
  Span<RegistrationResult> results_;
  // Experiences (attach_experiences).
  const ExperienceIndex* exp_index_ = nullptr;
  NodeWindow exp_window_;
  Span<std::uint32_t> winner_;   // per selected node: the record of its best match (kNoExperience: taught)
  Span<std::uint8_t> tried_;     // per selected node: candidates tried
  std::uint32_t last_pass_ = 0;  // pass id of the estimate's best match in the last update (0: taught)
  RegistrationResult scratch_;
  // The c-th candidate of `node` in try-order: the taught keypoints (true) or an experience record.
  bool candidate(std::uint32_t node, std::size_t c, std::uint32_t& record) const noexcept;
  std::size_t candidates(std::uint32_t node) const noexcept;
  // Registers sensed against candidate c of node; r = the better of r and this one (winner updated).
  Status try_candidate(const RouteNode& sensed, std::uint32_t node, std::size_t c, RegistrationResult& r, std::uint32_t& winner,
                       LocaliserStep& out) noexcept;
  CounterSet<LocaliserCounter> counters_;
};

}  // namespace qnav::route
