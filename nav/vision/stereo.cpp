#include "nav/vision/stereo.hpp"

#include <cmath>

namespace qnav::vision {

namespace {
constexpr int kMaxPatchRadius = 7;
constexpr int kMaxPatch = (2 * kMaxPatchRadius + 1) * (2 * kMaxPatchRadius + 1);

bool finite_pos(double v) noexcept { return std::isfinite(v) && v > 0.0; }

// A patch for ZNCC: its grey levels (row-major, side s) and moments; n2var = n * sum of squares - sum^2
// = n^2 * variance. All exact: integers below 2^53 held in doubles (no 64-bit integer arithmetic, a
// library call on 32-bit SPARC).
struct Template {
  std::int32_t v[kMaxPatch];
  double sum = 0.0;
  double n2var = 0.0;
};

// Loads the patch centred at (xc, yc) of half-side r.
inline void load_template(ConstImageViewU8 img, int xc, int yc, int r, Template& t) noexcept {
  const int s = 2 * r + 1;
  std::int32_t sum = 0, sq = 0;
  int k = 0;
  for (int j = 0; j < s; ++j) {
    const std::uint8_t* row = img.row(yc - r + j) + (xc - r);
    for (int i = 0; i < s; ++i, ++k) {
      const std::int32_t v = row[i];
      t.v[k] = v;
      sum += v;
      sq += v * v;
    }
  }
  t.sum = static_cast<double>(sum);
  t.n2var = static_cast<double>(s * s) * static_cast<double>(sq) - t.sum * t.sum;
}

// Column sums of the band of rows [y0, y0 + s) over columns [xa, xa + ncols), as prefix sums:
// ps[k] = sum of the grey levels of columns xa .. xa + k - 1, pq the same for their squares. A window
// of side s whose left column is xa + k then has sum ps[k + s] - ps[k] (likewise sq): each disparity's
// patch sums cost two subtractions instead of s * s additions.
// The usual sides get a fixed trip count with the band's row pointers taken once (unrolled: no row
// address per pixel on an in-order core); integer sums, so the same values as the generic loop.
template <int S>
inline void band_prefix_fixed(ConstImageViewU8 img, int xa, int ncols, int y0, std::int32_t* ps, std::int32_t* pq) noexcept {
  const std::uint8_t* rows[S];
  for (int j = 0; j < S; ++j) rows[j] = img.row(y0 + j) + xa;
  std::int32_t run_a = 0, run_q = 0;
  ps[0] = pq[0] = 0;
  for (int c = 0; c < ncols; ++c) {
    std::int32_t a = 0, q = 0;
    for (int j = 0; j < S; ++j) {
      const std::int32_t v = rows[j][c];
      a += v;
      q += v * v;
    }
    run_a += a;
    run_q += q;
    ps[c + 1] = run_a;
    pq[c + 1] = run_q;
  }
}

inline void band_prefix(ConstImageViewU8 img, int xa, int ncols, int y0, int s, std::int32_t* ps, std::int32_t* pq) noexcept {
  switch (s) {
    case 5: return band_prefix_fixed<5>(img, xa, ncols, y0, ps, pq);
    case 7: return band_prefix_fixed<7>(img, xa, ncols, y0, ps, pq);
    case 9: return band_prefix_fixed<9>(img, xa, ncols, y0, ps, pq);
    default: break;
  }
  ps[0] = pq[0] = 0;
  for (int c = 0; c < ncols; ++c) {
    std::int32_t a = 0, q = 0;
    for (int j = 0; j < s; ++j) {
      const std::int32_t v = img.row(y0 + j)[xa + c];
      a += v;
      q += v * v;
    }
    ps[c + 1] = ps[c] + a;
    pq[c + 1] = pq[c] + q;
  }
}

// sum(t v) over the window of side S at (x0, y0). The patch sides of the usual radii get a fixed trip
// count (fully unrolled inner loop: a third of the instructions on an in-order core without SIMD,
// scripts/timing --profile stereo); integer sums, so the result does not depend on the order.
template <int S>
inline std::int32_t cross_fixed(const std::int32_t* t, ConstImageViewU8 img, int x0, int y0) noexcept {
  std::int32_t cross = 0;
  for (int j = 0; j < S; ++j) {
    const std::uint8_t* row = img.row(y0 + j) + x0;
    const std::int32_t* tj = t + j * S;
    for (int i = 0; i < S; ++i) cross += tj[i] * static_cast<std::int32_t>(row[i]);
  }
  return cross;
}

// cross[m] = sum(t v) over the window of side S whose top-left corner is (x0 + m, y0), m = 0..count-1.
// Four neighbouring windows at a time share each template load and each pixel load (a pixel at column
// i + m serves windows m..m+3): about 18 instead of 28 instructions per window row on an in-order core
// without SIMD. Integer sums: the same values as cross_fixed.
template <int S>
inline void cross_run_fixed(const std::int32_t* t, ConstImageViewU8 img, int x0, int y0, int count,
                            std::int32_t* cross) noexcept {
  int m = 0;
  for (; m + 4 <= count; m += 4) {
    std::int32_t c0 = 0, c1 = 0, c2 = 0, c3 = 0;
    for (int j = 0; j < S; ++j) {
      const std::uint8_t* row = img.row(y0 + j) + x0 + m;  // columns up to x0 + m + S + 2 <= x0 + count + S - 2
      const std::int32_t* tj = t + j * S;
      std::int32_t p0 = row[0], p1 = row[1], p2 = row[2];
      for (int i = 0; i < S; ++i) {
        const std::int32_t p3 = row[i + 3], tv = tj[i];
        c0 += tv * p0;
        c1 += tv * p1;
        c2 += tv * p2;
        c3 += tv * p3;
        p0 = p1;
        p1 = p2;
        p2 = p3;
      }
    }
    cross[m] = c0;
    cross[m + 1] = c1;
    cross[m + 2] = c2;
    cross[m + 3] = c3;
  }
  for (; m < count; ++m) cross[m] = cross_fixed<S>(t, img, x0 + m, y0);
}

inline std::int32_t cross_sum(const Template& t, ConstImageViewU8 img, int x0, int y0, int s) noexcept {
  switch (s) {
    case 5: return cross_fixed<5>(t.v, img, x0, y0);
    case 7: return cross_fixed<7>(t.v, img, x0, y0);
    case 9: return cross_fixed<9>(t.v, img, x0, y0);
    default: break;
  }
  std::int32_t cross = 0;
  int k = 0;
  for (int j = 0; j < s; ++j) {
    const std::uint8_t* row = img.row(y0 + j) + x0;
    for (int i = 0; i < s; ++i, ++k) cross += t.v[k] * static_cast<std::int32_t>(row[i]);
  }
  return cross;
}

// cross_run_fixed for any side (the usual ones fixed).
inline void cross_run(const Template& t, ConstImageViewU8 img, int x0, int y0, int s, int count, std::int32_t* cross) noexcept {
  switch (s) {
    case 5: return cross_run_fixed<5>(t.v, img, x0, y0, count, cross);
    case 7: return cross_run_fixed<7>(t.v, img, x0, y0, count, cross);
    case 9: return cross_run_fixed<9>(t.v, img, x0, y0, count, cross);
    default: break;
  }
  for (int m = 0; m < count; ++m) cross[m] = cross_sum(t, img, x0 + m, y0, s);
}

// ZNCC of template t against a window of side s, given the window's sum and sum of squares (band_prefix)
// and sum(t v) (cross_run):
//   (n sum(t v) - sum(t) sum(v)) / sqrt((n sum(t^2) - sum(t)^2) (n sum(v^2) - sum(v)^2)),
// in integers up to the final division (225 * 255^2 fits 32 bits; the products are exact in double).
// Returns -1 when the window is flat (n2var <= min_n2var).
inline float zncc_window(const Template& t, int s, std::int32_t sum, std::int32_t sq, std::int32_t cross,
                         double min_n2var) noexcept {
  const double n = static_cast<double>(s * s);
  const double sum_d = static_cast<double>(sum);
  const double n2var = n * static_cast<double>(sq) - sum_d * sum_d;
  if (!(n2var > min_n2var)) return -1.0f;
  const double num = n * static_cast<double>(cross) - t.sum * sum_d;
  const double z = num / std::sqrt(t.n2var * n2var);
  return z > 1.0 ? 1.0f : (z < -1.0 ? -1.0f : static_cast<float>(z));
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
  // Flat-patch floor: n * variance > min_patch_stddev^2 * n, as n^2 * variance (Template::n2var).
  const double n = static_cast<double>(s * s);
  const double min_n2var = static_cast<double>(config_.min_patch_stddev) * static_cast<double>(config_.min_patch_stddev) * n * n;
  Template t;
  load_template(left, xi, yi, r, t);
  if (!(t.n2var > min_n2var)) {
    counters_.increment(VisionCounter::kStereoFlatPatch);
    return Status(StatusCode::kDegenerate, "stereo: left patch has no texture");
  }
  const int nd = dmax - dmin + 1;
  int best = -1;
  float best_v = -2.0f;
  // Right windows: left columns xi - dmax - r (i = nd - 1) .. xi - dmin - r (i = 0).
  const int xa = xi - dmax - r;
  band_prefix(right, xa, nd + s - 1, yi - r, s, prefix_sum_, prefix_sq_);
  cross_run(t, right, xa, yi - r, s, nd, cross_);
  for (int i = 0; i < nd; ++i) {
    const int x0 = xi - (dmin + i) - r, k = x0 - xa;
    const float v = zncc_window(t, s, prefix_sum_[k + s] - prefix_sum_[k], prefix_sq_[k + s] - prefix_sq_[k], cross_[k],
                                min_n2var);
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
    Template rt;
    load_template(right, xr, yi, r, rt);
    if (!(rt.n2var > min_n2var)) {
      counters_.increment(VisionCounter::kStereoFlatPatch);
      return Status(StatusCode::kDegenerate, "stereo: right patch has no texture");
    }
    const int lmax = xr + config_.max_disparity_px < W - 1 - r ? xr + config_.max_disparity_px : W - 1 - r;
    int lbest = xi;
    float lbest_v = -2.0f;
    const int la = xr + dmin - r;
    if (lmax >= xr + dmin) {
      band_prefix(left, la, lmax - (xr + dmin) + s, yi - r, s, prefix_sum_, prefix_sq_);
      cross_run(rt, left, la, yi - r, s, lmax - (xr + dmin) + 1, cross_);
    }
    for (int xl = xr + dmin; xl <= lmax; ++xl) {
      const int k = xl - r - la;
      const float v = zncc_window(rt, s, prefix_sum_[k + s] - prefix_sum_[k], prefix_sq_[k + s] - prefix_sq_[k], cross_[k],
                                  min_n2var);
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
