#include "nav/vision/patch_align.hpp"

#include <algorithm>
#include <cmath>

namespace qnav::vision {

namespace {

// The grey levels 0..255 as floats: one load instead of a conversion through memory (a store, a load
// and fitos on SPARC V8), the same exact values.
struct U8FloatTable {
  float v[256];
  constexpr U8FloatTable() noexcept : v() {
    for (int i = 0; i < 256; ++i) v[i] = static_cast<float>(i);
  }
};
constexpr U8FloatTable kU8Float{};

// Bilinear sample; the caller has checked the 2x2 support (inside()), so x, y >= 0 and truncation is
// the floor (std::floor is a library call on SPARC V8 and ARMv7: 2.3 M instructions per VO step on a
// LEON3, scripts/timing --profile vo_step). (Keys cubic interpolation was tried: the same accuracy on
// the Mars yard, 0.4 ms more per VO step.)
inline float sample(ConstImageViewU8 img, float x, float y) noexcept {
  const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
  const float ax = x - static_cast<float>(x0), ay = y - static_cast<float>(y0);
  const std::uint8_t* r0 = img.row(y0) + x0;
  const std::uint8_t* r1 = img.row(y0 + 1) + x0;
  const float a = kU8Float.v[r0[0]], b = kU8Float.v[r0[1]], c = kU8Float.v[r1[0]], d = kU8Float.v[r1[1]];
  const float top = a + ax * (b - a);
  const float bot = c + ax * (d - c);
  return top + ay * (bot - top);
}

// True when a square of half-side h (pixels) around (x, y) can be sampled bilinearly: floor(x - h) >= 0
// and floor(x + h) + 1 <= W - 1, i.e. x - h >= 0 and x + h < W - 1 (the same for y). False for NaN and
// infinities.
inline bool inside(ConstImageViewU8 img, float x, float y, int h) noexcept {
  const float hf = static_cast<float>(h);
  return x - hf >= 0.0f && y - hf >= 0.0f && x + hf < static_cast<float>(img.width() - 1) &&
         y + hf < static_cast<float>(img.height() - 1);
}

}  // namespace

Status PatchAligner::configure(const PatchAlignConfig& c) noexcept {
  ready_ = false;
  if (c.radius < 1 || c.radius > kMaxRadius || c.max_iterations < 1 || c.max_iterations > 100 ||
      !(c.converge_px > 0.0f) || !(c.max_shift_px > 0.0f) || !std::isfinite(c.max_shift_px) ||
      !(c.min_zncc >= -1.0f && c.min_zncc <= 1.0f) || !(c.min_gradient_energy > 0.0f) ||
      !std::isfinite(c.min_gradient_energy))
    return Status(StatusCode::kInvalidArgument, "patch align config out of range");
  config_ = c;
  ready_ = true;
  return Status::ok();
}

Status PatchAligner::align(ConstImageViewU8 ref, float ref_x, float ref_y, ConstImageViewU8 target, float x0, float y0,
                           bool rows_only, PatchAlignResult& out) noexcept {
  static constexpr float kIdentity[4] = {1.0f, 0.0f, 0.0f, 1.0f};
  return align_warped(ref, ref_x, ref_y, kIdentity, target, x0, y0, rows_only, out);
}

// The grid's first and last rows are read only at columns 1..s, by the vertical gradients: their corners
// are not sampled, and in row mode (no vertical gradients, none of the y terms below) neither are they. With the identity warp every sample falls on a pixel (cx, cy and the offsets are
// integers): the bilinear sample is then that pixel's value exactly (weights 0: a + 0 * (b - a) = a), so
// the pixels are copied. Otherwise each sample takes sample()'s arithmetic, with the warp's terms of the
// row (warp[1] dy, warp[3] dy) computed once per row and the column offset stepped by 1 (exact for these
// small integers): the same floats as cx + warp[0] dx + warp[1] dy per sample.
void PatchAligner::build_grid(ConstImageViewU8 ref, float cx, float cy, const float (&warp)[4], int r,
                              bool rows_only) noexcept {
  const int g = 2 * r + 3;
  const int j0 = rows_only ? 1 : 0;  // row mode has no vertical gradients: the first and last rows are not read
  const float w0 = warp[0], w1 = warp[1], w2 = warp[2], w3 = warp[3];
  if (w0 == 1.0f && w1 == 0.0f && w2 == 0.0f && w3 == 1.0f) {
    const int x0 = static_cast<int>(cx) - r - 1, y0 = static_cast<int>(cy) - r - 1;  // cx, cy >= reach: exact
    for (int j = j0; j < g - j0; ++j) {
      const int i0 = (j == 0 || j == g - 1) ? 1 : 0;
      const std::uint8_t* src = ref.row(y0 + j) + x0;
      float* dst = grid_ + j * g;
      for (int i = i0; i < g - i0; ++i) dst[i] = kU8Float.v[src[i]];
    }
    return;
  }
  for (int j = j0; j < g - j0; ++j) {
    const float dy = static_cast<float>(j - r - 1);
    const float w1dy = w1 * dy, w3dy = w3 * dy;
    const int i0 = (j == 0 || j == g - 1) ? 1 : 0;
    float dx = static_cast<float>(i0 - r - 1);
    float* dst = grid_ + j * g;
    for (int i = i0; i < g - i0; ++i, dx += 1.0f) dst[i] = sample(ref, cx + w0 * dx + w1dy, cy + w2 * dx + w3dy);
  }
}

Status PatchAligner::align_warped(ConstImageViewU8 ref, float ref_x, float ref_y, const float (&warp)[4],
                                  ConstImageViewU8 target, float x0, float y0, bool rows_only,
                                  PatchAlignResult& out) noexcept {
  if (!ready_) return Status(StatusCode::kNotReady, "PatchAligner::align before configure");
  if (ref.empty() || target.empty()) return Status(StatusCode::kInvalidArgument, "patch align: empty image");
  const float det_w = warp[0] * warp[3] - warp[1] * warp[2];
  const float norm_w = std::fabs(warp[0]) + std::fabs(warp[1]) + std::fabs(warp[2]) + std::fabs(warp[3]);
  if (!std::isfinite(det_w) || !std::isfinite(norm_w) || !(std::fabs(det_w) >= 1.0f / 16.0f) || !(std::fabs(det_w) <= 16.0f) ||
      !(norm_w <= 16.0f))
    return Status(StatusCode::kInvalidArgument, "patch align: warp not finite or scaling beyond 4x");
  const int r = config_.radius;
  if (!std::isfinite(ref_x) || !std::isfinite(ref_y) || !std::isfinite(x0) || !std::isfinite(y0))
    return Status(StatusCode::kOutOfRange, "patch align: position not finite");
  // The template is centred on the reference point's nearest pixel (with the identity warp its samples
  // are pixels, not interpolations: an interpolated template is blurred differently from the target and
  // moved the optimum by up to 0.03 px on blob texture); the nearest pixel's target position is solved
  // for and moved back by the warped sub-pixel offset. Target offset of a reference offset: warp^-1.
  const float cx = std::round(ref_x), cy = std::round(ref_y);
  const float ddx = ref_x - cx, ddy = ref_y - cy;
  const float ox = (warp[3] * ddx - warp[1] * ddy) / det_w, oy = (warp[0] * ddy - warp[2] * ddx) / det_w;
  const float xs = x0 - ox, ys = y0 - oy;
  // Reach of the warped template grid in the reference image (its corners).
  const float reach = static_cast<float>(r + 1) * std::max(std::fabs(warp[0]) + std::fabs(warp[1]),
                                                           std::fabs(warp[2]) + std::fabs(warp[3]));
  if (!inside(ref, cx, cy, static_cast<int>(std::ceil(reach))) || !inside(target, xs, ys, r))
    return Status(StatusCode::kOutOfRange, "patch align: patch outside the image");
  Hessian h;
  QNAV_RETURN_IF_ERROR(prepare_template(ref, cx, cy, warp, rows_only, h));
  float x = xs, y = ys;
  Residual last;
  QNAV_RETURN_IF_ERROR(iterate(target, xs, ys, rows_only, h, x, y, last));
  // Quality and uncertainty from the last evaluated patch (the final update was below converge_px).
  const float zncc = static_cast<float>(last.cross);
  if (!(zncc >= config_.min_zncc)) return Status(StatusCode::kNotFound, "patch align: final ZNCC below min_zncc");
  const int s = 2 * r + 1, n = s * s;
  const int dof = rows_only ? 1 : 2;
  const double var = last.ess / static_cast<double>(n > dof ? n - dof : 1);
  out.x_px = x + ox;
  out.y_px = rows_only ? y0 : y + oy;
  out.zncc = zncc;
  out.iterations = last.iterations;
  if (rows_only) {
    out.sigma_x_px = static_cast<float>(std::sqrt(var / h.xx));
    out.sigma_y_px = 0.0f;
  } else {
    out.sigma_x_px = static_cast<float>(std::sqrt(var * h.yy / h.det));
    out.sigma_y_px = static_cast<float>(std::sqrt(var * h.xx / h.det));
  }
  return Status::ok();
}

// Template grid one pixel wider than the patch (for central-difference gradients), laid out in target
// coordinates and sampled in the reference image through the warp. The normalised template and its
// gradients are affine in the raw samples, so one pass keeps the raw ones and their first and second
// moments, and the rest is closed form. With T the samples less the grid's centre (an exact bias that
// keeps the sums small), X and Y twice the central differences, m() a mean, c(A, B) = sum (A - mA)(B - mB)
// and inv = 1 / sqrt(c(T, T)):
//   t   = inv (T - mT)                          zero mean, unit norm
//   gx  = inv (X - mX) / 2 - gxt t,  gxt = inv^2 c(T, X) / 2   the gradient less its mean and its
//                                                              part along t (the target patch is
//                                                              normalised too: a shift cannot change
//                                                              it along {constant, t}; without this a
//                                                              patch on a brightness ramp gets a Hessian
//                                                              the error never sees)
//   hxx = sum gx^2 = inv^2 c(X, X) / 4 - gxt^2,  hxy = inv^2 c(X, Y) / 4 - gxt gyt  (sum t^2 = 1, sum gx t = 0)
// evaluate() correlates the target patch with the raw T, X, Y and applies the same maps to the sums.
Status PatchAligner::prepare_template(ConstImageViewU8 ref, float cx, float cy, const float (&warp)[4], bool rows_only,
                                      Hessian& h) noexcept {
  const int r = config_.radius;
  const int s = 2 * r + 1, g = s + 2, n = s * s;
  build_grid(ref, cx, cy, warp, r, rows_only);
  const float base = grid_[(r + 1) * g + (r + 1)];
  double st = 0.0, sx = 0.0, sy = 0.0, stt = 0.0, sxx = 0.0, syy = 0.0, sxy = 0.0, stx = 0.0, sty = 0.0;
  for (int j = 0; j < s; ++j) {
    const float* row = grid_ + (j + 1) * g + 1;
    float* t = t_ + j * s;
    float* gx = gx_ + j * s;
    float* gy = gy_ + j * s;
    for (int i = 0; i < s; ++i) {
      const float tv = row[i] - base, xv = row[i + 1] - row[i - 1];
      t[i] = tv;
      gx[i] = xv;
      const double td = static_cast<double>(tv), xd = static_cast<double>(xv);
      st += td;
      sx += xd;
      stt += td * td;
      sxx += xd * xd;
      stx += td * xd;
      if (!rows_only) {
        const float yv = row[i + g] - row[i - g];
        gy[i] = yv;
        const double yd = static_cast<double>(yv);
        sy += yd;
        syy += yd * yd;
        sxy += xd * yd;
        sty += td * yd;
      }
    }
  }
  const double inv_n = 1.0 / static_cast<double>(n);
  const double mt = st * inv_n, mx = sx * inv_n, my = sy * inv_n;
  const double ctt = stt - st * mt;
  if (!(ctt > 1e-6)) return Status(StatusCode::kDegenerate, "patch align: flat template");
  const double inv = 1.0 / std::sqrt(ctt), inv2 = inv * inv;
  const double gxt = 0.5 * inv2 * (stx - st * mx);
  const double gyt = rows_only ? 0.0 : 0.5 * inv2 * (sty - st * my);
  tmpl_ = TemplateMaps{mt, mx, my, inv, gxt, gyt};
  const double hxx = 0.25 * inv2 * (sxx - sx * mx) - gxt * gxt;
  h.xx = hxx;
  const double min_e = static_cast<double>(config_.min_gradient_energy);
  if (rows_only) {
    if (!(hxx > min_e)) return Status(StatusCode::kDegenerate, "patch align: no texture along the row");
    return Status::ok();
  }
  const double hyy = 0.25 * inv2 * (syy - sy * my) - gyt * gyt;
  const double hxy = 0.25 * inv2 * (sxy - sx * my) - gxt * gyt;
  h.xy = hxy;
  h.yy = hyy;
  const double tr = hxx + hyy;
  h.det = hxx * hyy - hxy * hxy;
  const double lmin = 0.5 * (tr - std::sqrt(std::max(0.0, tr * tr - 4.0 * h.det)));
  if (!(lmin > min_e) || !(h.det > 0.0)) return Status(StatusCode::kDegenerate, "patch align: template without 2D texture");
  return Status::ok();
}

// The normalised target patch at (x, y) against the template, in one pass: every sample has the same
// fractional offset (the bilinear weights are computed once), and both normalisations are applied to
// sums rather than to samples. With v the bilinear samples, c = v - mean(v), inv_v = 1 / |c| and the
// template maps of prepare_template (sum t = sum gx = sum gx t = 0, sum t^2 = 1):
//   sum t v  = inv (sum T v - mT sum v)
//   cross    = sum (inv_v c) t = inv_v sum t v                    (the ZNCC)
//   b        = sum gx (inv_v c - t) = inv_v (inv (sum X v - mX sum v) / 2 - gxt sum t v)
//   ess      = sum (inv_v c - t)^2 = 2 - 2 cross
// so one pass gathers sum v, sum v^2, sum T v, sum X v and sum Y v. The target pixels are taken less
// the window's centre pixel (exact integers: small sums; the normalised patch does not depend on it).
Status PatchAligner::evaluate(ConstImageViewU8 target, float x, float y, bool rows_only, Residual& e) noexcept {
  const int r = config_.radius;
  const int s = 2 * r + 1, n = s * s;
  const int ws = s + 1;  // side of the target window under the patch
  const int ix = static_cast<int>(x), iy = static_cast<int>(y);  // x, y >= r: truncation is the floor
  const float ax = x - static_cast<float>(ix), ay = y - static_cast<float>(iy);
  const float w00 = (1.0f - ax) * (1.0f - ay), w01 = ax * (1.0f - ay), w10 = (1.0f - ax) * ay, w11 = ax * ay;
  const int px0 = ix - r, py0 = iy - r;
  // The (s+1)^2 target pixels less the centre pixel, as floats, converted once per integer position (the
  // estimate moves by sub-pixel steps, so usually once per call).
  if (ix != win_x_ || iy != win_y_) {
    const float base = kU8Float.v[target.row(iy)[ix]];
    for (int j = 0; j < ws; ++j) {
      const std::uint8_t* src = target.row(py0 + j) + px0;
      float* dst = win_ + j * ws;
      for (int i = 0; i < ws; ++i) dst[i] = kU8Float.v[src[i]] - base;
    }
    win_x_ = ix;
    win_y_ = iy;
  }
  double sv = 0.0, svv = 0.0;
  float stv = 0.0f, sxv = 0.0f, syv = 0.0f;
  for (int j = 0; j < s; ++j) {
    const float* r0 = win_ + j * ws;
    const float* r1 = r0 + ws;
    const float* t = t_ + j * s;
    const float* gx = gx_ + j * s;
    const float* gy = gy_ + j * s;
    float row_sum = 0.0f, row_sq = 0.0f;
    for (int i = 0; i < s; ++i) {
      const float v = w00 * r0[i] + w01 * r0[i + 1] + w10 * r1[i] + w11 * r1[i + 1];
      row_sum += v;
      row_sq += v * v;
      stv += t[i] * v;
      sxv += gx[i] * v;
      if (!rows_only) syv += gy[i] * v;
    }
    sv += static_cast<double>(row_sum);
    svv += static_cast<double>(row_sq);
  }
  const double mean = sv / n;
  const double iss = svv - sv * mean;
  if (!(iss > 1e-6)) return Status(StatusCode::kNotFound, "patch align: flat target patch");
  const double inv_v = 1.0 / std::sqrt(iss);
  const TemplateMaps& m = tmpl_;
  const double tv = m.inv * (static_cast<double>(stv) - m.mt * sv);
  e.cross = inv_v * tv;
  e.bx = inv_v * (0.5 * m.inv * (static_cast<double>(sxv) - m.mx * sv) - m.gxt * tv);
  e.by = rows_only ? 0.0 : inv_v * (0.5 * m.inv * (static_cast<double>(syv) - m.my * sv) - m.gyt * tv);
  e.ess = std::max(0.0, 2.0 - 2.0 * e.cross);
  return Status::ok();
}

// Gauss-Newton from (xs, ys) until the update is below converge_px; (x, y) the estimate, `last` the
// residual of the last evaluated patch and the iterations taken.
Status PatchAligner::iterate(ConstImageViewU8 target, float xs, float ys, bool rows_only, const Hessian& h, float& x,
                             float& y, Residual& last) noexcept {
  const int r = config_.radius;
  win_x_ = -1;  // no target window converted yet
  win_y_ = -1;
  for (int it = 0; it < config_.max_iterations; ++it) {
    if (!inside(target, x, y, r)) return Status(StatusCode::kOutOfRange, "patch align: left the image");
    QNAV_RETURN_IF_ERROR(evaluate(target, x, y, rows_only, last));
    double dx = 0.0, dy = 0.0;
    if (rows_only) {
      dx = last.bx / h.xx;
    } else {
      dx = (h.yy * last.bx - h.xy * last.by) / h.det;
      dy = (h.xx * last.by - h.xy * last.bx) / h.det;
    }
    // Inverse compositional update for a translation: p <- p - dp.
    x -= static_cast<float>(dx);
    y -= static_cast<float>(dy);
    if (std::fabs(x - xs) > config_.max_shift_px || std::fabs(y - ys) > config_.max_shift_px)
      return Status(StatusCode::kNotFound, "patch align: moved beyond max_shift_px");
    if (std::sqrt(dx * dx + dy * dy) < static_cast<double>(config_.converge_px)) {
      last.iterations = it + 1;
      return Status::ok();
    }
  }
  return Status(StatusCode::kNotFound, "patch align: no convergence");
}

}  // namespace qnav::vision
