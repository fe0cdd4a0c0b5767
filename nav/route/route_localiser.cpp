#include "nav/route/route_localiser.hpp"

#include <cmath>

namespace qnav::route {

namespace {
std::size_t max_selected(const LocaliserConfig& c) noexcept {
  return c.filter.max_registrations() + 1;
}
}  // namespace

std::size_t RouteLocaliser::arena_bytes(const LocaliserConfig& c) noexcept {
  const std::size_t k = max_selected(c);
  const std::size_t exp = c.experiences_per_node == 0 ? 0
                          : NodeWindow::arena_bytes(c.experience_window_slots) + k * (sizeof(std::uint32_t) + sizeof(std::uint8_t)) + 64;
  return RouteFilter::arena_bytes(c.filter) + Registrar::arena_bytes(c.registration) + NodeWindow::arena_bytes(c.window_slots) +
         k * (sizeof(std::uint32_t) + sizeof(NodeMeasurement) + sizeof(RegistrationResult)) + exp + 512;
}

Status RouteLocaliser::init(const LocaliserConfig& c, Arena& arena) noexcept {
  if (c.window_slots < max_selected(c))
    return Status(StatusCode::kInvalidArgument, "localiser: window_slots must hold every node registered in one update");
  // Guidance reads "look-ahead node == estimated node" as the route's end.
  if (!(c.guidance.lookahead_nodes >= 0.5 && c.guidance.lookahead_nodes <= 1000.0))
    return Status(StatusCode::kInvalidArgument, "localiser: guidance lookahead_nodes must be >= 0.5 (rounds to >= 1 node)");
  QNAV_RETURN_IF_ERROR(filter_.init(c.filter, arena));
  QNAV_RETURN_IF_ERROR(registrar_.init(c.registration, arena));
  QNAV_RETURN_IF_ERROR(window_.init(c.window_slots, arena));
  const std::size_t k = max_selected(c);
  selected_ = arena.allocate<std::uint32_t>(k);
  measurements_ = arena.allocate<NodeMeasurement>(k);
  results_ = arena.allocate<RegistrationResult>(k);
  if (selected_.empty() || measurements_.empty() || results_.empty()) return Status(StatusCode::kCapacityExceeded, "localiser: arena too small");
  if (c.experiences_per_node > kMaxExperiencesPerNode) return Status(StatusCode::kInvalidArgument, "localiser: experiences_per_node > 8");
  if (c.experiences_per_node > 0) {
    QNAV_RETURN_IF_ERROR(exp_window_.init(c.experience_window_slots, arena));
    winner_ = arena.allocate<std::uint32_t>(k);
    tried_ = arena.allocate<std::uint8_t>(k);
    if (winner_.empty() || tried_.empty()) return Status(StatusCode::kCapacityExceeded, "localiser: arena too small");
  }
  config_ = c;
  guidance_ = Guidance(c.guidance);
  ready_ = true;
  return Status::ok();
}

double odometry_node_spacing_m(const RouteParams& params, Span<const NodeMeta> meta) noexcept {
  if (meta.size() >= 2) {
    const double s = (meta[meta.size() - 1].along_m - meta[0].along_m) / static_cast<double>(meta.size() - 1);
    if (std::isfinite(s) && s > 1e-3) return s;
  }
  return static_cast<double>(params.node_spacing_m);
}

Status RouteLocaliser::start(const RouteParams& params, Span<const NodeMeta> meta, NodeSource& source) noexcept {
  if (!ready_) return Status(StatusCode::kNotReady, "localiser: not initialised");
  started_ = false;
  if (params.sensor != config_.sensor) {
    counters_.increment(LocaliserCounter::kSensorMismatch);
    return Status(StatusCode::kInvalidArgument, "localiser: route sensor kind differs from the configured sensor");
  }
  if (meta.size() < 2) return Status(StatusCode::kInvalidArgument, "localiser: a route needs at least 2 nodes");
  if (source.node_count() != meta.size()) return Status(StatusCode::kInvalidArgument, "localiser: node source and metadata disagree");
  for (std::size_t i = 0; i < meta.size(); ++i)
    if (meta[i].index != i || !meta[i].pose.is_finite())
      return Status(StatusCode::kInvalidArgument, "localiser: node metadata out of order or not finite");
  spacing_m_ = odometry_node_spacing_m(params, meta);
  QNAV_RETURN_IF_ERROR(filter_.reset(static_cast<std::uint32_t>(meta.size()), spacing_m_));
  QNAV_RETURN_IF_ERROR(window_.bind(source));
  meta_ = meta;
  guidance_.reset();
  started_ = true;
  return Status::ok();
}

Status RouteLocaliser::attach_experiences(const ExperienceIndex* index, NodeSource* records) noexcept {
  if (index == nullptr || records == nullptr) {
    exp_index_ = nullptr;
    return Status::ok();
  }
  if (config_.experiences_per_node == 0 || winner_.empty())
    return Status(StatusCode::kInvalidArgument, "localiser: experiences_per_node is 0 (nothing allocated for experiences)");
  if (index->per_node() > config_.experiences_per_node)
    return Status(StatusCode::kInvalidArgument, "localiser: the experience index holds more per node than experiences_per_node");
  QNAV_RETURN_IF_ERROR(exp_window_.bind(*records));
  exp_index_ = index;
  last_pass_ = 0;
  return Status::ok();
}

std::size_t RouteLocaliser::candidates(std::uint32_t node) const noexcept {
  std::size_t n = 1;
  if (exp_index_ != nullptr)
    for (const ExperienceSlot& e : exp_index_->slots(node)) n += e.record != kNoExperience;
  return n;
}

bool RouteLocaliser::candidate(std::uint32_t node, std::size_t c, std::uint32_t& record) const noexcept {
  record = kNoExperience;
  if (exp_index_ == nullptr) return true;
  const Span<const ExperienceSlot> slots = exp_index_->slots(node);
  // The preferred experience: the slot of the last update's winning pass.
  std::size_t pref = slots.size();
  if (last_pass_ != 0)
    for (std::size_t i = 0; i < slots.size(); ++i)
      if (slots[i].record != kNoExperience && slots[i].pass_id == last_pass_) {
        pref = i;
        break;
      }
  std::size_t at = 0;
  if (pref < slots.size()) {
    if (c == at++) {
      record = slots[pref].record;
      return false;
    }
  }
  if (c == at++) return true;  // the taught keypoints
  for (std::size_t i = 0; i < slots.size(); ++i) {
    if (i == pref || slots[i].record == kNoExperience) continue;
    if (c == at++) {
      record = slots[i].record;
      return false;
    }
  }
  return true;  // beyond the candidates: the taught keypoints (not reached: callers bound c)
}

Status RouteLocaliser::try_candidate(const RouteNode& sensed, std::uint32_t node, std::size_t c, RegistrationResult& r, std::uint32_t& winner,
                                     LocaliserStep& out) noexcept {
  std::uint32_t record = kNoExperience;
  const bool taught = candidate(node, c, record);
  Status ls;
  const RouteNode* ref = taught ? window_.get(node, &ls) : exp_window_.get(record, &ls);
  if (ref == nullptr) {
    counters_.increment(LocaliserCounter::kLoadError);
    ++out.load_errors;
    return Status::ok();
  }
  if (!taught && ref->meta.index != node) {  // an experience record of another node: damage, not similarity
    counters_.increment(LocaliserCounter::kLoadError);
    ++out.load_errors;
    return Status::ok();
  }
  RegistrationResult& t = scratch_;
  t = RegistrationResult{};
  QNAV_RETURN_IF_ERROR(registrar_.register_tile(sensed, *ref, t));
  ++out.registrations;
  if (!taught) ++out.experience_registrations;
  if (c == 0 || (t.ok && (!r.ok || t.inliers > r.inliers))) {  // the first result stands unless a better one follows
    r = t;
    winner = record;
  }
  return Status::ok();
}

Status RouteLocaliser::step(const RouteNode& sensed, double distance_m, LocaliserStep& out) noexcept {
  out = LocaliserStep{};
  last_nm_ = 0;
  if (!started_) return Status(StatusCode::kNotReady, "localiser: start() first");
  if (sensed.keypoints.empty()) counters_.increment(LocaliserCounter::kEmptySensedTile);
  const bool heading_ok = std::isfinite(sensed.meta.pose.heading_rad);
  if (!heading_ok && !sensed.keypoints.empty()) counters_.increment(LocaliserCounter::kBadSensedTile);
  const bool usable = heading_ok && !sensed.keypoints.empty();
  QNAV_RETURN_IF_ERROR(filter_.predict(distance_m));
  const std::size_t k = filter_.select_nodes(Span<std::uint32_t>(selected_.data(), selected_.size() - 1));
  std::size_t nm = 0;
  const bool with_exp = exp_index_ != nullptr;
  for (std::size_t i = 0; i < k; ++i) {
    results_[i] = RegistrationResult{};
    if (with_exp) {
      winner_[i] = kNoExperience;
      tried_[i] = 0;
    }
  }
  // Round 0: every selected node's first candidate (without experiences: its taught keypoints).
  for (std::size_t i = 0; i < k; ++i) {
    if (!usable) {  // still fetched (a damaged record is counted) and counted as before, not registered
      ++out.registrations;
      Status ls;
      if (window_.get(selected_[i], &ls) == nullptr) {
        counters_.increment(LocaliserCounter::kLoadError);
        ++out.load_errors;
      }
      continue;
    }
    std::uint32_t w = kNoExperience;
    QNAV_RETURN_IF_ERROR(try_candidate(sensed, selected_[i], 0, results_[i], w, out));
    if (with_exp) {
      winner_[i] = w;
      tried_[i] = 1;
    }
  }
  // Further rounds on experiences (and the taught keypoints when an experience went first), while
  // the extra budget lasts.
  if (with_exp && usable) {
    const std::uint32_t budget = config_.experience_registrations > 0 ? config_.experience_registrations : config_.filter.max_registrations();
    std::uint32_t spent = 0;
    bool more = true;
    while (more && spent < budget) {
      more = false;
      for (std::size_t i = 0; i < k && spent < budget; ++i) {
        if (results_[i].ok && results_[i].inliers >= config_.enough_inliers) continue;
        if (tried_[i] >= candidates(selected_[i])) continue;
        QNAV_RETURN_IF_ERROR(try_candidate(sensed, selected_[i], tried_[i], results_[i], winner_[i], out));
        ++tried_[i];
        ++spent;
        more = true;
      }
    }
  }
  for (std::size_t i = 0; i < k; ++i) measurements_[nm++] = NodeMeasurement{selected_[i], static_cast<float>(results_[i].inliers)};
  last_nm_ = nm;
  Status us = filter_.update(Span<const NodeMeasurement>(measurements_.data(), nm));
  us.ignore();  // a degenerate belief was reset to uniform and counted by the filter
  out.estimate = filter_.argmax();
  out.probability = filter_.probability(out.estimate);
  out.mass_pm1 = filter_.mass_near_argmax();
  out.entropy = filter_.entropy();
  out.confident = filter_.confident();
  // Registration to the estimate (reuse this step's, else one more registration).
  bool found = false;
  for (std::size_t i = 0; i < k; ++i)
    if (selected_[i] == out.estimate) {
      out.registration = results_[i];
      if (with_exp) out.experience_record = winner_[i];
      found = true;
      break;
    }
  if (!found && usable) {  // one more registration: the estimate's first candidate
    std::uint32_t w = kNoExperience;
    QNAV_RETURN_IF_ERROR(try_candidate(sensed, out.estimate, 0, out.registration, w, out));
    out.experience_record = w;
  }
  // A neighbour (+/- 1 node) registered with more inliers than the estimate: use it, carried into
  // the estimate's frame through the two nodes' route-frame poses (the tile lies between nodes).
  {
    std::size_t best = k;
    std::uint32_t best_inliers = out.registration.ok ? out.registration.inliers : 0;
    for (std::size_t i = 0; i < k; ++i) {
      const std::int64_t d = static_cast<std::int64_t>(selected_[i]) - static_cast<std::int64_t>(out.estimate);
      if (results_[i].ok && (d == 1 || d == -1) && results_[i].inliers > best_inliers) {
        best = i;
        best_inliers = results_[i].inliers;
      }
    }
    if (best < k) {
      const Pose2 est_from_nb = meta_[out.estimate].pose.inverse().compose(meta_[selected_[best]].pose);
      out.registration = results_[best];
      if (with_exp) out.experience_record = winner_[best];
      out.registration.sensed_to_node = est_from_nb.compose(results_[best].sensed_to_node);
      // The translation's covariance turns with it (heading variance and cross terms likewise).
      Mat3d j = Mat3d::Identity();
      j.topLeftCorner<2, 2>() = est_from_nb.rotation();
      out.registration.covariance = j * results_[best].covariance * j.transpose();
      out.via_neighbour = true;
    }
  }
  out.best_inliers = out.registration.inliers;
  if (with_exp) {  // the pass whose view matched best is tried first next update
    out.experience_pass = 0;
    if (out.experience_record != kNoExperience)
      for (std::int64_t d = -1; d <= 1; ++d) {  // the winner is the estimate's or a neighbour's experience
        const std::int64_t n = static_cast<std::int64_t>(out.estimate) + d;
        if (n < 0) continue;
        for (const ExperienceSlot& e : exp_index_->slots(static_cast<std::uint32_t>(n)))
          if (e.record == out.experience_record) out.experience_pass = e.pass_id;
      }
    last_pass_ = out.experience_pass;
  }
  const std::int64_t dir = config_.filter.direction == RouteDirection::kForward ? 1 : -1;
  std::int64_t ahead = static_cast<std::int64_t>(out.estimate) + dir * static_cast<std::int64_t>(std::lround(config_.guidance.lookahead_nodes));
  if (ahead < 0) ahead = 0;
  if (ahead >= static_cast<std::int64_t>(meta_.size())) ahead = static_cast<std::int64_t>(meta_.size()) - 1;
  out.guidance = guidance_.compute(out.confident, config_.filter.direction, meta_[out.estimate], meta_[static_cast<std::size_t>(ahead)],
                                   out.registration, sensed.meta.pose.heading_rad, sensed.meta.pose);
  return Status::ok();
}

}  // namespace qnav::route
