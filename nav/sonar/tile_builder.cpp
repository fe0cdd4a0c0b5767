#include "nav/sonar/tile_builder.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace qnav::sonar {

namespace {
constexpr std::size_t kAlign = 16;
std::size_t padded(std::size_t bytes) noexcept { return bytes + kAlign; }
int side_sign(int side) noexcept { return side == 0 ? -1 : 1; }  // 0 = port (-starboard), 1 = stbd
double lerp_angle(double a, double b, double t) noexcept { return a + t * wrap_angle_rad(b - a); }
// floor(v) as an int, clamped to +/-2^30 (NaN to the low end): a pose far outside the tile (absurd
// navigation in a damaged file) lands outside the raster instead of overflowing the conversion.
// A pose step below this fraction of the mean step is "no odometry" (a DVL loss freezes the dead
// reckoning; the AHRS still turns its 1 s extrapolation by millimetres).
constexpr double kFrozenStepFraction = 0.05;
// Where the splat's fast path keeps the pixel column the next bin shares in registers (splat_side):
// on hosts with SIMD (out-of-order cores, where a 16-byte load half overlapping the previous store
// stalls on store forwarding); elsewhere (LEON3: in order, no forwarding to lose) the extra selects
// only add instructions. Both add the same terms to every pixel in the same order: the same tile.
#if defined(__SSE2__) || defined(__ARM_NEON) || defined(__aarch64__)
constexpr bool kCarryColumn = true;
#else
constexpr bool kCarryColumn = false;
#endif
int floor_to_int_clamped(double v) noexcept {
  constexpr double kLimit = 1073741824.0;
  if (!(v > -kLimit)) return -1073741824;
  if (v > kLimit) return 1073741824;
  return static_cast<int>(std::floor(v));
}
}  // namespace

std::size_t TileBuilder::arena_bytes(const TileBuilderConfig& c) noexcept {
  if (c.scanlines_per_tile <= 0 || c.max_bins_per_side <= 0 || c.tile_width_px <= 0 || c.tile_height_px <= 0) return 0;
  const std::size_t n = static_cast<std::size_t>(c.scanlines_per_tile);
  const std::size_t b = static_cast<std::size_t>(c.max_bins_per_side);
  const std::size_t px = static_cast<std::size_t>(c.tile_width_px) * static_cast<std::size_t>(c.tile_height_px);
  // The accumulator (its first half is the float intensity raster), one intensity row, coverage and u8.
  return padded(n * sizeof(Slot)) + padded(n * 2 * b * sizeof(float)) + padded(n * 2 * b) + padded(px * sizeof(Acc)) +
         padded(static_cast<std::size_t>(c.tile_width_px) * sizeof(float)) + padded(px) + (c.u8_raster ? padded(px) : 0);
}

