#include "nav/vision/stereo.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "nav/vision/harris.hpp"
#include "test/support/alloc_guard.hpp"
#include "test_images.hpp"

namespace qnav::vision {
namespace {

StereoCamera test_camera() {
  StereoCamera c;
  c.focal_px = 400.0;
  c.cu_px = 160.0;
  c.cv_px = 128.0;
  c.baseline_m = 0.12;
  return c;
}

// Right image = left image shifted by d px (right(x) = left(x + d)), with sub-pixel d by linear
// interpolation of a smooth texture.
void make_pair(std::vector<std::uint8_t>& l, std::vector<std::uint8_t>& r, int W, int H, double d, std::uint64_t seed) {
  l.assign(static_cast<std::size_t>(W * H), 0);
  r.assign(static_cast<std::size_t>(W * H), 0);
  // Render a wider texture and sample it.
  std::vector<std::uint8_t> wide(static_cast<std::size_t>((W + 80) * H));
  ImageViewU8 wv = ImageViewU8::make(wide.data(), W + 80, H).value();
  testing::texture(wv, seed);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      l[y * W + x] = wv(x, y);
      const double xs = x + d;
      const int x0 = static_cast<int>(std::floor(xs));
      const double f = xs - x0;
      r[y * W + x] = static_cast<std::uint8_t>(std::lround((1 - f) * wv(x0, y) + f * wv(x0 + 1, y)));
    }
}

TEST(Stereo, TriangulationFollowsMarsEq1) {
  const StereoCamera cam = test_camera();
  Vec3f p;
  ASSERT_TRUE(triangulate(cam, 260.0f, 28.0f, 8.0f, p));
  EXPECT_NEAR(p.z(), 0.12 * 400.0 / 8.0, 1e-5);             // Z = b f / d = 6 m
  EXPECT_NEAR(p.x(), (260.0 - 160.0) * 6.0 / 400.0, 1e-5);  // X = (u - cu) Z / f
  EXPECT_NEAR(p.y(), (28.0 - 128.0) * 6.0 / 400.0, 1e-5);
  EXPECT_NEAR(depth_sigma_m(cam, 6.0f, 0.5f), 36.0 / 48.0 * 0.5, 1e-6);  // Z^2/(bf) sigma_d
  EXPECT_FALSE(triangulate(cam, 1.0f, 1.0f, 0.0f, p));
  EXPECT_FALSE(triangulate(cam, 1.0f, 1.0f, -3.0f, p));
  EXPECT_FALSE(triangulate(cam, std::nanf(""), 1.0f, 3.0f, p));
}

TEST(Stereo, RecoversAKnownSubPixelDisparityAtHarrisCorners) {
  const int W = 240, H = 160;
  for (double d : {12.3, 25.7}) {
    std::vector<std::uint8_t> l, r;
    make_pair(l, r, W, H, d, 21);
    const ConstImageViewU8 lv = ConstImageViewU8::make(l.data(), W, H).value();
    const ConstImageViewU8 rv = ConstImageViewU8::make(r.data(), W, H).value();
    HarrisConfig hc;
    hc.max_width = W;
    hc.max_height = H;
    hc.max_corners = 200;
    ArenaStorage arena(HarrisDetector::arena_bytes(hc));
    HarrisDetector det;
    ASSERT_TRUE(det.init(hc, arena).is_ok());
    std::vector<Corner> cst(200);
    BoundedVector<Corner> corners(Span<Corner>(cst.data(), cst.size()));
    ASSERT_TRUE(det.detect(lv, corners).is_ok());
    ASSERT_GT(corners.size(), 60u);

    StereoMatcher m;
    StereoConfig sc;
    sc.max_disparity_px = 40;
    ASSERT_TRUE(m.init(sc, test_camera()).is_ok());
    std::vector<StereoPoint> pst(200);
    BoundedVector<StereoPoint> pts(Span<StereoPoint>(pst.data(), pst.size()));
    Status s;
    QNAV_EXPECT_NO_ALLOC(s = m.match(lv, rv, corners.span(), pts));
    ASSERT_TRUE(s.is_ok());
    // Most corners match (those near the left border cannot: the right patch leaves the image).
    EXPECT_GT(pts.size(), corners.size() * 3 / 4) << "d=" << d;
    double max_err = 0.0;
    for (const StereoPoint& p : pts) {
      max_err = std::max(max_err, std::fabs(static_cast<double>(p.disparity_px) - d));
      EXPECT_NEAR(p.p_m.z(), 0.12f * 400.0f / p.disparity_px, 1e-3);
      EXPECT_GT(p.sigma_z_m, 0.0f);
      EXPECT_EQ(p.x_px, corners[p.corner_index].x);
    }
    EXPECT_LT(max_err, 0.35) << "d=" << d;  // linear interpolation + parabola bias stays well under 0.5
  }
}

// Every patch radius (sides 5, 7, 9 take the fixed-side correlation, the others the general one) and
// disparity ranges whose window counts are not multiples of four (the scan correlates four windows at a
// time and the rest one by one).
TEST(Stereo, RecoversTheDisparityAtEveryPatchRadiusAndRangeLength) {
  const int W = 200, H = 120;
  const double d = 17.4;
  std::vector<std::uint8_t> l, r;
  make_pair(l, r, W, H, d, 7);
  const ConstImageViewU8 lv = ConstImageViewU8::make(l.data(), W, H).value();
  const ConstImageViewU8 rv = ConstImageViewU8::make(r.data(), W, H).value();
  for (int radius = 1; radius <= 7; ++radius)
    for (int max_d : {29, 30, 31, 32}) {
      StereoMatcher m;
      StereoConfig sc;
      sc.patch_radius = radius;
      sc.max_disparity_px = max_d;
      sc.min_patch_stddev = 1.0f;
      ASSERT_TRUE(m.init(sc, test_camera()).is_ok());
      int matched = 0, tried = 0;
      double max_err = 0.0;
      for (int y = 20; y < H - 20; y += 9)
        for (int x = 60; x < W - 20; x += 11) {
          ++tried;
          float disp = 0.0f, z = 0.0f;
          if (!m.match_one(lv, rv, static_cast<float>(x), static_cast<float>(y), disp, z).is_ok()) continue;
          ++matched;
          max_err = std::max(max_err, std::fabs(static_cast<double>(disp) - d));
          EXPECT_LE(z, 1.0f);
        }
      EXPECT_GT(matched, tried * 2 / 3) << "radius " << radius << " max_d " << max_d;
      // The right integer disparity with the parabola's sub-pixel step (measured: 0.51 px at radius 1, a
      // 3 x 3 patch on interpolated texture; below 0.5 px from radius 2).
      EXPECT_LT(max_err, radius == 1 ? 0.75 : 0.5) << "radius " << radius << " max_d " << max_d;
    }
}

TEST(Stereo, RejectsFlatWeakAmbiguousAndOutOfBoundsCorners) {
  const int W = 200, H = 100;
  std::vector<std::uint8_t> l(W * H, 100), r(W * H, 100);
  ImageViewU8 lv = ImageViewU8::make(l.data(), W, H).value();
  ImageViewU8 rv = ImageViewU8::make(r.data(), W, H).value();
  // Repetitive vertical stripes with period 8 px: every 8 px of disparity matches equally well.
  for (int y = 0; y < 50; ++y)
    for (int x = 0; x < W; ++x) lv(x, y) = rv(x, y) = (x % 8) < 4 ? 50 : 200;
  // Lower half: independent noise in left and right (no true match).
  testing::Rng rng(3);
  for (int y = 50; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      lv(x, y) = static_cast<std::uint8_t>(rng.next() & 0xff);
      rv(x, y) = static_cast<std::uint8_t>(rng.next() & 0xff);
    }
  StereoMatcher m;
  StereoConfig sc;
  sc.max_disparity_px = 30;
  ASSERT_TRUE(m.init(sc, test_camera()).is_ok());
  float d = 0, z = 0;
  EXPECT_EQ(m.match_one(lv, rv, 100.5f, 25.0f, d, z), StatusCode::kNotFound);  // stripes: ambiguous
  EXPECT_EQ(m.counters().get(VisionCounter::kStereoAmbiguous), 1u);
  EXPECT_EQ(m.match_one(lv, rv, 100.0f, 75.0f, d, z), StatusCode::kNotFound);  // noise: weak
  EXPECT_EQ(m.counters().get(VisionCounter::kStereoWeak), 1u);
  EXPECT_EQ(m.match_one(lv, rv, 2.0f, 75.0f, d, z), StatusCode::kOutOfRange);
  EXPECT_EQ(m.match_one(lv, rv, 100.0f, 99.0f, d, z), StatusCode::kOutOfRange);
  EXPECT_EQ(m.match_one(lv, rv, std::nanf(""), 50.0f, d, z), StatusCode::kOutOfRange);
  EXPECT_EQ(m.match_one(lv, rv, 1e9f, 50.0f, d, z), StatusCode::kOutOfRange);
  EXPECT_EQ(m.counters().get(VisionCounter::kStereoOutOfBounds), 4u);
  std::vector<std::uint8_t> flat(W * H, 77);
  const ConstImageViewU8 fv = ConstImageViewU8::make(flat.data(), W, H).value();
  EXPECT_EQ(m.match_one(fv, fv, 100.0f, 50.0f, d, z), StatusCode::kDegenerate);
  EXPECT_EQ(m.counters().get(VisionCounter::kStereoFlatPatch), 1u);
}

TEST(Stereo, LeftRightCheckRejectsAMatchThatPrefersAnotherLeftPixel) {
  // Right: texture. Left: a different texture, with the right patch around xr = 100 pasted twice:
  // noisy at xa = 110 (forward match d = 10, ZNCC ~0.9) and exact at xb = 130. The reverse search
  // from xr finds xb, so the forward match at xa is rejected; the one at xb passes (d = 30).
  const int W = 240, H = 60;
  std::vector<std::uint8_t> l(W * H), r(W * H);
  ImageViewU8 lv = ImageViewU8::make(l.data(), W, H).value();
  ImageViewU8 rv = ImageViewU8::make(r.data(), W, H).value();
  testing::texture(lv, 41);
  testing::texture(rv, 42);
  testing::Rng rng(9);
  for (int y = 25; y < 36; ++y)
    for (int x = -5; x <= 5; ++x) {
      const int v = rv(100 + x, y);
      lv(130 + x, y) = static_cast<std::uint8_t>(v);
      const int noisy = v + static_cast<int>((rng.uniform() - 0.5) * 40.0);
      lv(110 + x, y) = static_cast<std::uint8_t>(noisy < 0 ? 0 : (noisy > 255 ? 255 : noisy));
    }
  StereoMatcher m;
  StereoConfig sc;
  sc.min_zncc = 0.6f;
  ASSERT_TRUE(m.init(sc, test_camera()).is_ok());
  float d = 0, z = 0;
  EXPECT_EQ(m.match_one(lv, rv, 110.0f, 30.0f, d, z), StatusCode::kNotFound);
  EXPECT_EQ(m.counters().get(VisionCounter::kStereoLeftRight), 1u);
  ASSERT_TRUE(m.match_one(lv, rv, 130.0f, 30.0f, d, z).is_ok());
  EXPECT_NEAR(d, 30.0f, 0.2f);
  EXPECT_GT(z, 0.99f);
  // Without the check the noisy copy is accepted.
  sc.left_right_check = false;
  ASSERT_TRUE(m.init(sc, test_camera()).is_ok());
  ASSERT_TRUE(m.match_one(lv, rv, 110.0f, 30.0f, d, z).is_ok());
  EXPECT_NEAR(d, 10.0f, 0.5f);
}

TEST(Stereo, RejectsBadConfigAndImages) {
  StereoMatcher m;
  std::vector<StereoPoint> pst(4);
  BoundedVector<StereoPoint> pts(Span<StereoPoint>(pst.data(), pst.size()));
  std::uint8_t px[64] = {};
  const ConstImageViewU8 a = ConstImageViewU8::make(px, 8, 8).value();
  EXPECT_EQ(m.match(a, a, Span<const Corner>(), pts), StatusCode::kNotReady);
  StereoConfig sc;
  sc.patch_radius = 0;
  EXPECT_EQ(m.init(sc, test_camera()), StatusCode::kInvalidArgument);
  sc = StereoConfig{};
  sc.max_disparity_px = sc.min_disparity_px + 1;
  EXPECT_EQ(m.init(sc, test_camera()), StatusCode::kInvalidArgument);
  StereoCamera cam = test_camera();
  cam.baseline_m = 0.0;
  EXPECT_EQ(m.init(StereoConfig{}, cam), StatusCode::kInvalidArgument);
  cam = test_camera();
  cam.focal_px = std::nan("");
  EXPECT_EQ(m.init(StereoConfig{}, cam), StatusCode::kInvalidArgument);
  EXPECT_EQ(m.counters().get(VisionCounter::kBadConfig), 4u);
  ASSERT_TRUE(m.init(StereoConfig{}, test_camera()).is_ok());
  const ConstImageViewU8 b = ConstImageViewU8::make(px, 4, 8).value();
  EXPECT_EQ(m.match(a, b, Span<const Corner>(), pts), StatusCode::kInvalidArgument);
  EXPECT_EQ(m.match(a, ConstImageViewU8(), Span<const Corner>(), pts), StatusCode::kInvalidArgument);
}

TEST(Stereo, OutputCapacityIsReportedNotOverrun) {
  const int W = 240, H = 200;
  std::vector<std::uint8_t> l, r;
  make_pair(l, r, W, H, 9.0, 8);
  const ConstImageViewU8 lv = ConstImageViewU8::make(l.data(), W, H).value();
  const ConstImageViewU8 rv = ConstImageViewU8::make(r.data(), W, H).value();
  std::vector<Corner> cs;
  for (int i = 0; i < 10; ++i) {
    Corner c;
    c.x = 100.0f + 13.0f * i;
    c.y = 60.0f + 11.0f * i;
    cs.push_back(c);
  }
  StereoMatcher m;
  ASSERT_TRUE(m.init(StereoConfig{}, test_camera()).is_ok());
  std::vector<StereoPoint> pst(3);
  BoundedVector<StereoPoint> pts(Span<StereoPoint>(pst.data(), pst.size()));
  EXPECT_EQ(m.match(lv, rv, Span<const Corner>(cs.data(), cs.size()), pts), StatusCode::kCapacityExceeded);
  EXPECT_EQ(pts.size(), 3u);
  EXPECT_EQ(m.counters().get(VisionCounter::kStereoCapReached), 1u);
}

}  // namespace
}  // namespace qnav::vision
