#include "nav/vision/stereo.hpp"

#include <cmath>

namespace qnav::vision {

namespace {
constexpr int kMaxPatchRadius = 7;
constexpr int kMaxPatch = (2 * kMaxPatchRadius + 1) * (2 * kMaxPatchRadius + 1);

bool finite_pos(double v) noexcept { return std::isfinite(v) && v > 0.0; }

// ZNCC of a zero-mean template t (n values, sum of squares tss) against the patch of `img` whose
// top-left corner is (x0, y0), side s. Returns -1 when the patch is flat (variance <= min_var).
inline float zncc_at(const float* t, float tss, ConstImageViewU8 img, int x0, int y0, int s, float min_var_n) noexcept {
  float sum = 0.0f, sq = 0.0f, cross = 0.0f;
  int k = 0;
  for (int j = 0; j < s; ++j) {
    const std::uint8_t* row = img.row(y0 + j) + x0;
    for (int i = 0; i < s; ++i, ++k) {
      const float v = static_cast<float>(row[i]);
      sum += v;
      sq += v * v;
      cross += t[k] * v;
    }
  }
  const float n = static_cast<float>(s * s);
  const float var_n = sq - sum * sum / n;  // n * variance
  if (!(var_n > min_var_n)) return -1.0f;
  const float z = cross / std::sqrt(tss * var_n);
  return z > 1.0f ? 1.0f : (z < -1.0f ? -1.0f : z);
}

// Loads the zero-mean patch centred at (xc, yc); returns n * variance.
inline float load_template(ConstImageViewU8 img, int xc, int yc, int r, float* t) noexcept {
  const int s = 2 * r + 1;
  float sum = 0.0f;
  int k = 0;
  for (int j = 0; j < s; ++j) {
    const std::uint8_t* row = img.row(yc - r + j) + (xc - r);
    for (int i = 0; i < s; ++i, ++k) {
      t[k] = static_cast<float>(row[i]);
      sum += t[k];
    }
  }
  const float mean = sum / static_cast<float>(s * s);
  float ss = 0.0f;
  for (int i = 0; i < k; ++i) {
    t[i] -= mean;
    ss += t[i] * t[i];
  }
  return ss;
}
}  // namespace

bool triangulate(const StereoCamera& cam, float x_px, float y_px, float disparity_px, Vec3f& p_m) noexcept {
  if (!(disparity_px > 0.0f) || !std::isfinite(x_px) || !std::isfinite(y_px)) return false;
  if (!finite_pos(cam.focal_px) || !finite_pos(cam.baseline_m)) return false;
  const double z = cam.baseline_m * cam.focal_px / static_cast<double>(disparity_px);
  const double x = (static_cast<double>(x_px) - cam.cu_px) * z / cam.focal_px;
  const double y = (static_cast<double>(y_px) - cam.cv_px) * z / cam.focal_px;
  if (!std::isfinite(z) || !std::isfinite(x) || !std::isfinite(y)) return false;
  p_m = Vec3f(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z));
  return true;
}

float depth_sigma_m(const StereoCamera& cam, float z_m, float disparity_sigma_px) noexcept {
  const double bf = cam.baseline_m * cam.focal_px;
  if (!(bf > 0.0)) return 0.0f;
  return static_cast<float>(static_cast<double>(z_m) * static_cast<double>(z_m) / bf * static_cast<double>(disparity_sigma_px));
}

