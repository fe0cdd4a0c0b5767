#include "nav/route/route_filter.hpp"

#include <algorithm>
#include <cmath>

namespace qnav::route {

Status RouteFilter::init(const RouteFilterConfig& c, Arena& arena) noexcept {
  if (c.max_nodes < 2 || c.max_advance_nodes < 1 || c.max_advance_nodes > 64 || !(c.sigma_w2 > 0.0) ||
      !(c.odometry_sigma_frac >= 0.0) || !(c.odometry_sigma_min_nodes > 0.0) || !(c.kidnap_floor >= 0.0 && c.kidnap_floor < 1.0) ||
      !(c.inlier_floor > 0.0f) || !(c.chance_inliers >= 0.0f) || c.belief_registrations == 0 || c.searching_belief_registrations == 0 ||
      c.wide_search_period == 0 || !(c.confident_mass > 0.0 && c.confident_mass <= 1.0) || !(c.lost_reset_mass >= 0.0 && c.lost_reset_mass <= 1.0) ||
      !std::isfinite(c.lost_evidence_inliers) || c.max_registrations() > kMaxMeasurementsKept)
    return Status(StatusCode::kInvalidArgument, "route filter: bad configuration");
  bel_ = arena.allocate<float>(c.max_nodes);
  tmp_ = arena.allocate<float>(c.max_nodes);
  mark_ = arena.allocate<std::uint8_t>(c.max_nodes);
  if (bel_.empty() || tmp_.empty() || mark_.empty()) return Status(StatusCode::kCapacityExceeded, "route filter: arena too small");
  config_ = c;
  ready_ = true;
  return Status::ok();
}

Status RouteFilter::reset(std::uint32_t node_count, double node_spacing_m) noexcept {
  if (!ready_) return Status(StatusCode::kNotReady, "route filter not initialised");
  if (node_count < 2) return Status(StatusCode::kInvalidArgument, "route filter: a route needs at least 2 nodes");
  if (node_count > config_.max_nodes) return Status(StatusCode::kCapacityExceeded, "route filter: route longer than max_nodes");
  if (!(node_spacing_m > 0.0) || !std::isfinite(node_spacing_m)) return Status(StatusCode::kInvalidArgument, "route filter: bad node spacing");
  n_ = node_count;
  spacing_m_ = node_spacing_m;
  const float u = 1.0f / static_cast<float>(n_);
  for (std::uint32_t i = 0; i < n_; ++i) bel_[i] = u;
  updates_ = 0;
  selects_ = 0;
  misses_ = 0;
  unsupported_ = 0;
  lost_ = false;
  wide_phase_ = 0;
  wide_shift_nodes_ = 0.0;
  last_m_.clear();
  summarise();
  return Status::ok();
}

Status RouteFilter::apply_entry_prior(double mass, double sigma_nodes) noexcept {
  if (!ready_ || n_ < 2) return Status(StatusCode::kNotReady, "route filter: reset() before apply_entry_prior()");
  if (!(mass >= 0.0 && mass < 1.0) || !(sigma_nodes > 0.0 && sigma_nodes <= 1e6))
    return Status(StatusCode::kInvalidArgument, "route filter: entry prior mass must be in [0, 1), sigma > 0");
  if (mass == 0.0) return Status::ok();
  const bool fwd = config_.direction == RouteDirection::kForward;
  const std::uint32_t reach = static_cast<std::uint32_t>(std::min(static_cast<double>(n_ - 1), std::ceil(4.0 * sigma_nodes)));
  double g_sum = 0.0;
  for (std::uint32_t d = 0; d <= reach; ++d) g_sum += std::exp(-0.5 * (d / sigma_nodes) * (d / sigma_nodes));
  for (std::uint32_t i = 0; i < n_; ++i) bel_[i] = static_cast<float>((1.0 - mass) / n_);
  for (std::uint32_t d = 0; d <= reach; ++d)
    bel_[fwd ? d : n_ - 1 - d] += static_cast<float>(mass * std::exp(-0.5 * (d / sigma_nodes) * (d / sigma_nodes)) / g_sum);
  summarise();
  return Status::ok();
}

Status RouteFilter::normalise(Span<float> v) noexcept {
  double sum = 0.0;
  for (std::uint32_t i = 0; i < n_; ++i) sum += static_cast<double>(v[i]);
  if (!(sum > 1e-30) || !std::isfinite(sum)) {
    counters_.increment(FilterCounter::kDegenerateBelief);
    const float u = 1.0f / static_cast<float>(n_);
    for (std::uint32_t i = 0; i < n_; ++i) v[i] = u;
    return Status(StatusCode::kDegenerate, "route filter: belief vanished, reset to uniform");
  }
  const float inv = static_cast<float>(1.0 / sum);
  for (std::uint32_t i = 0; i < n_; ++i) v[i] *= inv;
  return Status::ok();
}

Status RouteFilter::predict(double distance_m) noexcept {
  if (n_ == 0) return Status(StatusCode::kNotReady, "route filter: reset() first");
  if (!std::isfinite(distance_m) || distance_m < 0.0) {
    counters_.increment(FilterCounter::kBadDistance);
    return Status(StatusCode::kInvalidArgument, "route filter: distance must be finite and >= 0");
  }
  // Kernel over signed advances n in [lo, hi] (in the configured direction).
  constexpr int kMaxTaps = 129;
  float w[kMaxTaps];
  int lo = 0, hi = config_.max_advance_nodes;
  if (config_.motion == MotionModel::kPaperEq5) {
    for (int k = lo; k <= hi; ++k) w[k - lo] = static_cast<float>(std::exp(-static_cast<double>(k) / config_.sigma_w2));
  } else {
    const int m = config_.max_advance_nodes;
    const double a_raw = distance_m / spacing_m_;
    if (!std::isfinite(a_raw)) {
      counters_.increment(FilterCounter::kBadDistance);
      return Status(StatusCode::kInvalidArgument, "route filter: distance / node spacing not finite");
    }
    // A longer jump than the kernel bound is clamped to it (counted): the kernel, its width and its
    // taps all come from the clamped advance, so lo and hi stay inside [-m, m].
    if (a_raw > m) counters_.increment(FilterCounter::kBadDistance);
    const double a = a_raw > m ? m : a_raw;
    double s = config_.odometry_sigma_frac * a;
    if (s < config_.odometry_sigma_min_nodes) s = config_.odometry_sigma_min_nodes;
    double flo = std::floor(a - 3.0 * s), fhi = std::ceil(a + 3.0 * s);
    if (flo < -m) flo = -m;
    if (fhi > m) fhi = m;
    lo = static_cast<int>(flo);
    hi = static_cast<int>(fhi);
    for (int k = lo; k <= hi; ++k) {
      const double d = (k - a) / s;
      w[k - lo] = static_cast<float>(std::exp(-0.5 * d * d));
    }
  }
  const int dir = config_.direction == RouteDirection::kForward ? 1 : -1;
  {
    double mean = 0.0, wsum = 0.0;
    for (int k = lo; k <= hi; ++k) {
      mean += static_cast<double>(w[k - lo]) * k;
      wsum += static_cast<double>(w[k - lo]);
    }
    if (wsum > 0.0) wide_shift_nodes_ += dir * mean / wsum;
    wide_shift_nodes_ -= std::floor(wide_shift_nodes_ / static_cast<double>(n_)) * static_cast<double>(n_);
  }
  const std::int64_t n = n_;
  // tmp[j] = sum_k w[k] bel[j - dir k]; the interior runs without bounds checks.
  const std::int64_t klo = lo, khi = hi;
  // j - dir*k in [0, n) for every k in [klo, khi]  <=>  j in [jlo, jhi)
  const std::int64_t jlo = dir > 0 ? (khi > 0 ? khi : 0) : (-klo > 0 ? -klo : 0);
  const std::int64_t jhi = dir > 0 ? n + (klo < 0 ? klo : 0) : n - (khi > 0 ? khi : 0);
  // Before the entry end (node 0 forwards, node n-1 in reverse) the route is open: a vehicle may
  // join it there. The virtual nodes before the entry carry min(entry belief, 1/n): a uniform belief
  // stays uniform, and a belief peaked on the entry node still moves on (copying the entry's own
  // belief there would keep feeding it). Mass pushed past the exit end leaves the route and is dropped.
  const std::size_t entry_node = dir > 0 ? 0 : static_cast<std::size_t>(n - 1);
  const float join = std::min(bel_[entry_node], 1.0f / static_cast<float>(n));
  auto edge = [&](std::int64_t j) {
    float acc = 0.0f;
    for (std::int64_t k = klo; k <= khi; ++k) {
      const std::int64_t src = j - dir * k;
      if (src >= 0 && src < n)
        acc += w[k - klo] * bel_[static_cast<std::size_t>(src)];
      else if ((dir > 0 && src < 0) || (dir < 0 && src >= n))
        acc += w[k - klo] * join;
    }
    tmp_[static_cast<std::size_t>(j)] = acc;
  };
  const std::int64_t a0 = jlo < n ? jlo : n, a1 = jhi > a0 ? jhi : a0;
  for (std::int64_t j = 0; j < a0; ++j) edge(j);
  const float* b = bel_.data();
  float* t = tmp_.data();
  const int taps = static_cast<int>(khi - klo + 1);
  for (std::int64_t j = a0; j < a1; ++j) {
    const float* src = b + (j - dir * klo);  // k = klo
    float acc = 0.0f;
    for (int k = 0; k < taps; ++k) acc += w[k] * src[-dir * k];
    t[j] = acc;
  }
  for (std::int64_t j = a1; j < n; ++j) edge(j);
  double sum = 0.0;
  for (std::uint32_t i = 0; i < n_; ++i) sum += static_cast<double>(tmp_[i]);
  Status s;
  if (!(sum > 1e-30) || !std::isfinite(sum)) {
    counters_.increment(FilterCounter::kDegenerateBelief);
    for (std::uint32_t i = 0; i < n_; ++i) tmp_[i] = 1.0f;
    sum = n_;
    s = Status(StatusCode::kDegenerate, "route filter: belief vanished, reset to uniform");
  }
  const float floor_each = static_cast<float>(config_.kidnap_floor / static_cast<double>(n_));
  const float keep = static_cast<float>((1.0 - config_.kidnap_floor) / sum);
  std::uint32_t best = 0;
  for (std::uint32_t i = 0; i < n_; ++i) {
    const float v = keep * tmp_[i] + floor_each;
    bel_[i] = v;
    if (v > bel_[best]) best = i;
  }
  summarise_at(best);
  return s;
}

Status RouteFilter::update(Span<const NodeMeasurement> m) noexcept {
  if (n_ == 0) return Status(StatusCode::kNotReady, "route filter: reset() first");
  last_m_.clear();
  const float fl = config_.inlier_floor;
  // Lost: the nodes around the estimate have shown no similarity while nodes elsewhere have, for
  // lost_after_updates updates (kidnapped, or the estimate is wrong): give mass back to the whole
  // route before this update. No similarity anywhere is no evidence (a featureless stretch, a tile
  // seen from far off the route): the belief then runs on the motion model alone.
  if (config_.lost_after_updates > 0) {
    bool support = false, elsewhere = false;
    for (const NodeMeasurement& x : m) {
      if (x.node >= n_ || !std::isfinite(x.inliers) || !(x.inliers > config_.chance_inliers)) continue;
      const std::int64_t d = static_cast<std::int64_t>(x.node) - static_cast<std::int64_t>(argmax_);
      if (d >= -1 && d <= 1)
        support = true;
      else if (x.inliers >= config_.lost_evidence_inliers)
        elsewhere = true;
    }
    if (support) {
      misses_ = 0;
      unsupported_ = 0;
      lost_ = false;
    } else {
      ++unsupported_;
      if (elsewhere && confident()) ++misses_;  // not confident: nothing to be lost from, Bayes moves the mass
    }
    if (misses_ >= config_.lost_after_updates) {
      misses_ = 0;
      lost_ = true;
      counters_.increment(FilterCounter::kLostResets);
      const float keep = static_cast<float>(1.0 - config_.lost_reset_mass);
      const float add = static_cast<float>(config_.lost_reset_mass / static_cast<double>(n_));
      for (std::uint32_t i = 0; i < n_; ++i) bel_[i] = keep * bel_[i] + add;
    }
  }
  // bel *= L / floor (unmeasured nodes keep their prediction: L / floor = 1).
  for (const NodeMeasurement& x : m) {
    if (x.node >= n_ || !std::isfinite(x.inliers) || x.inliers < 0.0f) {
      counters_.increment(FilterCounter::kBadMeasurement);
      continue;
    }
    if (mark_[x.node] == 1) continue;  // duplicate
    mark_[x.node] = 1;
    const float excess = x.inliers > config_.chance_inliers ? x.inliers - config_.chance_inliers : 0.0f;
    bel_[x.node] *= (fl + excess) / fl;
    last_m_.push_back(x).ignore();
  }
  for (const NodeMeasurement& x : m)
    if (x.node < n_) mark_[x.node] = 0;
  Status s = normalise(bel_);
  ++updates_;
  summarise();
  return s;
}

Status RouteFilter::measurement_probability(Span<float> out) const noexcept {
  if (out.size() < n_) return Status(StatusCode::kCapacityExceeded, "measurement_probability: buffer too small");
  double sum = static_cast<double>(config_.inlier_floor) * n_;
  for (std::uint32_t i = 0; i < n_; ++i) out[i] = config_.inlier_floor;
  for (const NodeMeasurement& x : last_m_) {
    const float excess = x.inliers > config_.chance_inliers ? x.inliers - config_.chance_inliers : 0.0f;
    out[x.node] += excess;
    sum += static_cast<double>(excess);
  }
  const float inv = static_cast<float>(1.0 / sum);
  for (std::uint32_t i = 0; i < n_; ++i) out[i] *= inv;
  return Status::ok();
}

std::size_t RouteFilter::select_nodes(Span<std::uint32_t> out) noexcept {
  if (n_ == 0 || out.empty()) return 0;
  std::size_t count = 0;
  // Top-B by belief (insertion into a short sorted list held at the front of out).
  // Searching (lost, not confident, or the estimate has shown nothing lately): the belief peak is
  // not worth the whole belief budget; keep searching_belief_registrations belief nodes and give the
  // rest to the wide search (same bound on registrations per update).
  const bool searching = lost_ || !confident() || unsupported_ > 0;
  std::uint32_t belief_budget = config_.belief_registrations;
  if (searching && config_.searching_belief_registrations < belief_budget) belief_budget = config_.searching_belief_registrations;
  const std::uint32_t wide_budget = searching ? config_.max_registrations() - belief_budget : config_.wide_search_registrations;
  const std::size_t b = belief_budget < out.size() ? belief_budget : out.size();
  const std::size_t want = b < n_ ? b : n_;
  for (std::uint32_t i = 0; i < n_; ++i) {
    const float p = bel_[i];
    if (count == want && p <= bel_[out[count - 1]]) continue;
    std::size_t pos = count < want ? count++ : want - 1;
    while (pos > 0 && bel_[out[pos - 1]] < p) {
      out[pos] = out[pos - 1];
      --pos;
    }
    out[pos] = i;
  }
  for (std::size_t i = 0; i < count; ++i) mark_[out[i]] = 1;
  // Every update while searching; otherwise every wide_search_period updates.
  const bool wide = searching || (selects_++ % config_.wide_search_period) == 0;
  if (wide && wide_budget > 0) {
    const std::uint32_t k = wide_budget;
    const double stride = static_cast<double>(n_) / k;
    // Golden-ratio phases cover the gaps evenly relative to the vehicle: the grid also moves with
    // the predicted advance, else a grid stepping in step with the vehicle would miss it every time.
    const double g = 0.6180339887498949 * static_cast<double>(wide_phase_);
    double phase = stride * (g - std::floor(g)) + wide_shift_nodes_;
    phase -= std::floor(phase / static_cast<double>(n_)) * static_cast<double>(n_);
    ++wide_phase_;
    for (std::uint32_t i = 0; i < k && count < out.size(); ++i) {
      const std::uint32_t node = static_cast<std::uint32_t>(phase + i * stride) % n_;
      if (mark_[node]) continue;
      mark_[node] = 1;
      out[count++] = node;
    }
  }
  for (std::size_t i = 0; i < count; ++i) mark_[out[i]] = 0;
  return count;
}

void RouteFilter::summarise() noexcept {
  std::uint32_t best = 0;
  for (std::uint32_t i = 0; i < n_; ++i)
    if (bel_[i] > bel_[best]) best = i;
  summarise_at(best);
}

void RouteFilter::summarise_at(std::uint32_t best) noexcept {
  argmax_ = best;
  double m = static_cast<double>(bel_[best]);
  if (best > 0) m += static_cast<double>(bel_[best - 1]);
  if (best + 1 < n_) m += static_cast<double>(bel_[best + 1]);
  mass_pm1_ = m;
}

double RouteFilter::entropy() const noexcept {
  double h = 0.0;
  for (std::uint32_t i = 0; i < n_; ++i) {
    const double p = static_cast<double>(bel_[i]);
    if (p > 0.0) h -= p * std::log(p);
  }
  return h;
}

}  // namespace qnav::route