Status TileBuilder::init(const TileBuilderConfig& c, Arena& arena) noexcept {
  ready_ = false;
  if (!(std::isfinite(c.resolution_m) && c.resolution_m > 1e-4 && c.resolution_m < 1000.0))
    return Status(StatusCode::kInvalidArgument, "resolution_m outside (1e-4, 1000)");
  if (c.tile_width_px < 8 || c.tile_height_px < 8 || c.tile_width_px > kMaxImageSide || c.tile_height_px > kMaxImageSide)
    return Status(StatusCode::kInvalidArgument, "tile size outside [8, 16384]");
  if (c.scanlines_per_tile < 2 || c.scanlines_per_tile > 100000)
    return Status(StatusCode::kInvalidArgument, "scanlines_per_tile outside [2, 100000]");
  if (c.tile_length_m != 0.0) {  // by distance (NaN lands here too)
    if (!(std::isfinite(c.tile_length_m) && c.tile_length_m > 0.0 && c.tile_length_m <= 100000.0))
      return Status(StatusCode::kInvalidArgument, "tile_length_m outside [0, 100000]");
    if (!(std::isfinite(c.tile_stride_m) && c.tile_stride_m > 0.0 && c.tile_stride_m <= 100000.0))
      return Status(StatusCode::kInvalidArgument, "tile_stride_m outside (0, 100000] (tiles by distance)");
  } else if (c.scanline_stride < 1 || c.scanline_stride > c.scanlines_per_tile) {
    return Status(StatusCode::kInvalidArgument, "scanline_stride outside [1, scanlines_per_tile]");
  }
  if (c.max_bins_per_side < 1 || c.max_bins_per_side > 65536) return Status(StatusCode::kInvalidArgument, "max_bins_per_side outside [1, 65536]");
  if (c.max_substeps < 1 || c.max_substeps > 1024) return Status(StatusCode::kInvalidArgument, "max_substeps outside [1, 1024]");
  if (!(c.max_gap_m > 0.0)) return Status(StatusCode::kInvalidArgument, "max_gap_m must be > 0");
  if (c.hole_fill_radius_px < 0 || c.hole_fill_radius_px > 8 || c.hole_fill_min_neighbours < 1 || c.hole_fill_min_neighbours > 4)
    return Status(StatusCode::kInvalidArgument, "hole fill radius outside [0, 8] or min neighbours outside [1, 4]");
  if (!(std::isfinite(c.display_max) && c.display_max > 0.0f)) return Status(StatusCode::kInvalidArgument, "display_max must be > 0");
  const std::size_t n = static_cast<std::size_t>(c.scanlines_per_tile);
  const std::size_t b = static_cast<std::size_t>(c.max_bins_per_side);
  const std::size_t px = static_cast<std::size_t>(c.tile_width_px) * static_cast<std::size_t>(c.tile_height_px);
  slots_ = arena.allocate<Slot>(n);
  values_ = arena.allocate<float>(n * 2 * b);
  valid_ = arena.allocate<std::uint8_t>(n * 2 * b);
  acc_ = arena.allocate<Acc>(px);
  static_assert(sizeof(Acc) == 2 * sizeof(float), "the intensity raster takes the first half of the accumulator");
  intensity_ = acc_.empty() ? nullptr : static_cast<float*>(static_cast<void*>(acc_.data()));
  row_ = arena.allocate<float>(static_cast<std::size_t>(c.tile_width_px));
  coverage_ = arena.allocate<std::uint8_t>(px);
  u8_ = c.u8_raster ? arena.allocate<std::uint8_t>(px) : Span<std::uint8_t>();
  if (slots_.empty() || values_.empty() || valid_.empty() || acc_.empty() || row_.empty() ||
      coverage_.empty() || (c.u8_raster && u8_.empty()))
    return Status(StatusCode::kCapacityExceeded, "arena too small for TileBuilder");
  cfg_ = c;
  reset();
  prev_x0_ = prev_y0_ = 0;
  prev_x1_ = prev_y1_ = -1;
  tiles_built_ = 0;
  tile_ = SonarTile{};
  ready_ = true;
  return Status::ok();
}

void TileBuilder::reset() noexcept {
  head_ = count_ = since_tile_ = 0;
  have_prev_pose_ = false;
  dist_m_ = 0.0;
  mean_step_m_ = 0.0;
  framing_started_ = false;
  next_end_m_ = last_end_m_ = 0.0;
  overflow_ = false;
}

void TileBuilder::set_next_stride_m(double stride_m) noexcept {
  if (!by_distance() || !framing_started_ || tiles_built_ == 0) return;
  if (!(std::isfinite(stride_m) && stride_m > 0.0 && stride_m <= 4.0 * cfg_.tile_stride_m)) return;
  next_end_m_ = last_end_m_ + stride_m;
}

