#include "nav/vision/patch_align.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "test/support/alloc_guard.hpp"

namespace qnav::vision {
namespace {

// A smooth analytic texture (frequencies below 0.45 rad/px).
double texture(double x, double y) {
  return 128.0 + 40.0 * std::sin(0.31 * x + 0.7) * std::cos(0.23 * y) + 30.0 * std::sin(0.17 * x + 0.29 * y) +
         20.0 * std::cos(0.37 * y - 0.21 * x);
}

struct Img {
  int w, h;
  std::vector<std::uint8_t> px;
  Img(int w_, int h_) : w(w_), h(h_), px(static_cast<std::size_t>(w_ * h_)) {}
  // pixel (x, y) = gain * texture(map(x, y)) + bias, clamped to 8 bits
  template <typename Map>
  void render(Map map, double gain = 1.0, double bias = 0.0) {
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        double u = 0.0, v = 0.0;
        map(static_cast<double>(x), static_cast<double>(y), u, v);
        const double val = gain * texture(u, v) + bias;
        px[static_cast<std::size_t>(y * w + x)] = static_cast<std::uint8_t>(std::lround(std::min(255.0, std::max(0.0, val))));
      }
  }
  ConstImageViewU8 view() const { return ConstImageViewU8::make(px.data(), w, h).value(); }
};

// Brute-force ZNCC optimum of the (2r+1)^2 template at integer (cx, cy) of ref in tgt, sampled
// bilinearly as the aligner does, on a 0.002 px grid within +/-0.15 px of (x0, y0). 8-bit quantisation
// and interpolation move the optimum away from the true shift by a few hundredths of a pixel on a 7x7
// patch; the aligner must find (nearly) the optimum itself.
void brute_zncc(ConstImageViewU8 ref, int cx, int cy, ConstImageViewU8 tgt, double x0, double y0, int r, double& bx,
                double& by) {
  double best = -2.0;
  for (double x = x0 - 0.15; x <= x0 + 0.15; x += 0.002)
    for (double y = y0 - 0.15; y <= y0 + 0.15; y += 0.002) {
      double st = 0, sv = 0, stt = 0, svv = 0, stv = 0;
      const int n = (2 * r + 1) * (2 * r + 1);
      for (int j = -r; j <= r; ++j)
        for (int i = -r; i <= r; ++i) {
          const double t = ref(cx + i, cy + j);
          const double xs = x + i, ys = y + j, fx = std::floor(xs), fy = std::floor(ys), ax = xs - fx, ay = ys - fy;
          const int xi = static_cast<int>(fx), yi = static_cast<int>(fy);
          const double v = (1 - ax) * (1 - ay) * tgt(xi, yi) + ax * (1 - ay) * tgt(xi + 1, yi) +
                           (1 - ax) * ay * tgt(xi, yi + 1) + ax * ay * tgt(xi + 1, yi + 1);
          st += t, sv += v, stt += t * t, svv += v * v, stv += t * v;
        }
      const double z = (stv - st * sv / n) / std::sqrt((stt - st * st / n) * (svv - sv * sv / n));
      if (z > best) best = z, bx = x, by = y;
    }
}

PatchAligner configured(int radius = 3) {
  PatchAligner a;
  PatchAlignConfig c;
  c.radius = radius;
  EXPECT_TRUE(a.configure(c).is_ok());
  return a;
}

TEST(PatchAlign, RecoversASubPixelShiftUnderGainAndBias) {
  Img ref(96, 96), tgt(96, 96);
  ref.render([](double x, double y, double& u, double& v) { u = x; v = y; });
  const double dx = 1.37, dy = -0.62;  // the texture moved by (dx, dy) in the target
  tgt.render([&](double x, double y, double& u, double& v) { u = x - dx; v = y - dy; }, 0.8, 25.0);
  PatchAligner a = configured();
  for (double px : {30.0, 47.25, 61.5}) {
    PatchAlignResult r;
    // Start at the old position: the aligner must walk 1.5 px.
    const Status st = a.align(ref.view(), static_cast<float>(px), 40.0f, tgt.view(), static_cast<float>(px), 40.0f, false, r);
    ASSERT_TRUE(st.is_ok()) << to_string(st.code()) << ": " << st.message();
    // The template sits on the nearest pixel; its optimum plus the sub-pixel offset is the answer.
    const double off = px - std::round(px);
    double bx = 0.0, by = 0.0;
    brute_zncc(ref.view(), static_cast<int>(std::round(px)), 40, tgt.view(), std::round(px) + dx, 40.0 + dy, 3, bx, by);
    EXPECT_NEAR(r.x_px, bx + off, 0.015) << px;  // the ZNCC optimum (inverse-compositional LK stops
    // where the template gradients, not the target's, are orthogonal to the residual: ~0.01 px apart)
    EXPECT_NEAR(r.y_px, by, 0.015) << px;
    EXPECT_NEAR(r.x_px, px + dx, 0.1) << px;  // and near the true shift (quantisation + interpolation)
    EXPECT_NEAR(r.y_px, 40.0 + dy, 0.1) << px;
    EXPECT_GT(r.zncc, 0.999f);
    EXPECT_GT(r.sigma_x_px, 0.0f);
    EXPECT_LT(r.sigma_x_px, 0.05f);
    EXPECT_GE(r.iterations, 2);
    EXPECT_LE(r.iterations, 6);  // Gauss-Newton: a 1.5 px walk in a few steps
  }
}

TEST(PatchAlign, RowModeRefinesADisparityAndKeepsTheRow) {
  Img left(96, 64), right(96, 64);
  left.render([](double x, double y, double& u, double& v) { u = x; v = y; });
  const double d = 12.3;  // right(x) = left(x + d)
  right.render([&](double x, double y, double& u, double& v) { u = x + d; v = y; });
  PatchAligner a = configured();
  PatchAlignResult r;
  ASSERT_TRUE(a.align(left.view(), 50.0f, 30.0f, right.view(), 50.0f - 12.0f, 30.0f, true, r).is_ok());
  EXPECT_NEAR(50.0 - static_cast<double>(r.x_px), d, 0.05);
  EXPECT_EQ(r.y_px, 30.0f);
  EXPECT_EQ(r.sigma_y_px, 0.0f);
}

TEST(PatchAlign, TheWarpPredictsAScaleChange) {
  // The target sees the texture 25 % larger about (48, 48), moved by (0.4, 0.3): a ground patch the
  // camera approached. Target offset o from the point corresponds to reference offset o / 1.25.
  const double s = 1.25, cx = 48.0, cy = 48.0, tx = 0.4, ty = 0.3;
  Img ref(96, 96), tgt(96, 96);
  ref.render([](double x, double y, double& u, double& v) { u = x; v = y; });
  tgt.render([&](double x, double y, double& u, double& v) {
    u = cx + (x - cx - tx) / s;
    v = cy + (y - cy - ty) / s;
  });
  PatchAligner a = configured(5);
  double err_plain = 0.0, err_warped = 0.0;
  int n = 0;
  for (double px : {36.0, 42.0, 55.0, 60.0})
    for (double py : {38.0, 57.0}) {
      const double ex = cx + s * (px - cx) + tx, ey = cy + s * (py - cy) + ty;  // where the point went
      PatchAlignResult rp, rw;
      const float warp[4] = {static_cast<float>(1.0 / s), 0.0f, 0.0f, static_cast<float>(1.0 / s)};
      ASSERT_TRUE(a.align_warped(ref.view(), static_cast<float>(px), static_cast<float>(py), warp, tgt.view(),
                                 static_cast<float>(std::round(ex)), static_cast<float>(std::round(ey)), false, rw)
                      .is_ok());
      err_warped = std::max(err_warped, std::hypot(static_cast<double>(rw.x_px) - ex, static_cast<double>(rw.y_px) - ey));
      if (a.align(ref.view(), static_cast<float>(px), static_cast<float>(py), tgt.view(),
                  static_cast<float>(std::round(ex)), static_cast<float>(std::round(ey)), false, rp)
              .is_ok())
        err_plain = std::max(err_plain, std::hypot(static_cast<double>(rp.x_px) - ex, static_cast<double>(rp.y_px) - ey));
      else
        err_plain = 1e9;
      ++n;
    }
  // Measured: 0.073 px warped (8-bit quantisation of a smooth texture), 0.55 px without the warp.
  EXPECT_LT(err_warped, 0.1) << "plain " << err_plain;
  EXPECT_GT(err_plain, 4.0 * err_warped);  // a translation-only template is biased by the scale change
}

TEST(PatchAlign, BadInputIsAnErrorNotAWrongPosition) {
  Img ref(64, 64), flat(64, 64), stripes(64, 64);
  ref.render([](double x, double y, double& u, double& v) { u = x; v = y; });
  flat.render([](double, double, double& u, double& v) { u = 0.0; v = 0.0; });
  // Vertical stripes only: texture along x, none along y.
  stripes.render([](double x, double, double& u, double& v) { u = x; v = 0.0; });
  PatchAlignResult r;
  PatchAligner unconfigured;
  EXPECT_EQ(unconfigured.align(ref.view(), 30, 30, ref.view(), 30, 30, false, r).code(), StatusCode::kNotReady);
  PatchAlignConfig bad;
  bad.radius = 0;
  EXPECT_EQ(unconfigured.configure(bad).code(), StatusCode::kInvalidArgument);
  bad.radius = PatchAligner::kMaxRadius + 1;
  EXPECT_EQ(unconfigured.configure(bad).code(), StatusCode::kInvalidArgument);
  bad = PatchAlignConfig{};
  bad.max_shift_px = std::nanf("");
  EXPECT_EQ(unconfigured.configure(bad).code(), StatusCode::kInvalidArgument);

  PatchAligner a = configured();
  EXPECT_EQ(a.align(ref.view(), 2.0f, 30.0f, ref.view(), 30.0f, 30.0f, false, r).code(), StatusCode::kOutOfRange);
  EXPECT_EQ(a.align(ref.view(), 30.0f, 30.0f, ref.view(), 61.5f, 30.0f, false, r).code(), StatusCode::kOutOfRange);
  EXPECT_EQ(a.align(ref.view(), std::nanf(""), 30.0f, ref.view(), 30.0f, 30.0f, false, r).code(), StatusCode::kOutOfRange);
  EXPECT_EQ(a.align(flat.view(), 30.0f, 30.0f, ref.view(), 30.0f, 30.0f, false, r).code(), StatusCode::kDegenerate);
  EXPECT_EQ(a.align(stripes.view(), 30.0f, 30.0f, stripes.view(), 30.0f, 30.0f, false, r).code(), StatusCode::kDegenerate);
  // ... but rows-only alignment along the stripes is well posed.
  EXPECT_TRUE(a.align(stripes.view(), 30.0f, 30.0f, stripes.view(), 30.4f, 30.0f, true, r).is_ok());
  EXPECT_NEAR(r.x_px, 30.0f, 0.02f);
  // A target with nothing like the template: no convergence, or a low ZNCC; never a position.
  Img other(64, 64);
  other.render([](double x, double y, double& u, double& v) { u = 3.1 * y + 7.0; v = 2.3 * x - 5.0; });
  r = PatchAlignResult{};
  r.x_px = -1.0f;
  EXPECT_FALSE(a.align(ref.view(), 30.0f, 30.0f, other.view(), 30.0f, 30.0f, false, r).is_ok());
  EXPECT_EQ(r.x_px, -1.0f);  // nothing written
  const float nan_warp[4] = {std::nanf(""), 0.0f, 0.0f, 1.0f};
  EXPECT_EQ(a.align_warped(ref.view(), 30, 30, nan_warp, ref.view(), 30, 30, false, r).code(), StatusCode::kInvalidArgument);
  const float huge_warp[4] = {8.0f, 0.0f, 0.0f, 8.0f};
  EXPECT_EQ(a.align_warped(ref.view(), 30, 30, huge_warp, ref.view(), 30, 30, false, r).code(), StatusCode::kInvalidArgument);
}

// The aligner normalises through sums (one pass per template, one per iteration); this is the per-sample
// form in double (the template made zero-mean and unit-norm, its gradients projected off {constant,
// template}, the target patch normalised at every iteration), identity warp, the template on the pixel
// (cx, cy). Returns false where it does not converge.
bool reference_align(ConstImageViewU8 ref, int cx, int cy, ConstImageViewU8 tgt, double x, double y, int r, bool rows_only,
                     double& xo, double& yo, double& zncc) {
  const int s = 2 * r + 1, n = s * s;
  const std::size_t nz = static_cast<std::size_t>(n);
  std::vector<double> t(nz), gx(nz), gy(nz), v(nz);
  for (int j = 0; j < s; ++j)
    for (int i = 0; i < s; ++i) {
      const int u = cx - r + i, w = cy - r + j, k = j * s + i;
      t[k] = ref(u, w);
      gx[k] = 0.5 * (ref(u + 1, w) - ref(u - 1, w));
      gy[k] = rows_only ? 0.0 : 0.5 * (ref(u, w + 1) - ref(u, w - 1));
    }
  auto normalise = [n](std::vector<double>& a) {
    double m = 0.0, ss = 0.0;
    for (double e : a) m += e / n;
    for (double& e : a) ss += (e - m) * (e - m);
    for (double& e : a) e = (e - m) / std::sqrt(ss);
    return 1.0 / std::sqrt(ss);
  };
  const double inv = normalise(t);
  for (std::vector<double>* g : {&gx, &gy}) {
    double m = 0.0, gt = 0.0;
    for (double& e : *g) e *= inv;
    for (double e : *g) m += e / n;
    for (int k = 0; k < n; ++k) gt += ((*g)[k] - m) * t[k];
    for (int k = 0; k < n; ++k) (*g)[k] = (*g)[k] - m - gt * t[k];
  }
  double hxx = 0.0, hxy = 0.0, hyy = 0.0;
  for (int k = 0; k < n; ++k) hxx += gx[k] * gx[k], hxy += gx[k] * gy[k], hyy += gy[k] * gy[k];
  for (int it = 0; it < 12; ++it) {
    const int ix = static_cast<int>(std::floor(x)), iy = static_cast<int>(std::floor(y));
    const double ax = x - ix, ay = y - iy;
    for (int j = 0; j < s; ++j)
      for (int i = 0; i < s; ++i) {
        const int u = ix - r + i, w = iy - r + j;
        v[j * s + i] = (1 - ax) * (1 - ay) * tgt(u, w) + ax * (1 - ay) * tgt(u + 1, w) + (1 - ax) * ay * tgt(u, w + 1) +
                       ax * ay * tgt(u + 1, w + 1);
      }
    normalise(v);
    double bx = 0.0, by = 0.0;
    zncc = 0.0;
    for (int k = 0; k < n; ++k) bx += gx[k] * (v[k] - t[k]), by += gy[k] * (v[k] - t[k]), zncc += v[k] * t[k];
    const double dx = rows_only ? bx / hxx : (hyy * bx - hxy * by) / (hxx * hyy - hxy * hxy);
    const double dy = rows_only ? 0.0 : (hxx * by - hxy * bx) / (hxx * hyy - hxy * hxy);
    x -= dx;
    y -= dy;
    if (std::hypot(dx, dy) < 0.01) {
      xo = x, yo = y;
      return true;
    }
  }
  return false;
}

TEST(PatchAlign, SumsGiveThePerSampleNormalisationsEstimate) {
  Img ref(96, 96), tgt(96, 96);
  ref.render([](double x, double y, double& u, double& v) { u = x; v = y; });
  tgt.render([](double x, double y, double& u, double& v) { u = x - 0.83 + 0.004 * y; v = y + 0.41; }, 0.7, 40.0);
  for (int radius : {3, 5}) {
    PatchAligner a = configured(radius);
    int checked = 0;
    for (int py = 24; py <= 72; py += 12)
      for (int px = 24; px <= 72; px += 8)
        for (bool rows_only : {false, true}) {
          const float x0 = static_cast<float>(px) + 0.5f, y0 = static_cast<float>(py) + (rows_only ? 0.41f : 0.0f);
          PatchAlignResult r;
          double xr = 0.0, yr = 0.0, zr = 0.0;
          const bool ok_ref = reference_align(ref.view(), px, py, tgt.view(), static_cast<double>(x0),
                                              static_cast<double>(y0), radius, rows_only, xr, yr, zr);
          if (!a.align(ref.view(), static_cast<float>(px), static_cast<float>(py), tgt.view(), x0, y0, rows_only, r).is_ok())
            continue;  // (a ZNCC below min_zncc or no convergence: checked elsewhere)
          ASSERT_TRUE(ok_ref) << px << " " << py;
          // The same iterates up to float rounding: the final positions differ by far less than the
          // 0.01 px convergence step, the ZNCC to float precision.
          EXPECT_NEAR(r.x_px, xr, 2e-4) << px << " " << py << " rows " << rows_only;
          if (!rows_only) {
            EXPECT_NEAR(r.y_px, yr, 2e-4) << px << " " << py;
          }
          EXPECT_NEAR(r.zncc, zr, 2e-6) << px << " " << py << " rows " << rows_only;
          ++checked;
        }
    EXPECT_GT(checked, 50) << radius;
  }
}

TEST(PatchAlign, AlignsWithoutHeap) {
  Img ref(64, 64), tgt(64, 64);
  ref.render([](double x, double y, double& u, double& v) { u = x; v = y; });
  tgt.render([](double x, double y, double& u, double& v) { u = x - 0.3; v = y + 0.2; });
  PatchAligner a = configured(PatchAligner::kMaxRadius);
  PatchAlignResult r;
  QNAV_EXPECT_NO_ALLOC((void)a.align(ref.view(), 30.0f, 30.0f, tgt.view(), 30.0f, 30.0f, false, r));
  EXPECT_NEAR(r.x_px, 30.3f, 0.02f);
}

}  // namespace
}  // namespace qnav::vision