Status StereoMatcher::init(const StereoConfig& c, const StereoCamera& cam) noexcept {
  ready_ = false;
  const char* err = nullptr;
  if (c.patch_radius < 1 || c.patch_radius > kMaxPatchRadius) err = "stereo: patch_radius must be 1..7";
  else if (c.min_disparity_px < 0 || c.max_disparity_px < c.min_disparity_px + 2) err = "stereo: disparity range needs min >= 0 and max >= min + 2";
  else if (c.max_disparity_px - c.min_disparity_px + 1 > kMaxDisparityRange) err = "stereo: disparity range too large";
  else if (!(c.min_zncc > -1.0f && c.min_zncc <= 1.0f)) err = "stereo: min_zncc must be in (-1, 1]";
  else if (!(c.uniqueness_margin >= 0.0f && c.uniqueness_margin < 2.0f)) err = "stereo: uniqueness_margin must be in [0, 2)";
  else if (!(c.left_right_tolerance_px >= 0.0f && c.left_right_tolerance_px < 100.0f)) err = "stereo: bad left_right_tolerance_px";
  else if (!(c.min_patch_stddev >= 0.0f && c.min_patch_stddev < 128.0f)) err = "stereo: bad min_patch_stddev";
  else if (!(c.disparity_sigma_px > 0.0f && c.disparity_sigma_px < 100.0f)) err = "stereo: disparity_sigma_px must be > 0";
  else if (!finite_pos(cam.focal_px) || !finite_pos(cam.baseline_m) || !std::isfinite(cam.cu_px) || !std::isfinite(cam.cv_px))
    err = "stereo: camera needs finite focal_px > 0, baseline_m > 0 and a finite principal point";
  if (err != nullptr) {
    counters_.increment(VisionCounter::kBadConfig);
    return Status(StatusCode::kInvalidArgument, err);
  }
  config_ = c;
  camera_ = cam;
  ready_ = true;
  return Status::ok();
}

Status StereoMatcher::match_one(ConstImageViewU8 left, ConstImageViewU8 right, float x_px, float y_px, float& disparity_px,
                                float& zncc) noexcept {
  if (!ready_) return Status(StatusCode::kNotReady, "stereo: match before init");
  if (left.empty() || right.empty() || left.width() != right.width() || left.height() != right.height()) {
    counters_.increment(VisionCounter::kBadImage);
    return Status(StatusCode::kInvalidArgument, "stereo: images empty or of different sizes");
  }
  const int r = config_.patch_radius, s = 2 * r + 1;
  const int W = left.width(), H = left.height();
  if (!std::isfinite(x_px) || !std::isfinite(y_px) || x_px < 0.0f || y_px < 0.0f || x_px > W || y_px > H) {
    counters_.increment(VisionCounter::kStereoOutOfBounds);
    return Status(StatusCode::kOutOfRange, "stereo: corner outside the image");
  }
  const int xi = static_cast<int>(std::lround(x_px)), yi = static_cast<int>(std::lround(y_px));
  const int dmin = config_.min_disparity_px;
  // Right patch must lie inside: xi - d - r >= 0.
  const int dmax = config_.max_disparity_px < xi - r ? config_.max_disparity_px : xi - r;
  if (yi < r || yi >= H - r || xi < r || xi >= W - r || xi - r - dmin < 0 || dmax < dmin + 2) {
    counters_.increment(VisionCounter::kStereoOutOfBounds);
    return Status(StatusCode::kOutOfRange, "stereo: patch or disparity range leaves the image");
  }
  float t[kMaxPatch];
  const float n = static_cast<float>(s * s);
  const float min_var_n = config_.min_patch_stddev * config_.min_patch_stddev * n;
  const float tss = load_template(left, xi, yi, r, t);
  if (!(tss > min_var_n)) {
    counters_.increment(VisionCounter::kStereoFlatPatch);
    return Status(StatusCode::kDegenerate, "stereo: left patch has no texture");
  }
  const int nd = dmax - dmin + 1;
  int best = -1;
  float best_v = -2.0f;
  for (int i = 0; i < nd; ++i) {
    const float v = zncc_at(t, tss, right, xi - (dmin + i) - r, yi - r, s, min_var_n);
    scores_[i] = v;
    if (v > best_v) {
      best_v = v;
      best = i;
    }
  }
  if (best_v < config_.min_zncc) {
    counters_.increment(VisionCounter::kStereoWeak);
    return Status(StatusCode::kNotFound, "stereo: best correlation below min_zncc");
  }
  if (best == 0 || best == nd - 1) {
    counters_.increment(VisionCounter::kStereoEdgeOfRange);
    return Status(StatusCode::kNotFound, "stereo: best disparity on the edge of the search range");
  }
  // Uniqueness: the best other local maximum (not adjacent to the best) must be clearly lower.
  float second = -2.0f;
  for (int i = 0; i < nd; ++i) {
    if (i >= best - 1 && i <= best + 1) continue;
    const bool peak = (i == 0 || scores_[i] >= scores_[i - 1]) && (i == nd - 1 || scores_[i] >= scores_[i + 1]);
    if (peak && scores_[i] > second) second = scores_[i];
  }
  if (second > best_v - config_.uniqueness_margin) {
    counters_.increment(VisionCounter::kStereoAmbiguous);
    return Status(StatusCode::kNotFound, "stereo: ambiguous match (second peak too close)");
  }
  const int dbest = dmin + best;
  // Sub-pixel: parabola through the three scores around the best.
  const float sl = scores_[best - 1], sc = scores_[best], sr = scores_[best + 1];
  const float den = sl - 2.0f * sc + sr;
  float off = den < 0.0f ? 0.5f * (sl - sr) / den : 0.0f;
  off = off > 0.5f ? 0.5f : (off < -0.5f ? -0.5f : off);

  if (config_.left_right_check) {
    const int xr = xi - dbest;
    float rt[kMaxPatch];
    const float rss = load_template(right, xr, yi, r, rt);
    if (!(rss > min_var_n)) {
      counters_.increment(VisionCounter::kStereoFlatPatch);
      return Status(StatusCode::kDegenerate, "stereo: right patch has no texture");
    }
    const int lmax = xr + config_.max_disparity_px < W - 1 - r ? xr + config_.max_disparity_px : W - 1 - r;
    int lbest = xi;
    float lbest_v = -2.0f;
    for (int xl = xr + dmin; xl <= lmax; ++xl) {
      const float v = zncc_at(rt, rss, left, xl - r, yi - r, s, min_var_n);
      if (v > lbest_v) {
        lbest_v = v;
        lbest = xl;
      }
    }
    if (std::fabs(static_cast<float>(lbest - xi)) > config_.left_right_tolerance_px) {
      counters_.increment(VisionCounter::kStereoLeftRight);
      return Status(StatusCode::kNotFound, "stereo: left-right check failed");
    }
  }
  disparity_px = static_cast<float>(dbest) + off;
  zncc = best_v;
  if (!(disparity_px > 0.0f)) {
    counters_.increment(VisionCounter::kStereoEdgeOfRange);
    return Status(StatusCode::kNotFound, "stereo: non-positive disparity");
  }
  return Status::ok();
}