int TileBuilder::first_in_tile(double start_m) const noexcept {
  int first = 0;
  while (first < count_ - 1 && slots_[ring(first)].dist_m < start_m) ++first;
  return first;
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
  const bool by_dist = by_distance();
  if (have_prev_pose_) {
    const double step = std::hypot(pose.x_m - prev_pose_.x_m, pose.y_m - prev_pose_.y_m);
    if (by_dist && mean_step_m_ > 0.0 && step < kFrozenStepFraction * mean_step_m_) {
      dist_m_ += mean_step_m_;  // no odometry: the pose is (all but) frozen, the pings go on
      counters_.increment(TileCounter::kFrozenPose);
    } else if (step > 0.0) {
      dist_m_ += step;
      if (step <= cfg_.max_gap_m) mean_step_m_ = mean_step_m_ > 0.0 ? 0.9 * mean_step_m_ + 0.1 * step : step;
    }
  }
  prev_pose_ = pose;
  have_prev_pose_ = true;
  if (by_dist && !framing_started_) {
    framing_started_ = true;
    next_end_m_ = dist_m_ + cfg_.tile_length_m;
  }
  if (count_ == N) {
    // The oldest scanline leaves the ring; by distance, the next tile may still have needed it.
    if (by_dist && slots_[ring(0)].dist_m >= next_end_m_ - cfg_.tile_length_m) overflow_ = true;
    head_ = (head_ + 1) % N;
    --count_;
  }
  const int i = count_++;
  Slot& s = slots_[ring(i)];
  s.pose = pose;
  s.stamp_ns = line.stamp_ns;
  s.ping = line.ping_number;
  s.dist_m = dist_m_;
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
  // Per side, the run of valid bins that starts at the first valid one (splat_side() needs no masks there).
  for (int side = 0; side < 2; ++side) {
    const std::uint8_t* k = side == 0 ? kp : ks;
    int lo = 0;
    while (lo < s.bins && k[lo] == 0) ++lo;
    int hi = lo;
    while (hi < s.bins && k[hi] != 0) ++hi;
    s.run_lo[side] = lo;
    s.run_hi[side] = hi;
  }
  ++since_tile_;
  if (by_dist) {
    if (dist_m_ < next_end_m_) return false;
    const int first = first_in_tile(dist_m_ - cfg_.tile_length_m);
    last_end_m_ = dist_m_;
    next_end_m_ += cfg_.tile_stride_m;
    if (next_end_m_ <= dist_m_) next_end_m_ = dist_m_ + cfg_.tile_stride_m;  // a jump past several boundaries: one tile
    if (count_ - first < 2) return false;  // one scanline after a jump: no tile
    if (overflow_) counters_.increment(TileCounter::kTileOverflow);
    overflow_ = false;
    QNAV_RETURN_IF_ERROR(build(first, count_ - first));
    since_tile_ = 0;
    return true;
  }
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
  if (by_distance()) {
    // The last tile_length_m of travel, when at least half a stride was travelled since the last tile.
    if (tiles_built_ > 0 && dist_m_ - last_end_m_ < 0.5 * cfg_.tile_stride_m) return false;
    const int first = first_in_tile(dist_m_ - cfg_.tile_length_m);
    if (count_ - first < min_scanlines || count_ - first < 2) return false;
    last_end_m_ = dist_m_;
    QNAV_RETURN_IF_ERROR(build(first, count_ - first));
    since_tile_ = 0;
    return true;
  }
  int n = since_tile_ + (cfg_.scanlines_per_tile - cfg_.scanline_stride);
  if (tiles_built_ == 0) n = since_tile_;
  if (n > count_) n = count_;
  if (n < min_scanlines || n < 2) return false;
  QNAV_RETURN_IF_ERROR(build(count_ - n, n));
  since_tile_ = 0;
  return true;
}

inline void TileBuilder::splat(float col, float row, float v) noexcept {
  // Bilinear splat of one sample at continuous pixel coordinates (pixel centres at +0.5). The
  // caller keeps the touched box (bb_*) up to date per line of samples.
  const float x = col - 0.5f, y = row - 0.5f;
  const int W = cfg_.tile_width_px, H = cfg_.tile_height_px;
  if (!(x >= -1.0f && y >= -1.0f && x < static_cast<float>(W) && y < static_cast<float>(H))) {
    ++clipped_;
    return;
  }
  const int x0 = static_cast<int>(x + 1.0f) - 1, y0 = static_cast<int>(y + 1.0f) - 1;  // floor for x >= -1
  const float ax = x - static_cast<float>(x0), ay = y - static_cast<float>(y0);
  const float w00 = (1 - ax) * (1 - ay), w10 = ax * (1 - ay), w01 = (1 - ax) * ay, w11 = ax * ay;
  if (x0 >= 0 && y0 >= 0 && x0 + 1 < W && y0 + 1 < H) {
    Acc* a = acc_.data() + static_cast<std::size_t>(y0) * static_cast<std::size_t>(W) + static_cast<std::size_t>(x0);
    Acc* c = a + W;
    a[0].sum += w00 * v;
    a[0].weight += w00;
    a[1].sum += w10 * v;
    a[1].weight += w10;
    c[0].sum += w01 * v;
    c[0].weight += w01;
    c[1].sum += w11 * v;
    c[1].weight += w11;
    return;
  }
  const int xs[4] = {x0, x0 + 1, x0, x0 + 1};
  const int ys[4] = {y0, y0, y0 + 1, y0 + 1};
  const float w[4] = {w00, w10, w01, w11};
  for (int k = 0; k < 4; ++k) {
    if (xs[k] < 0 || ys[k] < 0 || xs[k] >= W || ys[k] >= H) continue;
    Acc& a = acc_[static_cast<std::size_t>(ys[k]) * static_cast<std::size_t>(W) + static_cast<std::size_t>(xs[k])];
    a.sum += w[k] * v;
    a.weight += w[k];
  }
}

