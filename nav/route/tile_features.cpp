#include "nav/route/tile_features.hpp"

#include <cmath>
#include <cstring>

namespace qnav::route {

namespace {
// The planes are the downsampled tile's: max_width / downsample x max_height / downsample.
int coarse(int side, int downsample) noexcept { return downsample >= 1 ? side / downsample : side; }

vision::HarrisConfig harris_config(const TileFeatureConfig& c) noexcept {
  vision::HarrisConfig h;
  h.max_width = coarse(c.max_width, c.downsample);
  h.max_height = coarse(c.max_height, c.downsample);
  h.max_corners = static_cast<int>(c.max_keypoints * 4);
  h.block_radius = c.harris_block_radius;
  h.nms_radius = c.harris_nms_radius;
  h.border_px = 4 * c.descriptor_step_px + 2;
  if (h.border_px < c.harris_block_radius + 1) h.border_px = c.harris_block_radius + 1;
  h.norm_cell_px = c.harris_norm_cell_px;
  h.quality_level = 1e-7f;  // keep weak corners: the normalised score, not the raw response, ranks them
  return h;
}
}  // namespace

std::size_t TileFeatureExtractor::arena_bytes(const TileFeatureConfig& c) noexcept {
  const std::size_t px = static_cast<std::size_t>(coarse(c.max_width, c.downsample)) * static_cast<std::size_t>(coarse(c.max_height, c.downsample));
  return 2 * px * sizeof(float) + px + c.max_keypoints * 4 * sizeof(vision::Corner) + vision::HarrisDetector::arena_bytes(harris_config(c)) + 256;
}

Status TileFeatureExtractor::init(const TileFeatureConfig& c, Arena& arena) noexcept {
  if (c.max_width <= 0 || c.max_height <= 0 || c.max_width > kMaxImageSide || c.max_height > kMaxImageSide ||
      c.max_keypoints == 0 || c.max_keypoints > kMaxKeypointsPerNode || c.descriptor_step_px < 1 || c.blur_radius_px < 0 ||
      c.downsample < 1 || c.downsample > 16 ||
      c.blur_radius_px > 8)
    return Status(StatusCode::kInvalidArgument, "tile features: bad configuration");
  QNAV_RETURN_IF_ERROR(harris_.init(harris_config(c), arena));
  const std::size_t px = static_cast<std::size_t>(coarse(c.max_width, c.downsample)) * static_cast<std::size_t>(coarse(c.max_height, c.downsample));
  work_ = arena.allocate<float>(px);
  tmp_ = arena.allocate<float>(px);
  cov_ = arena.allocate<std::uint8_t>(px);
  corners_ = arena.allocate<vision::Corner>(c.max_keypoints * 4);
  if (work_.empty() || tmp_.empty() || cov_.empty() || corners_.empty()) return Status(StatusCode::kCapacityExceeded, "tile features: arena too small");
  config_ = c;
  ready_ = true;
  return Status::ok();
}

namespace {
// True when the float stored at p is neither inf nor NaN, read by its exponent bits (an integer load:
// no float compare sequence, and no float -> integer move through memory on SPARC V8).
inline bool finite_at(const float* p) noexcept {
  std::uint32_t b;
  std::memcpy(&b, __builtin_assume_aligned(p, alignof(float)), sizeof b);  // one word load, not four bytes
  return (b & 0x7f800000u) != 0x7f800000u;
}

// Block average over covered pixels (covered: coverage non-zero, or no coverage plane, and a finite
// intensity); a coarse pixel is covered when >= half its pixels are. Each coarse pixel sums its
// pixels row by row, left to right, from 0.0f (the order the result depends on). sum / n: the
// covered coarse pixels' values, for the mean. F: the factor when fixed at compile time (the loops
// unroll), 0 = f.
template <int F>
void block_average_f(ConstImageViewF32 in, ConstImageViewU8 cov, int f_runtime, ImageViewF32 wk, ImageView<std::uint8_t> cv,
                     double& sum, std::size_t& n) noexcept {
  const int f = F > 0 ? F : f_runtime;
  const int w = wk.width(), h = wk.height();
  const int need = (f * f + 1) / 2;
  const bool all_covered = cov.empty();
  for (int y = 0; y < h; ++y) {
    float* wr = wk.row(y);
    std::uint8_t* cr = cv.row(y);
    for (int x = 0; x < w; ++x) {
      float s = 0.0f;
      int k = 0;
      for (int yy = 0; yy < f; ++yy) {
        const float* ir = in.row(y * f + yy) + x * f;
        const std::uint8_t* fr = all_covered ? nullptr : cov.row(y * f + yy) + x * f;
        for (int t = 0; t < f; ++t)
          if ((all_covered || fr[t] != 0) && finite_at(ir + t)) {
            s += ir[t];
            ++k;
          }
      }
      cr[x] = k >= need ? 1 : 0;
      wr[x] = k > 0 ? s / static_cast<float>(k) : 0.0f;
      if (k >= need) {
        sum += static_cast<double>(wr[x]);
        ++n;
      }
    }
  }
}

// Separable box blur of radius r (edges clamped), wk -> tp along rows, tp -> wk along columns. Each
// output sums its 2r + 1 inputs from 0.0f in offset order -r..r, then scales by 1 / (2r + 1):
// interior pixels skip the clamping, columns run a row at a time. R: the radius when fixed at
// compile time (the tap loops unroll), 0 = r.
template <int R>
void box_blur_r(ImageViewF32 wk, ImageViewF32 tp, int r_runtime) noexcept {
  const int r = R > 0 ? R : r_runtime;
  const int w = wk.width(), h = wk.height();
  const float inv = 1.0f / static_cast<float>(2 * r + 1);
  const auto clamp = [](int v, int hi) { return v < 0 ? 0 : (v > hi ? hi : v); };
  for (int y = 0; y < h; ++y) {
    const float* src = wk.row(y);
    float* dst = tp.row(y);
    const int lo = r < w ? r : w, hi = w - r > lo ? w - r : lo;  // [lo, hi): no clamping needed
    for (int x = 0; x < lo; ++x) {
      float s = 0.0f;
      for (int k = -r; k <= r; ++k) s += src[clamp(x + k, w - 1)];
      dst[x] = s * inv;
    }
    for (int x = lo; x < hi; ++x) {
      float s = 0.0f;
      for (int k = -r; k <= r; ++k) s += src[x + k];
      dst[x] = s * inv;
    }
    for (int x = hi; x < w; ++x) {
      float s = 0.0f;
      for (int k = -r; k <= r; ++k) s += src[clamp(x + k, w - 1)];
      dst[x] = s * inv;
    }
  }
  const float* rows[2 * 8 + 1];  // blur_radius_px <= 8 (init)
  for (int y = 0; y < h; ++y) {
    for (int k = -r; k <= r; ++k) rows[k + r] = tp.row(clamp(y + k, h - 1));
    float* dst = wk.row(y);
    for (int x = 0; x < w; ++x) {
      float s = 0.0f;
      for (int k = 0; k <= 2 * r; ++k) s += rows[k][x];
      dst[x] = s * inv;
    }
  }
}
}  // namespace

void TileFeatureExtractor::block_average(ConstImageViewF32 in, ConstImageViewU8 cov, ImageViewF32 wk,
                                         ImageView<std::uint8_t> cv, double& sum, std::size_t& n) const noexcept {
  switch (config_.downsample) {  // the factors route_defaults and camera_tile_pipeline use, unrolled
    case 1: return block_average_f<1>(in, cov, 1, wk, cv, sum, n);
    case 2: return block_average_f<2>(in, cov, 2, wk, cv, sum, n);
    case 3: return block_average_f<3>(in, cov, 3, wk, cv, sum, n);
    case 4: return block_average_f<4>(in, cov, 4, wk, cv, sum, n);
    default: return block_average_f<0>(in, cov, config_.downsample, wk, cv, sum, n);
  }
}

void TileFeatureExtractor::box_blur(ImageViewF32 wk, ImageViewF32 tp) const noexcept {
  switch (config_.blur_radius_px) {
    case 0: return;
    case 1: return box_blur_r<1>(wk, tp, 1);
    case 2: return box_blur_r<2>(wk, tp, 2);
    default: return box_blur_r<0>(wk, tp, config_.blur_radius_px);
  }
}

Status TileFeatureExtractor::extract(ConstImageViewF32 in, ConstImageViewU8 cov, const TileGeometry& g, RouteNode& out) noexcept {
  out.keypoints.clear();
  plane_w_ = plane_h_ = 0;
  if (!ready_) return Status(StatusCode::kNotReady, "tile features: not initialised");
  if (in.empty() || in.width() > config_.max_width || in.height() > config_.max_height ||
      (!cov.empty() && (cov.width() != in.width() || cov.height() != in.height())) || !(g.resolution_m > 0.0) ||
      !std::isfinite(g.resolution_m) || !g.pose.is_finite() || !std::isfinite(g.origin_north_m) || !std::isfinite(g.origin_east_m)) {
    counters_.increment(FeatureCounter::kBadTile);
    return Status(StatusCode::kInvalidArgument, "tile features: bad tile or geometry");
  }
  const int f = config_.downsample;
  const int w = in.width() / f, h = in.height() / f;
  if (w < 16 || h < 16) {
    counters_.increment(FeatureCounter::kBadTile);
    return Status(StatusCode::kInvalidArgument, "tile features: tile too small for the downsample factor");
  }
  ImageViewF32 wk = ImageViewF32::unchecked(work_.data(), w, h, w);
  ImageViewF32 tp = ImageViewF32::unchecked(tmp_.data(), w, h, w);
  ImageView<std::uint8_t> cv = ImageView<std::uint8_t>::unchecked(cov_.data(), w, h, w);
  double sum = 0.0;
  std::size_t n = 0;
  block_average(in, cov, wk, cv, sum, n);
  if (n == 0) {
    counters_.increment(FeatureCounter::kEmptyTile);
    return Status(StatusCode::kEmpty, "tile features: tile has no covered pixel");
  }
  const float mean = static_cast<float>(sum / static_cast<double>(n));
  for (int y = 0; y < h; ++y) {
    float* wr = wk.row(y);
    const std::uint8_t* cr = cv.row(y);
    for (int x = 0; x < w; ++x)
      if (cr[x] == 0) wr[x] = mean;
  }
  box_blur(wk, tp);
  plane_w_ = w;
  plane_h_ = h;
  BoundedVector<vision::Corner> corners(corners_);
  QNAV_RETURN_IF_ERROR(harris_.detect(ConstImageViewF32(wk), corners));

  auto covered = [&](int x, int y) { return cv(x, y) != 0; };
  const int step = config_.descriptor_step_px;
  const Pose2 inv_pose = g.pose.inverse();
  for (const vision::Corner& c : corners) {
    if (out.keypoints.size() >= config_.max_keypoints) break;
    // Descriptor samples (bilinear on the smoothed plane), all inside covered pixels.
    float samples[kDescriptorBytes];
    bool ok = true;
    for (int j = 0; j < kDescriptorSide && ok; ++j)
      for (int i = 0; i < kDescriptorSide && ok; ++i) {
        const float sx = c.x + (static_cast<float>(i) - 3.5f) * static_cast<float>(step);
        const float sy = c.y + (static_cast<float>(j) - 3.5f) * static_cast<float>(step);
        const int x0 = static_cast<int>(std::floor(sx)), y0 = static_cast<int>(std::floor(sy));
        if (x0 < 0 || y0 < 0 || x0 + 1 >= w || y0 + 1 >= h || !covered(x0, y0) || !covered(x0 + 1, y0 + 1) ||
            !covered(x0 + 1, y0) || !covered(x0, y0 + 1)) {
          ok = false;
          break;
        }
        const float fx = sx - static_cast<float>(x0), fy = sy - static_cast<float>(y0);
        samples[j * kDescriptorSide + i] = (1 - fx) * (1 - fy) * wk(x0, y0) + fx * (1 - fy) * wk(x0 + 1, y0) +
                                           (1 - fx) * fy * wk(x0, y0 + 1) + fx * fy * wk(x0 + 1, y0 + 1);
      }
    if (!ok) {
      counters_.increment(FeatureCounter::kFootprintUncovered);
      continue;
    }
    double m = 0.0, v = 0.0;
    for (float s : samples) m += static_cast<double>(s);
    m /= static_cast<double>(kDescriptorBytes);
    for (float s : samples) v += (static_cast<double>(s) - m) * (static_cast<double>(s) - m);
    const double sd = std::sqrt(v / static_cast<double>(kDescriptorBytes));
    if (!(sd > 1e-6)) continue;
    RouteKeypoint* kp = out.keypoints.emplace_back();
    if (kp == nullptr) break;
    for (std::size_t i = 0; i < kDescriptorBytes; ++i) {
      double q = (static_cast<double>(samples[i]) - m) / sd * 32.0;
      q = q > 127.0 ? 127.0 : (q < -127.0 ? -127.0 : q);
      kp->descriptor[i] = static_cast<std::int8_t>(std::lround(q));
    }
    const double north = g.origin_north_m - (static_cast<double>(c.y) + 0.5) * f * g.resolution_m;
    const double east = g.origin_east_m + (static_cast<double>(c.x) + 0.5) * f * g.resolution_m;
    const Vec2d t = inv_pose.apply(Vec2d(north, east));
    kp->x_m = static_cast<float>(t.x());
    kp->y_m = static_cast<float>(t.y());
    kp->score = c.score;
  }
  out.meta.pose = g.pose;
  out.meta.keypoint_count = static_cast<std::uint16_t>(out.keypoints.size());
  return Status::ok();
}

}  // namespace qnav::route