Status StereoMatcher::match(ConstImageViewU8 left, ConstImageViewU8 right, Span<const Corner> corners,
                            BoundedVector<StereoPoint>& out) noexcept {
  out.clear();
  if (!ready_) return Status(StatusCode::kNotReady, "stereo: match before init");
  if (left.empty() || right.empty() || left.width() != right.width() || left.height() != right.height()) {
    counters_.increment(VisionCounter::kBadImage);
    return Status(StatusCode::kInvalidArgument, "stereo: images empty or of different sizes");
  }
  for (std::size_t i = 0; i < corners.size(); ++i) {
    const Corner& c = corners[i];
    float d = 0.0f, z = 0.0f;
    if (!match_one(left, right, c.x, c.y, d, z).is_ok()) continue;  // counted in match_one
    StereoPoint p;
    p.x_px = c.x;
    p.y_px = c.y;
    p.disparity_px = d;
    p.zncc = z;
    p.corner_index = static_cast<std::uint32_t>(i);
    if (!triangulate(camera_, c.x, c.y, d, p.p_m)) continue;
    p.sigma_z_m = depth_sigma_m(camera_, p.p_m.z(), config_.disparity_sigma_px);
    if (!out.push_back(p).is_ok()) {
      counters_.increment(VisionCounter::kStereoCapReached);
      return Status(StatusCode::kCapacityExceeded, "stereo: output full");
    }
  }
  return Status::ok();
}

}  // namespace qnav::vision