void TileBuilder::place_tile(int first, int count) noexcept {
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
      int lo = 0, hi = s.bins - 1;  // first and last valid bin (-1, -1: none)
      while (lo < s.bins && !k[lo]) ++lo;
      while (hi > lo && !k[hi]) --hi;
      if (lo == s.bins) lo = hi = -1;
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
}

void TileBuilder::clear_previous_box() noexcept {
  // Every buffer is zero outside the previous tile's touched box (init zeroes them all), so only
  // that box needs clearing. The accumulator was emptied by normalise(); what its bytes still hold
  // is the previous tile's intensity, in the same box of the intensity raster.
  const int W = cfg_.tile_width_px;
  if (prev_x1_ >= prev_x0_) {
    const std::size_t len = static_cast<std::size_t>(prev_x1_ - prev_x0_ + 1);
    for (int y = prev_y0_; y <= prev_y1_; ++y) {
      const std::size_t k = static_cast<std::size_t>(y) * static_cast<std::size_t>(W) + static_cast<std::size_t>(prev_x0_);
      std::memset(static_cast<void*>(intensity_ + k), 0, len * sizeof(float));  // 0.0f is all zero bytes
      std::fill(coverage_.data() + k, coverage_.data() + k + len, std::uint8_t{0});
      if (!u8_.empty()) std::fill(u8_.data() + k, u8_.data() + k + len, std::uint8_t{0});
    }
  }
}

void TileBuilder::splat_scanline(int i, int end) noexcept {
  const int W = cfg_.tile_width_px, H = cfg_.tile_height_px;
  // Sub-sample spacing of at most one pixel: the bilinear splat spreads each sample over 2 x 2
  // pixels, so one-pixel spacing leaves no pixel between samples without weight.
  const double step_m = cfg_.resolution_m;
  const double inv_res = inv_res_;
  const Slot& a = slots_[ring(i)];
  const bool has_next = i + 1 < end;
  const Slot* bslot = has_next ? &slots_[ring(i + 1)] : nullptr;
  int steps = 1;
  if (has_next) {
    const double d = (bslot->pose.translation() - a.pose.translation()).norm();
    if (d > cfg_.max_gap_m) {
      counters_.increment(TileCounter::kNavJump);
      bslot = nullptr;
    } else {
      // Steps such that the far-range bins advance at most one pixel per sub-step.
      const double reach = a.bins * static_cast<double>(a.bin_m);
      const double dh = std::fabs(wrap_angle_rad(bslot->pose.heading_rad - a.pose.heading_rad));
      const double move = d + dh * reach;
      const double want = std::ceil(move / step_m - 1e-3);
      steps = !(want >= 1.0) ? 1 : (want > static_cast<double>(cfg_.max_substeps) ? cfg_.max_substeps : static_cast<int>(want));
    }
  }
  // Pixels across one bin (float bin sizes), at most the raster's size: a bin wider than the tile
  // (a damaged ping's range) is not spread over more sub-steps than the tile has pixels.
  const int across_max = W > H ? W : H;
  const int across_px = floor_to_int_clamped(std::ceil(static_cast<double>(a.bin_m) / step_m - 1e-3));
  const int across = across_px > across_max ? across_max : across_px;
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
    for (int side = 0; side < 2; ++side) splat_side(i, side, bslot, t, c0, r0, sb, across);
  }
}

