// ExperienceLearner: decides which repeat tiles become experiences of their node (issue 29), so that
// nothing wrong is learnt. After each RouteLocaliser::step() the caller passes the sensed tile, the
// distance travelled and the step; a tile is a candidate only when
//   - the filter is confident,
//   - the registration used for guidance is strong (>= min_inliers; 8: no registration with 8 or more
//     inliers was wrong in the route evaluation, docs/route.md) and not already a near-copy of what the
//     route knows (< redundant_inliers: a view the route has needs no second copy),
//   - the estimate agrees with the odometry's expected node: the previous confident estimate moved
//     on by the distance travelled (in nodes of the route's spacing, in the pass's direction), within
//     max_node_disagreement + 0.5 nodes (the half node: the estimate is a whole node, the odometry not),
//     and the tile's heading is the pass's direction on that node (within 90 deg of the node's heading
//     forwards, of its opposite in reverse): a pass told the wrong direction, whose belief sweeps the
//     route against the vehicle, agrees with a registration where the two cross (counted as
//     disagrees_with_odometry);
// and it is learnt only when the NEXT step confirms it (confident, agreeing with odometry again). A
// pass on another route (no strong registration), one never confident, or one whose estimate jumps
// against its odometry (a forced mislocalisation) therefore learns nothing. finish() (end of the
// pass) drops a candidate not yet confirmed.
// The candidate's keypoints are carried into the estimated node's tile frame by the step's
// registration (sensed_to_node), so an experience registers like the taught node does.
// Memory: one pending Experience (about 10 KB) from an Arena; observe() is O(keypoints). No heap.
#pragma once

#include <cmath>
#include <cstdint>

#include "nav/core/arena.hpp"
#include "nav/core/counters.hpp"
#include "nav/core/span.hpp"
#include "nav/core/status.hpp"
#include "nav/route/experience.hpp"
#include "nav/route/route_localiser.hpp"

