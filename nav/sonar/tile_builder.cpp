#include "nav/sonar/tile_builder.hpp"

#include <cmath>

namespace qnav::sonar {

namespace {
constexpr std::size_t kAlign = 16;
std::size_t padded(std::size_t bytes) noexcept { return bytes + kAlign; }
int side_sign(int side) noexcept { return side == 0 ? -1 : 1; }  // 0 = port (-starboard), 1 = stbd
double lerp_angle(double a, double b, double t) noexcept { return a + t * wrap_angle_rad(b - a); }
}  // namespace

std::size_t TileBuilder::arena_bytes(const TileBuilderConfig& c) noexcept {
  if (c.scanlines_per_tile <= 0 || c.max_bins_per_side <= 0 || c.tile_width_px <= 0 || c.tile_height_px <= 0) return 0;
  const std::size_t n = static_cast<std::size_t>(c.scanlines_per_tile);
  const std::size_t b = static_cast<std::size_t>(c.max_bins_per_side);
  const std::size_t px = static_cast<std::size_t>(c.tile_width_px) * static_cast<std::size_t>(c.tile_height_px);
  return padded(n * sizeof(Slot)) + padded(n * 2 * b * sizeof(float)) + padded(n * 2 * b) + 3 * padded(px * sizeof(float)) +
         2 * padded(px);
}

Status TileBuilder::init(const TileBuilderConfig& c, Arena& arena) noexcept {
  ready_ = false;
  if (!(std::isfinite(c.resolution_m) && c.resolution_m > 1e-4 && c.resolution_m < 1000.0))
    return Status(StatusCode::kInvalidArgument, "resolution_m outside (1e-4, 1000)");
  if (c.tile_width_px < 8 || c.tile_height_px < 8 || c.tile_width_px > kMaxImageSide || c.tile_height_px > kMaxImageSide)
    return Status(StatusCode::kInvalidArgument, "tile size outside [8, 16384]");
  if (c.scanlines_per_tile < 2 || c.scanlines_per_tile > 100000)
    return Status(StatusCode::kInvalidArgument, "scanlines_per_tile outside [2, 100000]");
  if (c.scanline_stride < 1 || c.scanline_stride > c.scanlines_per_tile)
    return Status(StatusCode::kInvalidArgument, "scanline_stride outside [1, scanlines_per_tile]");
  if (c.max_bins_per_side < 1 || c.max_bins_per_side > 65536) return Status(StatusCode::kInvalidArgument, "max_bins_per_side outside [1, 65536]");
  if (c.max_substeps < 1 || c.max_substeps > 1024) return Status(StatusCode::kInvalidArgument, "max_substeps outside [1, 1024]");
  if (!(c.max_gap_m > 0.0)) return Status(StatusCode::kInvalidArgument, "max_gap_m must be > 0");
  if (c.hole_fill_radius_px < 0 || c.hole_fill_radius_px > 8 || c.hole_fill_min_neighbours < 1)
    return Status(StatusCode::kInvalidArgument, "hole fill radius outside [0, 8] or min neighbours < 1");
  if (!(std::isfinite(c.display_max) && c.display_max > 0.0f)) return Status(StatusCode::kInvalidArgument, "display_max must be > 0");
  const std::size_t n = static_cast<std::size_t>(c.scanlines_per_tile);
  const std::size_t b = static_cast<std::size_t>(c.max_bins_per_side);
  const std::size_t px = static_cast<std::size_t>(c.tile_width_px) * static_cast<std::size_t>(c.tile_height_px);
  slots_ = arena.allocate<Slot>(n);
  values_ = arena.allocate<float>(n * 2 * b);
  valid_ = arena.allocate<std::uint8_t>(n * 2 * b);
  sum_ = arena.allocate<float>(px);
  weight_ = arena.allocate<float>(px);
  intensity_ = arena.allocate<float>(px);
  coverage_ = arena.allocate<std::uint8_t>(px);
  u8_ = arena.allocate<std::uint8_t>(px);
  if (slots_.empty() || values_.empty() || valid_.empty() || sum_.empty() || weight_.empty() || intensity_.empty() ||
      coverage_.empty() || u8_.empty())
    return Status(StatusCode::kCapacityExceeded, "arena too small for TileBuilder");
  cfg_ = c;
  head_ = count_ = since_tile_ = 0;
  tiles_built_ = 0;
  tile_ = SonarTile{};
  ready_ = true;
  return Status::ok();
}

void TileBuilder::reset() noexcept {
  head_ = count_ = since_tile_ = 0;
}

Result<bool> TileBuilder::push(const CorrectedScanline& line, const Pose2& pose) noexcept {
  if (!ready_) return Status(StatusCode::kNotReady, "TileBuilder not initialised");
  if (!pose.is_finite()) {
    counters_.increment(TileCounter::kBadPose);
    return Status(StatusCode::kInvalidArgument, "scanline pose not finite");
  }
  const std::size_t bins = line.port.size();
  if (bins == 0 || bins > static_cast<std::size_t>(cfg_.max_bins_per_side) || line.stbd.size() != bins ||
      line.port_valid.size() != bins || line.stbd_valid.size() != bins || !(std::isfinite(line.bin_m) && line.bin_m > 0.0f)) {
    counters_.increment(TileCounter::kBadScanline);
    return Status(StatusCode::kInvalidArgument, "scanline sizes differ, exceed max_bins_per_side or bin_m <= 0");
  }
  for (std::size_t i = 0; i < bins; ++i) {
    if (!std::isfinite(line.port[i]) || !std::isfinite(line.stbd[i])) {
      counters_.increment(TileCounter::kBadScanline);
      return Status(StatusCode::kInvalidArgument, "scanline value not finite");
    }
  }
  const int N = cfg_.scanlines_per_tile;
  if (count_ == N) {
    head_ = (head_ + 1) % N;
    --count_;
  }
  const int i = count_++;
  Slot& s = slots_[ring(i)];
  s.pose = pose;
  s.stamp_ns = line.stamp_ns;
  s.ping = line.ping_number;
  s.bin_m = line.bin_m;
  s.bins = static_cast<int>(bins);
  float* vp = values(i, 0);
  float* vs = values(i, 1);
  std::uint8_t* kp = valid(i, 0);
  std::uint8_t* ks = valid(i, 1);
  for (std::size_t k = 0; k < bins; ++k) {
    vp[k] = line.port[k];
    vs[k] = line.stbd[k];
    kp[k] = line.port_valid[k] ? 1 : 0;
    ks[k] = line.stbd_valid[k] ? 1 : 0;
  }
  ++since_tile_;
  if (count_ == N && (tiles_built_ == 0 ? since_tile_ >= N : since_tile_ >= cfg_.scanline_stride)) {
    QNAV_RETURN_IF_ERROR(build(0, N));
    since_tile_ = 0;
    return true;
  }
  return false;
}

Result<bool> TileBuilder::flush(int min_scanlines) noexcept {
  if (!ready_) return Status(StatusCode::kNotReady, "TileBuilder not initialised");
  if (since_tile_ <= 0) return false;
  int n = since_tile_ + (cfg_.scanlines_per_tile - cfg_.scanline_stride);
  if (tiles_built_ == 0) n = since_tile_;
  if (n > count_) n = count_;
  if (n < min_scanlines || n < 2) return false;
  QNAV_RETURN_IF_ERROR(build(count_ - n, n));
  since_tile_ = 0;
  return true;
}

void TileBuilder::splat(double col, double row, float v) noexcept {
  // Bilinear splat of one sample at continuous pixel coordinates (pixel centres at +0.5).
  const double x = col - 0.5, y = row - 0.5;
  const double fx0 = std::floor(x), fy0 = std::floor(y);
  const int W = cfg_.tile_width_px, H = cfg_.tile_height_px;
  if (!(fx0 >= -1.0 && fy0 >= -1.0 && fx0 < W && fy0 < H)) {
    ++clipped_;
    return;
  }
  const int x0 = static_cast<int>(fx0), y0 = static_cast<int>(fy0);
  const float ax = static_cast<float>(x - fx0), ay = static_cast<float>(y - fy0);
  const float w[4] = {(1 - ax) * (1 - ay), ax * (1 - ay), (1 - ax) * ay, ax * ay};
  const int xs[4] = {x0, x0 + 1, x0, x0 + 1};
  const int ys[4] = {y0, y0, y0 + 1, y0 + 1};
  for (int k = 0; k < 4; ++k) {
    if (xs[k] < 0 || ys[k] < 0 || xs[k] >= W || ys[k] >= H) continue;
    const std::size_t idx = static_cast<std::size_t>(ys[k]) * static_cast<std::size_t>(W) + static_cast<std::size_t>(xs[k]);
    sum_[idx] += w[k] * v;
    weight_[idx] += w[k];
  }
}

Status TileBuilder::build(int first, int count) noexcept {
  const int W = cfg_.tile_width_px, H = cfg_.tile_height_px;
  const double res = cfg_.resolution_m;
  // Bounding box of the swath (first and last valid bin of each side of each scanline).
  double nmin = 1e300, nmax = -1e300, emin = 1e300, emax = -1e300;
  for (int i = first; i < first + count; ++i) {
    const Slot& s = slots_[ring(i)];
    const Vec2d c = s.pose.translation();
    const Vec2d sb = starboard_unit(s.pose.heading_rad);
    for (int side = 0; side < 2; ++side) {
      const std::uint8_t* k = valid(i, side);
      int lo = -1, hi = -1;
      for (int b = 0; b < s.bins; ++b)
        if (k[b]) {
          if (lo < 0) lo = b;
          hi = b;
        }
      const int ends[2] = {lo, hi};
      for (int e = 0; e < 2; ++e) {
        const double g = ends[e] < 0 ? 0.0 : (ends[e] + 0.5) * static_cast<double>(s.bin_m);
        const Vec2d p = c + side_sign(side) * g * sb;
        nmin = p.x() < nmin ? p.x() : nmin;
        nmax = p.x() > nmax ? p.x() : nmax;
        emin = p.y() < emin ? p.y() : emin;
        emax = p.y() > emax ? p.y() : emax;
      }
    }
  }
  const double cn = 0.5 * (nmin + nmax), ce = 0.5 * (emin + emax);
  tile_.resolution_m = res;
  tile_.origin_north_m = std::round((cn + 0.5 * H * res) / res) * res;
  tile_.origin_east_m = std::round((ce - 0.5 * W * res) / res) * res;
  const std::size_t px = static_cast<std::size_t>(W) * static_cast<std::size_t>(H);
  for (std::size_t k = 0; k < px; ++k) {
    sum_[k] = 0.0f;
    weight_[k] = 0.0f;
  }
  clipped_ = 0;
  const double inv_res = 1.0 / res;
  const double half_px = 0.5 * res;
  for (int i = first; i < first + count; ++i) {
    const Slot& a = slots_[ring(i)];
    const bool has_next = i + 1 < first + count;
    const Slot* bslot = has_next ? &slots_[ring(i + 1)] : nullptr;
    int steps = 1;
    if (has_next) {
      const double d = (bslot->pose.translation() - a.pose.translation()).norm();
      if (d > cfg_.max_gap_m) {
        counters_.increment(TileCounter::kNavJump);
        bslot = nullptr;
      } else {
        // Steps such that the far-range bins advance at most half a pixel per sub-step.
        const double reach = a.bins * static_cast<double>(a.bin_m);
        const double dh = std::fabs(wrap_angle_rad(bslot->pose.heading_rad - a.pose.heading_rad));
        const double move = d + dh * reach;
        steps = static_cast<int>(std::ceil(move / half_px));
        if (steps < 1) steps = 1;
        if (steps > cfg_.max_substeps) steps = cfg_.max_substeps;
      }
    }
    const int bins = a.bins;
    const int across = static_cast<int>(std::ceil(static_cast<double>(a.bin_m) / half_px));
    for (int j = 0; j < steps; ++j) {
      const float t = static_cast<float>(j) / static_cast<float>(steps);
      Pose2 p = a.pose;
      if (bslot != nullptr && j > 0) {
        const double td = static_cast<double>(t);
        p.x_m = a.pose.x_m + td * (bslot->pose.x_m - a.pose.x_m);
        p.y_m = a.pose.y_m + td * (bslot->pose.y_m - a.pose.y_m);
        p.heading_rad = lerp_angle(a.pose.heading_rad, bslot->pose.heading_rad, td);
      }
      const Vec2d sb = starboard_unit(p.heading_rad);
      const double c0 = (p.y_m - tile_.origin_east_m) * inv_res;
      const double r0 = (tile_.origin_north_m - p.x_m) * inv_res;
      for (int side = 0; side < 2; ++side) {
        const float* va = values(i, side);
        const std::uint8_t* ka = valid(i, side);
        const float* vb = bslot != nullptr && bslot->bins == bins ? values(i + 1, side) : nullptr;
        const std::uint8_t* kb = vb != nullptr ? valid(i + 1, side) : nullptr;
        // Per metre across track: d(col) = sign*sb.east/res, d(row) = -sign*sb.north/res.
        const double dc = side_sign(side) * sb.y() * inv_res;
        const double dr = -side_sign(side) * sb.x() * inv_res;
        for (int b = 0; b < bins; ++b) {
          float v;
          if (vb != nullptr && ka[b] && kb[b]) {
            v = va[b] + t * (vb[b] - va[b]);
          } else if (ka[b] && (vb == nullptr || t < 0.5f || !kb[b])) {
            v = va[b];
          } else if (vb != nullptr && kb[b] && t >= 0.5f) {
            v = vb[b];
          } else {
            continue;
          }
          if (across <= 1) {
            const double g = (b + 0.5) * static_cast<double>(a.bin_m);
            splat(c0 + g * dc, r0 + g * dr, v);
          } else {
            // Bin wider than half a pixel: spread it across in sub-steps (constant value within the bin).
            for (int q = 0; q < across; ++q) {
              const double g = (b + (q + 0.5) / across) * static_cast<double>(a.bin_m);
              splat(c0 + g * dc, r0 + g * dr, v);
            }
          }
        }
      }
    }
  }
  // Normalise and mark coverage.
  const float eps = 1e-3f;
  for (std::size_t k = 0; k < px; ++k) {
    if (weight_[k] > eps) {
      intensity_[k] = sum_[k] / weight_[k];
      coverage_[k] = 1;
    } else {
      intensity_[k] = 0.0f;
      coverage_[k] = 0;
    }
  }
  if (cfg_.hole_fill_radius_px > 0) fill_holes();
  std::size_t covered = 0;
  const float scale = 255.0f / cfg_.display_max;
  for (std::size_t k = 0; k < px; ++k) {
    if (coverage_[k] != 0) ++covered;
    float u = intensity_[k] * scale + 0.5f;
    u = u < 0.0f ? 0.0f : (u > 255.0f ? 255.0f : u);
    u8_[k] = static_cast<std::uint8_t>(u);
  }
  counters_.increment(TileCounter::kClippedSplat, clipped_);
  const Slot& f = slots_[ring(first)];
  const Slot& l = slots_[ring(first + count - 1)];
  const Slot& m = slots_[ring(first + count / 2)];
  tile_.index = tiles_built_;
  tile_.intensity = ConstImageViewF32::unchecked(intensity_.data(), W, H, W);
  tile_.intensity_u8 = ConstImageViewU8::unchecked(u8_.data(), W, H, W);
  tile_.coverage = ConstImageViewU8::unchecked(coverage_.data(), W, H, W);
  tile_.pose = m.pose;
  tile_.first_pose = f.pose;
  tile_.last_pose = l.pose;
  tile_.first_stamp_ns = f.stamp_ns;
  tile_.last_stamp_ns = l.stamp_ns;
  tile_.first_ping = f.ping;
  tile_.last_ping = l.ping;
  tile_.scanlines = static_cast<std::uint32_t>(count);
  const double rf = f.bins * static_cast<double>(f.bin_m), rl = l.bins * static_cast<double>(l.bin_m);
  tile_.footprint_ne[0] = f.pose.translation() - rf * starboard_unit(f.pose.heading_rad);
  tile_.footprint_ne[1] = f.pose.translation() + rf * starboard_unit(f.pose.heading_rad);
  tile_.footprint_ne[2] = l.pose.translation() + rl * starboard_unit(l.pose.heading_rad);
  tile_.footprint_ne[3] = l.pose.translation() - rl * starboard_unit(l.pose.heading_rad);
  tile_.coverage_fraction = static_cast<float>(static_cast<double>(covered) / static_cast<double>(px));
  tile_.clipped_splats = clipped_;
  ++tiles_built_;
  return Status::ok();
}

void TileBuilder::fill_holes() noexcept {
  // Reads measured pixels only (coverage 1), so filling does not cascade: holes wider than
  // 2 * radius stay empty. Sides = the four quadrants around the pixel; a hole pixel needs
  // measured neighbours in at least hole_fill_min_neighbours quadrants (so edges are not grown).
  const int W = cfg_.tile_width_px, H = cfg_.tile_height_px, R = cfg_.hole_fill_radius_px;
  for (int y = 0; y < H; ++y) {
    for (int x = 0; x < W; ++x) {
      const std::size_t idx = static_cast<std::size_t>(y) * static_cast<std::size_t>(W) + static_cast<std::size_t>(x);
      if (coverage_[idx] != 0) continue;
      float acc = 0.0f, wsum = 0.0f;
      unsigned quadrants = 0;
      for (int dy = -R; dy <= R; ++dy) {
        const int yy = y + dy;
        if (yy < 0 || yy >= H) continue;
        for (int dx = -R; dx <= R; ++dx) {
          const int xx = x + dx;
          if (xx < 0 || xx >= W || (dx == 0 && dy == 0)) continue;
          const std::size_t j = static_cast<std::size_t>(yy) * static_cast<std::size_t>(W) + static_cast<std::size_t>(xx);
          if (coverage_[j] != 1) continue;
          const float w = 1.0f / static_cast<float>(dx * dx + dy * dy);
          acc += w * intensity_[j];
          wsum += w;
          quadrants |= (dx < 0 ? 1u : 0u) | (dx > 0 ? 2u : 0u) | (dy < 0 ? 4u : 0u) | (dy > 0 ? 8u : 0u);
        }
      }
      const int sides = static_cast<int>(((quadrants & 1u) && (quadrants & 2u)) ? 1 : 0) +
                        static_cast<int>(((quadrants & 4u) && (quadrants & 8u)) ? 1 : 0);
      if (wsum > 0.0f && sides >= 1 && __builtin_popcount(quadrants) >= cfg_.hole_fill_min_neighbours) {
        intensity_[idx] = acc / wsum;
        coverage_[idx] = 2;
      }
    }
  }
}

}  // namespace qnav::sonar