void TileBuilder::splat_side(int i, int side, const Slot* bslot, float t, double c0, double r0, const Vec2d& sb, int across) noexcept {
  const int W = cfg_.tile_width_px, H = cfg_.tile_height_px;
  const double inv_res = inv_res_;
  const Slot& a = slots_[ring(i)];
  const int bins = a.bins;
  const float* va = values(i, side);
  const std::uint8_t* ka = valid(i, side);
  const float* vb = bslot != nullptr && bslot->bins == bins ? values(i + 1, side) : nullptr;
  const std::uint8_t* kb = vb != nullptr ? valid(i + 1, side) : nullptr;
  // Per metre across track: d(col) = sign*sb.east/res, d(row) = -sign*sb.north/res.
  const double dc = side_sign(side) * sb.y() * inv_res;
  const double dr = -side_sign(side) * sb.x() * inv_res;
  bool inside;
  {
    // Touched box of this line of samples: its two ends (+1 pixel for the bilinear splat).
    const double reach = bins * static_cast<double>(a.bin_m);
    const double xa = c0 - 0.5, ya = r0 - 0.5, xb = c0 + reach * dc - 0.5, yb = r0 + reach * dr - 0.5;
    const int lx = floor_to_int_clamped(xa < xb ? xa : xb), hx = floor_to_int_clamped(xa < xb ? xb : xa) + 1;
    const int ly = floor_to_int_clamped(ya < yb ? ya : yb), hy = floor_to_int_clamped(ya < yb ? yb : ya) + 1;
    bb_x0_ = lx < bb_x0_ ? lx : bb_x0_;
    bb_y0_ = ly < bb_y0_ ? ly : bb_y0_;
    bb_x1_ = hx > bb_x1_ ? hx : bb_x1_;
    bb_y1_ = hy > bb_y1_ ? hy : bb_y1_;
    inside = lx >= 0 && ly >= 0 && hx < W && hy < H;
  }
  const float c0f = static_cast<float>(c0), r0f = static_cast<float>(r0);
  const float dcb = static_cast<float>(dc * static_cast<double>(a.bin_m));  // per bin
  const float drb = static_cast<float>(dr * static_cast<double>(a.bin_m));
  if (inside && across <= 1 && vb != nullptr) {
    // Fast path (the common case): the whole line lies inside the raster, one splat per bin.
    const float cx = c0f - 0.5f + 0.5f * dcb, cy = r0f - 0.5f + 0.5f * drb;
    Acc* base = acc_.data();
    // Bins [lo, hi) are valid on both lines (the overlap of their first runs, see push()): there the
    // value is always the interpolated one and no mask is read; the bins around it go through the masks.
    const int rlo = a.run_lo[side] > bslot->run_lo[side] ? a.run_lo[side] : bslot->run_lo[side];
    const int rhi = a.run_hi[side] < bslot->run_hi[side] ? a.run_hi[side] : bslot->run_hi[side];
    const int lo = rlo < rhi ? rlo : 0, hi = rlo < rhi ? rhi : 0;
    const BinRun run{va, vb, ka, kb, t, cx, cy, dcb, drb, lo, hi, bins, base, W};
    if (!kCarryColumn)
      splat_run_plain(run);
    else
      splat_run_carry(run);
    return;
  }
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
      const float g = static_cast<float>(b) + 0.5f;  // in bins
      splat(c0f + g * dcb, r0f + g * drb, v);
    } else {
      // Bin wider than a pixel: spread it across in sub-steps (constant value within the bin).
      for (int q = 0; q < across; ++q) {
        const float g = static_cast<float>(b) + (static_cast<float>(q) + 0.5f) / static_cast<float>(across);
        splat(c0f + g * dcb, r0f + g * drb, v);
      }
    }
  }
}

namespace {
// The value of each bin of a fast-path run (TileBuilder::BinRun) at its sub-step, handed with float(b)
// to put(bf, v) for every bin that has one: over [lo, hi) (valid on both lines) the interpolated value,
// no mask read; elsewhere by the masks: both lines valid: interpolated; this line only: its value; the
// next line only: its value from t >= 0.5; none: skipped. float(b) is counted (exact below 2^24: no
// int-to-float conversion, which goes through memory on SPARC V8). one: 1.0f (as a value the caller
// keeps in a register, see splat_run_plain).
template <class Run, class Put>
inline void for_each_bin_value(const Run& r, float one, Put&& put) noexcept {
  const float* va = r.va;
  const float* vb = r.vb;
  const std::uint8_t* ka = r.ka;
  const std::uint8_t* kb = r.kb;
  const float t = r.t, zero = one - one;
  const int lo = r.lo, hi = r.hi, bins = r.bins;
  const bool first_half = t < 0.5f;
  const auto masked = [&](int b) {
    const unsigned m = static_cast<unsigned>(ka[b]) | (static_cast<unsigned>(kb[b]) << 1);
    if (m == 0 || (m == 2 && first_half)) return -one;
    return m == 3 ? va[b] + t * (vb[b] - va[b]) : (m == 1 ? va[b] : vb[b]);
  };
  float bf = -one;
  int b = 0;
  for (; b < lo; ++b) {
    bf += one;
    const float v = masked(b);
    if (!(v < zero)) put(bf, v);
  }
  for (; b < hi; ++b) {
    bf += one;
    const float v = va[b] + t * (vb[b] - va[b]);
    if (!(v < zero)) put(bf, v);
  }
  for (; b < bins; ++b) {
    bf += one;
    const float v = masked(b);
    if (!(v < zero)) put(bf, v);
  }
}
}  // namespace

