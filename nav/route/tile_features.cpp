#include "nav/route/tile_features.hpp"

#include <cmath>

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

Status TileFeatureExtractor::extract(ConstImageViewF32 in, ConstImageViewU8 cov, const TileGeometry& g, RouteNode& out) noexcept {
  out.keypoints.clear();
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
  auto fine_covered = [&](int x, int y) { return (cov.empty() || cov(x, y) != 0) && std::isfinite(in(x, y)); };
  // Block average over covered pixels; a coarse pixel is covered when >= half its pixels are.
  ImageViewF32 wk = ImageViewF32::unchecked(work_.data(), w, h, w);
  ImageViewF32 tp = ImageViewF32::unchecked(tmp_.data(), w, h, w);
  ImageView<std::uint8_t> cv = ImageView<std::uint8_t>::unchecked(cov_.data(), w, h, w);
  double sum = 0.0;
  std::size_t n = 0;
  const int need = (f * f + 1) / 2;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      float s = 0.0f;
      int k = 0;
      for (int yy = y * f; yy < (y + 1) * f; ++yy)
        for (int xx = x * f; xx < (x + 1) * f; ++xx)
          if (fine_covered(xx, yy)) {
            s += in(xx, yy);
            ++k;
          }
      cv(x, y) = k >= need ? 1 : 0;
      wk(x, y) = k > 0 ? s / static_cast<float>(k) : 0.0f;
      if (k >= need) {
        sum += static_cast<double>(wk(x, y));
        ++n;
      }
    }
  if (n == 0) {
    counters_.increment(FeatureCounter::kEmptyTile);
    return Status(StatusCode::kEmpty, "tile features: tile has no covered pixel");
  }
  const float mean = static_cast<float>(sum / static_cast<double>(n));
  auto covered = [&](int x, int y) { return cv(x, y) != 0; };
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      if (!covered(x, y)) wk(x, y) = mean;
  const int r = config_.blur_radius_px;
  if (r > 0) {
    const float inv = 1.0f / static_cast<float>(2 * r + 1);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        float s = 0.0f;
        for (int k = -r; k <= r; ++k) {
          int xx = x + k;
          xx = xx < 0 ? 0 : (xx >= w ? w - 1 : xx);
          s += wk(xx, y);
        }
        tp(x, y) = s * inv;
      }
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        float s = 0.0f;
        for (int k = -r; k <= r; ++k) {
          int yy = y + k;
          yy = yy < 0 ? 0 : (yy >= h ? h - 1 : yy);
          s += tp(x, yy);
        }
        wk(x, y) = s * inv;
      }
  }
  BoundedVector<vision::Corner> corners(corners_);
  QNAV_RETURN_IF_ERROR(harris_.detect(ConstImageViewF32(wk), corners));

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
