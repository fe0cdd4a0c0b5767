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
  return RouteFilter::arena_bytes(c.filter) + Registrar::arena_bytes(c.registration) + NodeWindow::arena_bytes(c.window_slots) +
         k * (sizeof(std::uint32_t) + sizeof(NodeMeasurement) + sizeof(RegistrationResult)) + 512;
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
  for (std::size_t i = 0; i < k; ++i) {
    const std::uint32_t node = selected_[i];
    RegistrationResult& r = results_[i];
    r = RegistrationResult{};
    Status ls;
    const RouteNode* ref = window_.get(node, &ls);
    if (ref == nullptr) {
      counters_.increment(LocaliserCounter::kLoadError);
      ++out.load_errors;
    } else if (usable) {
      QNAV_RETURN_IF_ERROR(registrar_.register_tile(sensed, *ref, r));
    }
    measurements_[nm++] = NodeMeasurement{node, static_cast<float>(r.inliers)};
  }
  out.registrations = static_cast<std::uint32_t>(k);
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
      found = true;
      break;
    }
  if (!found && usable) {
    const RouteNode* ref = window_.get(out.estimate);
    if (ref != nullptr) {
      QNAV_RETURN_IF_ERROR(registrar_.register_tile(sensed, *ref, out.registration));
      ++out.registrations;
    }
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
      out.registration.sensed_to_node = est_from_nb.compose(results_[best].sensed_to_node);
      // The translation's covariance turns with it (heading variance and cross terms likewise).
      Mat3d j = Mat3d::Identity();
      j.topLeftCorner<2, 2>() = est_from_nb.rotation();
      out.registration.covariance = j * results_[best].covariance * j.transpose();
      out.via_neighbour = true;
    }
  }
  out.best_inliers = out.registration.inliers;
  const std::int64_t dir = config_.filter.direction == RouteDirection::kForward ? 1 : -1;
  std::int64_t ahead = static_cast<std::int64_t>(out.estimate) + dir * static_cast<std::int64_t>(std::lround(config_.guidance.lookahead_nodes));
  if (ahead < 0) ahead = 0;
  if (ahead >= static_cast<std::int64_t>(meta_.size())) ahead = static_cast<std::int64_t>(meta_.size()) - 1;
  out.guidance = guidance_.compute(out.confident, config_.filter.direction, meta_[out.estimate], meta_[static_cast<std::size_t>(ahead)],
                                   out.registration, sensed.meta.pose.heading_rad, sensed.meta.pose);
  return Status::ok();
}

}  // namespace qnav::route