// splat_side's fast path without kCarryColumn (LEON3 and other targets without SIMD): one bilinear
// splat per bin straight into the accumulator.
void TileBuilder::splat_run_plain(const BinRun& r) const noexcept {
  const float cx = r.cx, cy = r.cy, dcb = r.dcb, drb = r.drb;
  const int W = r.W;
  Acc* base = r.base;
  // 1 as a value the compiler cannot fold (one_ is 1.0f): it keeps it (and 0) in registers instead
  // of loading the constants from the GOT each bin (four instructions each on a PIC SPARC build).
  const float one = one_;
  const auto put = [&](float bf, float v) {
    const float x = cx + bf * dcb, y = cy + bf * drb;
    const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);  // x, y >= 0 here
    const float ax = x - static_cast<float>(x0), ay = y - static_cast<float>(y0);
    Acc* q0 = base + static_cast<std::size_t>(y0) * static_cast<std::size_t>(W) + static_cast<std::size_t>(x0);
    Acc* q1 = q0 + W;
    const float w00 = (one - ax) * (one - ay), w10 = ax * (one - ay), w01 = (one - ax) * ay, w11 = ax * ay;
#if defined(__sparc__)
    // SPARC: a pixel's {sum, weight} is one aligned doubleword, moved by one ldd / std into and out
    // of an even/odd float register pair (4 instructions a pixel instead of 6; the compiler splits
    // the pair into two ld / st). The same additions of the same products as the portable code
    // below: the same sums bit for bit.
    const float s00 = w00 * v, s10 = w10 * v, s01 = w01 * v, s11 = w11 * v;
    double p00, p10, p01, p11;
    __asm__(
        "ldd [%6], %0\n\t"
        "ldd [%6+8], %1\n\t"
        "ldd [%7], %2\n\t"
        "ldd [%7+8], %3\n\t"
        "fadds %0, %8, %0\n\t"
        "fadds %R0, %9, %R0\n\t"
        "fadds %1, %10, %1\n\t"
        "fadds %R1, %11, %R1\n\t"
        "fadds %2, %12, %2\n\t"
        "fadds %R2, %13, %R2\n\t"
        "fadds %3, %14, %3\n\t"
        "fadds %R3, %15, %R3\n\t"
        "std %0, [%6]\n\t"
        "std %1, [%6+8]\n\t"
        "std %2, [%7]\n\t"
        "std %3, [%7+8]"
        : "=&f"(p00), "=&f"(p10), "=&f"(p01), "=&f"(p11), "+m"(*reinterpret_cast<Acc(*)[2]>(q0)),
          "+m"(*reinterpret_cast<Acc(*)[2]>(q1))
        : "r"(q0), "r"(q1), "f"(s00), "f"(w00), "f"(s10), "f"(w10), "f"(s01), "f"(w01), "f"(s11), "f"(w11));
#else
    q0[0].sum += w00 * v;
    q0[0].weight += w00;
    q0[1].sum += w10 * v;
    q0[1].weight += w10;
    q1[0].sum += w01 * v;
    q1[0].weight += w01;
    q1[1].sum += w11 * v;
    q1[1].weight += w11;
#endif
  };
  for_each_bin_value(r, one, put);
}

