#include "nav/match/ratio_match.hpp"

#include <cmath>

namespace qnav::match {

namespace {

// Squared L2 distance in a fixed order, abandoned (returning the partial sum, > bound) once a block
// of 16 dimensions leaves it above bound.
float distance_sq_bounded(const float* a, const float* b, float bound) noexcept {
  float d = 0.0f;
  for (int blk = 0; blk < vision::kOrientedDims; blk += 16) {
    for (int i = blk; i < blk + 16; ++i) {
      const float e = a[i] - b[i];
      d += e * e;
    }
    if (d > bound) return d;
  }
  return d;
}

constexpr float kHuge = 3.0e38f;

bool position_finite(const vision::OrientedDescriptor& d) noexcept { return std::isfinite(d.x) && std::isfinite(d.y); }

}  // namespace

std::size_t RatioMatcher::arena_bytes(const RatioMatchConfig& c) noexcept {
  const std::size_t cells = c.grid_side * c.grid_side + 1;
  return c.max_query * (sizeof(std::int32_t) + 2 * sizeof(float) + 1) + c.max_train * (sizeof(std::int32_t) + sizeof(float)) +
         cells * sizeof(std::uint32_t) + c.max_train * sizeof(std::uint16_t) + 8 * 16;
}

Status RatioMatcher::init(const RatioMatchConfig& c, Arena& arena) noexcept {
  if (c.max_query == 0 || c.max_query > 65535 || c.max_train == 0 || c.max_train > 65535 || !(c.max_ratio > 0.0f) ||
      !(c.max_ratio <= 1.0f) || !(c.max_distance > 0.0f) || !(c.search_radius_px > 0.0f) || !std::isfinite(c.search_radius_px) ||
      c.max_candidates == 0 || c.grid_side == 0 || c.grid_side > 256)
    return Status(StatusCode::kInvalidArgument, "ratio_match: bad configuration");
  q_t1_ = arena.allocate<std::int32_t>(c.max_query);
  q_d1_ = arena.allocate<float>(c.max_query);
  q_d2_ = arena.allocate<float>(c.max_query);
  q_has2_ = arena.allocate<std::uint8_t>(c.max_query);
  t_q1_ = arena.allocate<std::int32_t>(c.max_train);
  t_d1_ = arena.allocate<float>(c.max_train);
  cell_start_ = arena.allocate<std::uint32_t>(c.grid_side * c.grid_side + 1);
  cell_items_ = arena.allocate<std::uint16_t>(c.max_train);
  if (q_t1_.empty() || q_d1_.empty() || q_d2_.empty() || q_has2_.empty() || t_q1_.empty() || t_d1_.empty() ||
      cell_start_.empty() || cell_items_.empty())
    return Status(StatusCode::kCapacityExceeded, "ratio_match: arena too small");
  config_ = c;
  ready_ = true;
  return Status::ok();
}

void RatioMatcher::reset_train(std::size_t nt) noexcept {
  for (std::size_t j = 0; j < nt; ++j) {
    t_q1_[j] = -1;
    t_d1_[j] = kHuge;
  }
}

void RatioMatcher::consider(std::uint32_t qi, const vision::OrientedDescriptor& q, std::uint32_t ti,
                            const vision::OrientedDescriptor& t, Best& best) noexcept {
  // The pair matters while its distance could enter q's top two, or become t's nearest query.
  float bound = best.t1 < 0 ? kHuge : (best.has2 ? best.d2 : kHuge);
  if (config_.mutual && t_d1_[ti] > bound) bound = t_d1_[ti];
  ++stats_.distances;
  const float d = distance_sq_bounded(q.v, t.v, bound);
  if (config_.mutual && d < t_d1_[ti]) {
    t_d1_[ti] = d;
    t_q1_[ti] = static_cast<std::int32_t>(qi);
  }
  if (best.t1 < 0 || d < best.d1) {
    if (best.t1 >= 0) {
      best.d2 = best.d1;
      best.has2 = true;
    }
    best.d1 = d;
    best.t1 = static_cast<std::int32_t>(ti);
  } else if (!best.has2 || d < best.d2) {
    best.d2 = d;
    best.has2 = true;
  }
}

Status RatioMatcher::finish(std::size_t nq, BoundedVector<DescriptorMatch>& out) noexcept {
  const float r2 = config_.max_ratio * config_.max_ratio;
  const float dmax2 = config_.max_distance * config_.max_distance;
  Status status = Status::ok();
  for (std::size_t i = 0; i < nq; ++i) {
    const std::int32_t t = q_t1_[i];
    if (t == -2) continue;  // invalid query (counted)
    if (t < 0) {
      ++stats_.no_candidate;
      continue;
    }
    const float d1 = q_d1_[i];
    if (q_has2_[i] != 0 ? !(d1 < r2 * q_d2_[i]) : !config_.accept_single) {
      ++stats_.ratio_rejected;
      continue;
    }
    if (!(d1 <= dmax2)) {
      ++stats_.distance_rejected;
      continue;
    }
    if (config_.mutual && t_q1_[static_cast<std::size_t>(t)] != static_cast<std::int32_t>(i)) {
      ++stats_.mutual_rejected;
      continue;
    }
    DescriptorMatch m;
    m.query = static_cast<std::uint16_t>(i);
    m.train = static_cast<std::uint16_t>(t);
    m.distance = std::sqrt(d1);
    m.ratio = q_has2_[i] != 0 && q_d2_[i] > 0.0f ? std::sqrt(d1 / q_d2_[i]) : 0.0f;
    if (!out.push_back(m).is_ok()) {
      counters_.increment(RatioMatchCounter::kOutputFull);
      status = Status(StatusCode::kCapacityExceeded, "ratio_match: output full");
      break;
    }
    ++stats_.matched;
  }
  return status;
}

// Queries and train descriptors beyond the configured capacities are ignored, and counted.
void RatioMatcher::clamp_sizes(std::size_t& nq, std::size_t& nt) noexcept {
  if (nq > config_.max_query) {
    counters_.increment(RatioMatchCounter::kQueryIgnored, static_cast<std::uint32_t>(nq - config_.max_query));
    nq = config_.max_query;
  }
  if (nt > config_.max_train) {
    counters_.increment(RatioMatchCounter::kTrainIgnored, static_cast<std::uint32_t>(nt - config_.max_train));
    nt = config_.max_train;
  }
}

Status RatioMatcher::match(Span<const vision::OrientedDescriptor> query, Span<const vision::OrientedDescriptor> train,
                           BoundedVector<DescriptorMatch>& out) noexcept {
  out.clear();
  stats_ = RatioMatchStats{};
  if (!ready_) return Status(StatusCode::kNotReady, "ratio_match: not initialised");
  std::size_t nq = query.size(), nt = train.size();
  clamp_sizes(nq, nt);
  std::uint32_t invalid_train = 0;
  for (std::size_t j = 0; j < nt; ++j) invalid_train += train[j].valid ? 0u : 1u;
  if (invalid_train > 0) counters_.increment(RatioMatchCounter::kInvalidDescriptor, invalid_train);
  reset_train(nt);
  for (std::size_t i = 0; i < nq; ++i) {
    const vision::OrientedDescriptor& q = query[i];
    if (!q.valid) {
      counters_.increment(RatioMatchCounter::kInvalidDescriptor);
      q_t1_[i] = -2;
      continue;
    }
    ++stats_.queries;
    Best best;
    for (std::size_t j = 0; j < nt; ++j)
      if (train[j].valid) consider(static_cast<std::uint32_t>(i), q, static_cast<std::uint32_t>(j), train[j], best);
    q_t1_[i] = best.t1;
    q_d1_[i] = best.d1;
    q_d2_[i] = best.d2;
    q_has2_[i] = best.has2 ? 1 : 0;
  }
  return finish(nq, out);
}

Status RatioMatcher::match_predicted(Span<const vision::OrientedDescriptor> query, Span<const Vec2d> predicted_px,
                                     Span<const vision::OrientedDescriptor> train, BoundedVector<DescriptorMatch>& out) noexcept {
  out.clear();
  stats_ = RatioMatchStats{};
  if (!ready_) return Status(StatusCode::kNotReady, "ratio_match: not initialised");
  if (predicted_px.size() != query.size()) return Status(StatusCode::kInvalidArgument, "ratio_match: one prediction per query");
  std::size_t nq = query.size(), nt = train.size();
  clamp_sizes(nq, nt);
  reset_train(nt);
  // Grid over the usable train positions: bounding box, cell side >= the search radius.
  float x0 = kHuge, y0 = kHuge, x1 = -kHuge, y1 = -kHuge;
  std::uint32_t usable = 0, invalid_train = 0;
  for (std::size_t j = 0; j < nt; ++j) {
    if (!train[j].valid || !position_finite(train[j])) {
      ++invalid_train;
      continue;
    }
    ++usable;
    // Plain comparisons, not fminf / fmaxf (the freestanding LEON3 libm does not carry them).
    if (train[j].x < x0) x0 = train[j].x;
    if (train[j].y < y0) y0 = train[j].y;
    if (train[j].x > x1) x1 = train[j].x;
    if (train[j].y > y1) y1 = train[j].y;
  }
  if (invalid_train > 0) counters_.increment(RatioMatchCounter::kInvalidDescriptor, invalid_train);
  const float radius = config_.search_radius_px;
  const std::size_t side = config_.grid_side;
  std::size_t nx = 1, ny = 1;
  float cell = radius;
  if (usable > 0) {
    const float ext = (x1 - x0) > (y1 - y0) ? (x1 - x0) : (y1 - y0);
    if (ext / static_cast<float>(side) > cell) cell = ext / static_cast<float>(side);
    nx = static_cast<std::size_t>((x1 - x0) / cell) + 1;
    ny = static_cast<std::size_t>((y1 - y0) / cell) + 1;
    if (nx > side) nx = side;
    if (ny > side) ny = side;
  }
  auto cell_of = [&](float v, float v0, std::size_t n) -> std::size_t {
    const float f = (v - v0) / cell;
    if (!(f > 0.0f)) return 0;
    const std::size_t k = static_cast<std::size_t>(f);
    return k < n ? k : n - 1;
  };
  // Counting sort of the train indices by cell.
  const std::size_t ncells = nx * ny;
  for (std::size_t k = 0; k <= ncells; ++k) cell_start_[k] = 0;
  for (std::size_t j = 0; j < nt; ++j)
    if (train[j].valid && position_finite(train[j])) ++cell_start_[cell_of(train[j].y, y0, ny) * nx + cell_of(train[j].x, x0, nx) + 1];
  for (std::size_t k = 0; k < ncells; ++k) cell_start_[k + 1] += cell_start_[k];
  // Fill: cursor per cell in cell_start_ shifted by one, restored after.
  for (std::size_t j = 0; j < nt; ++j) {
    if (!train[j].valid || !position_finite(train[j])) continue;
    const std::size_t k = cell_of(train[j].y, y0, ny) * nx + cell_of(train[j].x, x0, nx);
    cell_items_[cell_start_[k]++] = static_cast<std::uint16_t>(j);
  }
  for (std::size_t k = ncells; k > 0; --k) cell_start_[k] = cell_start_[k - 1];
  cell_start_[0] = 0;

  const float r2 = radius * radius;
  for (std::size_t i = 0; i < nq; ++i) {
    const vision::OrientedDescriptor& q = query[i];
    q_t1_[i] = -2;
    if (!q.valid) {
      counters_.increment(RatioMatchCounter::kInvalidDescriptor);
      continue;
    }
    const Vec2d& p = predicted_px[i];
    if (!p.allFinite()) {
      counters_.increment(RatioMatchCounter::kBadPrediction);
      continue;
    }
    ++stats_.queries;
    Best best;
    if (usable > 0) {
      const float px = static_cast<float>(p.x()), py = static_cast<float>(p.y());
      const bool outside = px + radius < x0 || px - radius > x1 || py + radius < y0 || py - radius > y1;
      std::size_t compared = 0;
      bool capped = false;
      if (!outside) {
        const std::size_t cx0 = cell_of(px - radius, x0, nx), cx1 = cell_of(px + radius, x0, nx);
        const std::size_t cy0 = cell_of(py - radius, y0, ny), cy1 = cell_of(py + radius, y0, ny);
        for (std::size_t cy = cy0; cy <= cy1 && !capped; ++cy) {
          for (std::size_t cx = cx0; cx <= cx1 && !capped; ++cx) {
            const std::size_t k = cy * nx + cx;
            for (std::uint32_t s = cell_start_[k]; s < cell_start_[k + 1]; ++s) {
              const std::uint32_t j = cell_items_[s];
              const float dx = train[j].x - px, dy = train[j].y - py;
              if (dx * dx + dy * dy > r2) continue;
              if (compared == config_.max_candidates) {
                capped = true;
                break;
              }
              ++compared;
              consider(static_cast<std::uint32_t>(i), q, j, train[j], best);
            }
          }
        }
      }
      if (capped) counters_.increment(RatioMatchCounter::kCandidatesCapped);
    }
    q_t1_[i] = best.t1;
    q_d1_[i] = best.d1;
    q_d2_[i] = best.d2;
    q_has2_[i] = best.has2 ? 1 : 0;
  }
  return finish(nq, out);
}

}  // namespace qnav::match