namespace qnav::route {

struct ExperienceLearnConfig {
  std::uint32_t min_inliers = 8;
  std::uint32_t redundant_inliers = 30;
  double max_node_disagreement = 1.0;
};

enum class LearnCounter : std::uint8_t {
  kLearned, kNotConfident, kWeakRegistration, kRedundant, kDisagreesWithOdometry, kUnconfirmed, kNoSlot, kCount
};
inline constexpr const char* kLearnCounterNames[] = {"learned", "not_confident", "weak_registration", "redundant",
                                                     "disagrees_with_odometry", "unconfirmed", "no_slot"};

class ExperienceLearner {
 public:
  ExperienceLearner() noexcept : counters_(kLearnCounterNames) {}
  static std::size_t arena_bytes() noexcept { return sizeof(Experience) + 64; }
  Status init(const ExperienceLearnConfig& c, Arena& arena) noexcept {
    Span<Experience> p = arena.allocate<Experience>(1);
    if (p.empty()) return Status(StatusCode::kCapacityExceeded, "experience learner: arena too small");
    pending_ = p.data();
    config_ = c;
    return Status::ok();
  }
  // A new pass: meta = the route's nodes, spacing_m = the odometry spacing (RouteLocaliser::node_spacing_m),
  // pass_id (>= 1) names the pass in the experiences it learns.
  Status start(Span<const NodeMeta> meta, double spacing_m, bool reverse, std::uint32_t pass_id) noexcept {
    if (pending_ == nullptr) return Status(StatusCode::kNotReady, "experience learner: not initialised");
    if (!(spacing_m > 0.0) || pass_id == 0) return Status(StatusCode::kInvalidArgument, "experience learner: spacing must be > 0, pass id >= 1");
    meta_ = meta;
    spacing_m_ = spacing_m;
    reverse_ = reverse;
    pass_id_ = pass_id;
    has_anchor_ = false;
    has_pending_ = false;
    return Status::ok();
  }
  // After each step. Returns true when `out` holds an experience to append (the previous step's tile,
  // confirmed by this one; its slot chosen in `index` by the replacement rule).
  bool observe(const RouteNode& sensed, double distance_m, const LocaliserStep& step, const ExperienceIndex& index, Experience& out) noexcept {
    bool emitted = false;
    const bool agrees = step.confident && agrees_with_odometry(step.estimate, distance_m) && heading_agrees(sensed, step.estimate);
    if (has_pending_) {
      if (agrees) {
        const std::uint16_t slot = index.choose_slot(pending_->meta.node, pending_keep_);
        if (slot < index.per_node()) {
          pending_->meta.slot = slot;
          out = *pending_;
          emitted = true;
          counters_.increment(LearnCounter::kLearned);
        } else {
          counters_.increment(LearnCounter::kNoSlot);
        }
      } else {
        counters_.increment(LearnCounter::kUnconfirmed);
      }
      has_pending_ = false;
    }
    // The anchor: the last confident estimate (the odometry's expected node is measured from it).
    const bool had_anchor = has_anchor_;
    if (step.confident) {
      anchor_node_ = step.estimate;
      has_anchor_ = true;
      since_anchor_m_ = 0.0;
    } else if (has_anchor_ && std::isfinite(distance_m)) {
      since_anchor_m_ += distance_m;
    }
    if (!step.confident) {
      counters_.increment(LearnCounter::kNotConfident);
      return emitted;
    }
    if (!had_anchor || !agrees) {
      counters_.increment(LearnCounter::kDisagreesWithOdometry);
      return emitted;
    }
    const RegistrationResult& r = step.registration;
    if (!r.ok || r.inliers < config_.min_inliers || step.estimate >= meta_.size()) {
      counters_.increment(LearnCounter::kWeakRegistration);
      return emitted;
    }
    if (r.inliers >= config_.redundant_inliers) {
      counters_.increment(LearnCounter::kRedundant);
      return emitted;
    }
    Experience& e = *pending_;
    e.meta = ExperienceMeta{};
    e.meta.node = step.estimate;
    e.meta.reverse = reverse_;
    e.meta.offset_m = static_cast<float>(r.sensed_to_node.y_m);
    e.meta.pass_id = pass_id_;
    e.meta.stamp_ns = sensed.meta.stamp_ns;
    e.meta.inliers = static_cast<std::uint16_t>(r.inliers > 65535u ? 65535u : r.inliers);
    e.meta.node_heading_rad = static_cast<float>(meta_[step.estimate].pose.heading_rad);
    e.node.meta = NodeMeta{};
    e.node.meta.index = step.estimate;
    e.node.meta.pose.heading_rad = static_cast<double>(e.meta.node_heading_rad);
    e.node.meta.stamp_ns = sensed.meta.stamp_ns;
    e.node.keypoints.clear();
    for (const RouteKeypoint& k : sensed.keypoints) {
      RouteKeypoint* c = e.node.keypoints.emplace_back();
      if (c == nullptr) break;
      *c = k;
      const Vec2d p = r.sensed_to_node.apply(Vec2d(k.x_m, k.y_m));
      c->x_m = static_cast<float>(p.x());
      c->y_m = static_cast<float>(p.y());
    }
    e.meta.keypoint_count = static_cast<std::uint16_t>(e.node.keypoints.size());
    pending_keep_ = step.experience_record;
    has_pending_ = true;
    return emitted;
  }
  // End of the pass: a candidate not yet confirmed is dropped.
  void finish() noexcept {
    if (has_pending_) counters_.increment(LearnCounter::kUnconfirmed);
    has_pending_ = false;
    has_anchor_ = false;
  }
  const CounterSet<LearnCounter>& counters() const noexcept { return counters_; }
  const ExperienceLearnConfig& config() const noexcept { return config_; }

 private:
  bool heading_agrees(const RouteNode& sensed, std::uint32_t estimate) const noexcept {
    if (estimate >= meta_.size() || !std::isfinite(sensed.meta.pose.heading_rad)) return false;
    const double along = std::cos(sensed.meta.pose.heading_rad - meta_[estimate].pose.heading_rad);  // > 0: the node's direction
    return reverse_ ? along < 0.0 : along > 0.0;
  }
  bool agrees_with_odometry(std::uint32_t estimate, double distance_m) const noexcept {
    if (!has_anchor_ || !std::isfinite(distance_m)) return false;
    const double moved = (since_anchor_m_ + distance_m) / spacing_m_;
    const double expected = static_cast<double>(anchor_node_) + (reverse_ ? -moved : moved);
    return std::fabs(static_cast<double>(estimate) - expected) <= config_.max_node_disagreement + 0.5;
  }
  ExperienceLearnConfig config_{};
  Experience* pending_ = nullptr;
  bool has_pending_ = false;
  std::uint32_t pending_keep_ = kNoExperience;
  Span<const NodeMeta> meta_;
  double spacing_m_ = 0.0;
  bool reverse_ = false;
  std::uint32_t pass_id_ = 0;
  bool has_anchor_ = false;
  std::uint32_t anchor_node_ = 0;
  double since_anchor_m_ = 0.0;
  CounterSet<LearnCounter> counters_;
};

}  // namespace qnav::route