// splat_side's fast path with kCarryColumn (hosts with SIMD): the column two neighbouring splats share
// is kept in registers.
void TileBuilder::splat_run_carry(const BinRun& r) const noexcept {
  const float cx = r.cx, cy = r.cy, dcb = r.dcb, drb = r.drb;
  const int W = r.W;
  Acc* base = r.base;
  // Along a row the next bin's splat usually shares a column of two pixels with this one (the
  // line moves one pixel a bin). With kCarryColumn that column is kept in registers ("pending")
  // until the next splat has added to it, instead of a store the next 16-byte load only half
  // overlaps (no store forwarding: that stall was most of the host's build). Every pixel receives
  // the same additions in the same order as splatting into memory one bin at a time, so the sums
  // are the same bit for bit.
  const bool east = dcb >= 0.0f;  // the shared column: the left one moving east, the right one west
  Acc* pending = nullptr;         // top pixel of the column kept in p0 (row y0) and p1 (row y0 + 1)
  Acc p0{0.0f, 0.0f}, p1{0.0f, 0.0f};
  const auto put = [&](float bf, float v) {
    const float x = cx + bf * dcb, y = cy + bf * drb;
    const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);  // x, y >= 0 here
    const float ax = x - static_cast<float>(x0), ay = y - static_cast<float>(y0);
    Acc* q0 = base + static_cast<std::size_t>(y0) * static_cast<std::size_t>(W) + static_cast<std::size_t>(x0);
    const float w00 = (1 - ax) * (1 - ay), w10 = ax * (1 - ay), w01 = (1 - ax) * ay, w11 = ax * ay;
    Acc* shared = east ? q0 : q0 + 1;  // the column the previous splat may have left pending
    Acc* fresh = east ? q0 + 1 : q0;   // the column the next splat may share
    const float ws0 = east ? w00 : w10, ws1 = east ? w01 : w11, wf0 = east ? w10 : w00, wf1 = east ? w11 : w01;
    Acc s0, s1;
    if (shared == pending) {
      s0 = p0;
      s1 = p1;
    } else {
      if (pending != nullptr) {
        pending[0] = p0;
        pending[W] = p1;
      }
      s0 = shared[0];
      s1 = shared[W];
    }
    Acc f0 = fresh[0], f1 = fresh[W];
    s0.sum += ws0 * v;
    s0.weight += ws0;
    f0.sum += wf0 * v;
    f0.weight += wf0;
    s1.sum += ws1 * v;
    s1.weight += ws1;
    f1.sum += wf1 * v;
    f1.weight += wf1;
    shared[0] = s0;
    shared[W] = s1;
    pending = fresh;
    p0 = f0;
    p1 = f1;
  };
  for_each_bin_value(r, 1.0f, put);
  if (pending != nullptr) {
    pending[0] = p0;
    pending[W] = p1;
  }
}

std::size_t TileBuilder::normalise() noexcept {
  // The box in locals: the u8 stores may alias members, which would otherwise be reloaded per pixel.
  const int bx0 = bb_x0_, bx1 = bb_x1_, by0 = bb_y0_, by1 = bb_y1_;
  // Normalise, mark coverage, count it and quantise to the u8 raster in one pass over the box.
  // Branch-free: an empty pixel divides 0 by 1 (intensity 0, u8 0). fill_holes() later sets the u8
  // of the pixels it fills, so the u8 raster is the quantised final intensity everywhere.
  // Row by row; each accumulator row is emptied after it is read (the next tile starts from zero).
  // The intensity raster overlays the accumulator's first half: intensity row y
  // lies over accumulator pixels [(y W) / 2, ((y + 1) W) / 2), all in rows before y for y >= 1 (and
  // in row 0, already read, for y = 0): rows this loop has read and emptied, or rows outside the box,
  // which hold zero and are not read. So every byte of the block outside the intensity box is zero
  // afterwards, as the tile's intensity view needs.
  const int W = cfg_.tile_width_px;
  const float eps = 1e-3f;
  const float scale = 255.0f / cfg_.display_max;
  // 1, 0.5, 0 and 255 as values the compiler cannot fold (see one_): kept in registers, not reloaded
  // from the GOT per pixel (and after each u8 store: a byte store may alias anything).
  const float one = one_, half = 0.5f * one, zero = one - one, top = 255.0f * one;
  if (bx1 < bx0) return 0;
  const std::size_t len = static_cast<std::size_t>(bx1 - bx0 + 1);
  float* tmp = row_.data();
  std::size_t covered = 0;
  for (int y = by0; y <= by1; ++y) {
    const std::size_t row = static_cast<std::size_t>(y) * static_cast<std::size_t>(W);
    const Acc* acc = acc_.data() + row;
    std::uint8_t* cov = coverage_.data() + row;
    std::uint32_t row_covered = 0;
    // Row 0's intensity overlays its own accumulator row: it goes through row_. Any other row's
    // intensity lies over accumulator rows before it ((y + 1) W / 2 <= y W for y >= 1), already
    // emptied or outside the box, and is written in place.
    float* out_f = y == 0 ? tmp : intensity_ + row;
    if (!kCarryColumn && !u8_.empty()) {
      // Without SIMD (LEON3) one loop does both: the intensity is quantised while in a register,
      // not re-read by a second loop.
      std::uint8_t* out = u8_.data() + row;
      // Branching on the coverage (no selects on SPARC V8): an empty pixel is 0 / 1 = 0, u8 0.
      for (int x = bx0; x <= bx1; ++x) {
        const float w = acc[x].weight;
        if (w > eps) {
          const float f = acc[x].sum / w;
          out_f[x] = f;
          cov[x] = 1;
          ++row_covered;
          float u = f * scale + half;
          u = u < zero ? zero : (u > top ? top : u);
          out[x] = static_cast<std::uint8_t>(static_cast<std::int32_t>(u));
        } else {
          out_f[x] = zero;
          cov[x] = 0;
          out[x] = 0;
        }
      }
      covered += row_covered;
      std::memset(static_cast<void*>(acc_.data() + row + bx0), 0, len * sizeof(Acc));
      if (y == 0) std::copy(tmp + bx0, tmp + bx0 + len, intensity_ + row + static_cast<std::size_t>(bx0));
      continue;
    }
    for (int x = bx0; x <= bx1; ++x) {
      const bool c = acc[x].weight > eps;
      out_f[x] = (c ? acc[x].sum : zero) / (c ? acc[x].weight : one);
      cov[x] = c ? 1 : 0;
      row_covered += c ? 1u : 0u;
    }
    covered += row_covered;
    if (!u8_.empty()) {
      std::uint8_t* out = u8_.data() + row;
      for (int x = bx0; x <= bx1; ++x) {
        float u = out_f[x] * scale + half;
        u = u < zero ? zero : (u > top ? top : u);
        out[x] = static_cast<std::uint8_t>(static_cast<std::int32_t>(u));
      }
    }
    std::memset(static_cast<void*>(acc_.data() + row + bx0), 0, len * sizeof(Acc));  // Acc{0, 0} is all zero bytes
    if (y == 0) std::copy(tmp + bx0, tmp + bx0 + len, intensity_ + row + static_cast<std::size_t>(bx0));
  }
  return covered;
}

void TileBuilder::finish_tile(int first, int count, std::size_t covered) noexcept {
  const int W = cfg_.tile_width_px, H = cfg_.tile_height_px;
  const std::size_t px = static_cast<std::size_t>(W) * static_cast<std::size_t>(H);
  prev_x0_ = bb_x0_;
  prev_y0_ = bb_y0_;
  prev_x1_ = bb_x1_;
  prev_y1_ = bb_y1_;
  counters_.increment(TileCounter::kClippedSplat, clipped_);
  const Slot& f = slots_[ring(first)];
  const Slot& l = slots_[ring(first + count - 1)];
  const Slot& m = slots_[ring(first + count / 2)];
  tile_.index = tiles_built_;
  tile_.intensity = ConstImageViewF32::unchecked(intensity_, W, H, W);
  tile_.intensity_u8 = u8_.empty() ? ConstImageViewU8{} : ConstImageViewU8::unchecked(u8_.data(), W, H, W);
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
}

Status TileBuilder::build(int first, int count) noexcept {
  // Place the raster on the swath, clear what the previous tile left, splat every scanline (and
  // its sub-steps toward the next), then normalise (and quantise) and fill holes inside the touched box.
  const int W = cfg_.tile_width_px, H = cfg_.tile_height_px;
  place_tile(first, count);
  clear_previous_box();
  bb_x0_ = W;
  bb_y0_ = H;
  bb_x1_ = -1;
  bb_y1_ = -1;
  clipped_ = 0;
  inv_res_ = 1.0 / cfg_.resolution_m;
  for (int i = first; i < first + count; ++i) splat_scanline(i, first + count);
  // Touched box, clipped to the raster (every later pass works inside it only).
  if (bb_x0_ < 0) bb_x0_ = 0;
  if (bb_y0_ < 0) bb_y0_ = 0;
  if (bb_x1_ > W - 1) bb_x1_ = W - 1;
  if (bb_y1_ > H - 1) bb_y1_ = H - 1;
  std::size_t covered = normalise();
  if (cfg_.hole_fill_radius_px > 0) {
    const HoleFillRaster raster{intensity_, coverage_.data(), u8_.empty() ? nullptr : u8_.data(), W};
    covered += fill_holes(raster, RasterBox{bb_x0_, bb_y0_, bb_x1_, bb_y1_}, cfg_.hole_fill_radius_px,
                          cfg_.hole_fill_min_neighbours, 255.0f / cfg_.display_max);  // normalise()'s u8 scale
  }
  finish_tile(first, count, covered);
  return Status::ok();
}


}  // namespace qnav::sonar
