#include "nav/vision/rectify.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "test/support/alloc_guard.hpp"

namespace qnav::vision {
namespace {

// EuRoC V1_01 cam0 / cam1 (sensor.yaml), hard-coded so the test runs on every target.
PinholeRadTan euroc_cam0() {
  PinholeRadTan c;
  c.fx = 458.654;
  c.fy = 457.296;
  c.cx = 367.215;
  c.cy = 248.375;
  c.k1 = -0.28340811;
  c.k2 = 0.07395907;
  c.p1 = 0.00019359;
  c.p2 = 1.76187114e-05;
  c.width = 752;
  c.height = 480;
  return c;
}
PinholeRadTan euroc_cam1() {
  PinholeRadTan c;
  c.fx = 457.587;
  c.fy = 456.134;
  c.cx = 379.999;
  c.cy = 255.238;
  c.k1 = -0.28368365;
  c.k2 = 0.07451284;
  c.p1 = -0.00010473;
  c.p2 = -3.55590700e-05;
  c.width = 752;
  c.height = 480;
  return c;
}
Pose3 euroc_T_BS(const double d[16]) {
  Pose3 p;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) p.R(r, c) = d[4 * r + c];
    p.t(r) = d[4 * r + 3];
  }
  return p;
}
Pose3 euroc_T_left_right() {
  const double b0[16] = {0.0148655429818, -0.999880929698, 0.00414029679422, -0.0216401454975,
                         0.999557249008,  0.0149672133247, 0.025715529948,   -0.064676986768,
                         -0.0257744366974, 0.00375618835797, 0.999660727178, 0.00981073058949,
                         0,               0,               0,               1};
  const double b1[16] = {0.0125552670891, -0.999755099723, 0.0182237714554, -0.0198435579556,
                         0.999598781151,  0.0130119051815, 0.0251588363115, 0.0453689425024,
                         -0.0253898008918, 0.0179005838253, 0.999517347078, 0.00786212447038,
                         0,               0,               0,               1};
  Pose3 p0 = euroc_T_BS(b0), p1 = euroc_T_BS(b1);
  // The yaml rotations are orthonormal to ~1e-9; re-orthonormalise to be safe.
  p0.R = Eigen::Quaterniond(p0.R).normalized().toRotationMatrix();
  p1.R = Eigen::Quaterniond(p1.R).normalized().toRotationMatrix();
  return p0.inverse().compose(p1);
}

Mat3d K_of(const PinholeRadTan& c) {
  Mat3d K = Mat3d::Identity();
  K(0, 0) = c.fx;
  K(1, 1) = c.fy;
  K(0, 2) = c.cx;
  K(1, 2) = c.cy;
  return K;
}

// Raw pixel of a 3D point in a camera frame (with refraction and distortion).
bool project(const PinholeRadTan& c, const FlatPortRefraction& port, const Vec3d& p, Vec2d& px) {
  if (p.z() <= 0) return false;
  Vec2d xy(p.x() / p.z(), p.y() / p.z());
  if (port.enabled) {
    const double r = xy.norm();
    double ra = 0;
    if (r > 0) {
      if (!refract_radius(r, port.index_ratio, ra)) return false;
      xy *= ra / r;
    }
  }
  const Vec2d d = distort_normalised(c, xy);
  px = Vec2d(c.fx * d.x() + c.cx, c.fy * d.y() + c.cy);
  return true;
}

double smooth_scene(double x, double y) {  // a smooth pattern on normalised image coordinates
  return 128.0 + 60.0 * std::sin(9.0 * x + 1.0) * std::cos(7.0 * y - 0.5) + 30.0 * std::sin(17.0 * x * y);
}

TEST(Rectify, UndistortInvertsDistortOverTheImage) {
  const PinholeRadTan c = euroc_cam0();
  double worst = 0;
  for (int v = 0; v < c.height; v += 20)
    for (int u = 0; u < c.width; u += 20) {
      const Vec2d xd((u - c.cx) / c.fx, (v - c.cy) / c.fy);
      Vec2d xy;
      ASSERT_TRUE(undistort_normalised(c, xd, xy)) << u << "," << v;
      worst = std::max(worst, (distort_normalised(c, xy) - xd).norm());
    }
  EXPECT_LT(worst, 1e-9);
}

TEST(Rectify, RefractionFollowsUnderwaterEq1) {
  double ra = 0;
  ASSERT_TRUE(refract_radius(0.0, 1.33, ra));
  EXPECT_EQ(ra, 0.0);
  ASSERT_TRUE(refract_radius(1e-4, 1.33, ra));
  EXPECT_NEAR(ra / 1e-4, 1.33, 1e-6);  // paraxial: r_air = n r_water
  const double r = 0.5;                 // 26.6 deg in water
  ASSERT_TRUE(refract_radius(r, 1.33, ra));
  EXPECT_NEAR(ra, std::tan(std::asin(1.33 * std::sin(std::atan(r)))), 1e-12);
  EXPECT_GT(ra, 1.33 * r);  // grows faster than linear off-axis (pincushion)
  EXPECT_FALSE(refract_radius(1.2, 1.33, ra));  // 50 deg in water: past the critical angle
  EXPECT_FALSE(refract_radius(std::nan(""), 1.33, ra));
}

TEST(Rectify, IdentityTableReproducesTheImage) {
  PinholeRadTan c;
  c.fx = c.fy = 100;
  c.cx = 31.5;
  c.cy = 23.5;
  c.width = 64;
  c.height = 48;
  RemapConfig rc;
  rc.max_width = 64;
  rc.max_height = 48;
  ArenaStorage arena(64 * 48 * 8);
  RemapTable t;
  ASSERT_TRUE(t.init(rc, arena).is_ok());
  ASSERT_TRUE(t.build_undistort(c, FlatPortRefraction{}).is_ok());
  std::vector<std::uint8_t> src(64 * 48), dst(64 * 48, 0);
  for (std::size_t i = 0; i < src.size(); ++i) src[i] = static_cast<std::uint8_t>((i * 37) % 251);
  ASSERT_TRUE(t.apply(ConstImageViewU8::make(src.data(), 64, 48).value(), ImageViewU8::make(dst.data(), 64, 48).value()).is_ok());
  for (int y = 0; y < 47; ++y)
    for (int x = 0; x < 63; ++x) ASSERT_EQ(dst[y * 64 + x], src[y * 64 + x]) << x << "," << y;
  // The last column/row is sampled from its neighbour with weight 1/256 (no pixel beyond the edge).
  for (int y = 0; y < 48; ++y) EXPECT_NEAR(dst[y * 64 + 63], src[y * 64 + 63], 1) << y;
  for (int x = 0; x < 64; ++x) EXPECT_NEAR(dst[47 * 64 + x], src[47 * 64 + x], 1) << x;
  EXPECT_EQ(t.valid_pixels(), 64u * 48u);
}

// Renders the raw image a camera (distortion, optional port) sees of smooth_scene, corrects it with a
// table built for table_port, and returns the mean absolute error against the ideal pinhole image.
double correction_error(const FlatPortRefraction& port, const FlatPortRefraction& table_port, double& worst) {
  // EuRoC cam0 at 1/4 scale (188 x 120): same field of view and distortion, 16x fewer pixels (qemu).
  PinholeRadTan c = euroc_cam0();
  c.fx /= 4;
  c.fy /= 4;
  c.cx = (c.cx + 0.5) / 4 - 0.5;
  c.cy = (c.cy + 0.5) / 4 - 0.5;
  c.width /= 4;
  c.height /= 4;
  std::vector<std::uint8_t> raw(static_cast<std::size_t>(c.width * c.height));
  for (int v = 0; v < c.height; ++v)
    for (int u = 0; u < c.width; ++u) {
      Vec2d xy;
      const Vec2d xd((u - c.cx) / c.fx, (v - c.cy) / c.fy);
      double val = 0;
      if (undistort_normalised(c, xd, xy)) {
        if (port.enabled) {  // air ray -> water ray
          const double ra = xy.norm();
          if (ra > 0) xy *= std::tan(std::asin(std::sin(std::atan(ra)) / port.index_ratio)) / ra;
        }
        val = smooth_scene(xy.x(), xy.y());
      }
      raw[static_cast<std::size_t>(v * c.width + u)] = static_cast<std::uint8_t>(std::lround(val));
    }
  RemapConfig rc;
  rc.max_width = c.width;
  rc.max_height = c.height;
  ArenaStorage arena(static_cast<std::size_t>(c.width * c.height) * 8);
  RemapTable t;
  EXPECT_TRUE(t.init(rc, arena).is_ok());
  EXPECT_TRUE(t.build_undistort(c, table_port).is_ok());
  std::vector<std::uint8_t> out(raw.size());
  ImageViewU8 ov = ImageViewU8::make(out.data(), c.width, c.height).value();
  Status s;
  QNAV_EXPECT_NO_ALLOC(s = t.apply(ConstImageViewU8::make(raw.data(), c.width, c.height).value(), ov));
  EXPECT_TRUE(s.is_ok());
  double sum = 0;
  worst = 0;
  std::size_t n = 0;
  for (int v = 2; v < c.height - 2; ++v)
    for (int u = 2; u < c.width - 2; ++u) {
      float sx, sy;
      if (!t.source_of(u, v, sx, sy)) continue;
      const double ideal = smooth_scene((u - c.cx) / c.fx, (v - c.cy) / c.fy);
      const double e = std::fabs(ov(u, v) - ideal);
      sum += e;
      worst = std::max(worst, e);
      ++n;
    }
  EXPECT_GT(n, static_cast<std::size_t>(c.width * c.height / 3));
  return n > 0 ? sum / static_cast<double>(n) : 1e9;
}

TEST(Rectify, TableUndoesRadialTangentialDistortion) {
  double worst = 0;
  EXPECT_LT(correction_error(FlatPortRefraction{}, FlatPortRefraction{}, worst), 1.0);  // grey levels
  EXPECT_LT(worst, 8.0);
}

TEST(Rectify, TableUndoesFlatPortRefractionComposedWithDistortion) {
  FlatPortRefraction port;
  port.enabled = true;
  double worst = 0;
  EXPECT_LT(correction_error(port, port, worst), 1.0);
  EXPECT_LT(worst, 8.0);
  // The same raw image corrected without the refraction term is far off.
  EXPECT_GT(correction_error(port, FlatPortRefraction{}, worst), 10.0);
  // Without the refraction term the same image is visibly wrong (the test can fail).
  const PinholeRadTan c = euroc_cam0();
  Vec2d with, without;
  const Vec3d p(0.3, 0.2, 1.0);  // a point in water
  ASSERT_TRUE(project(c, port, p, with));
  ASSERT_TRUE(project(c, FlatPortRefraction{}, p, without));
  EXPECT_GT((with - without).norm(), 20.0);
  Vec2d back;
  ASSERT_TRUE(rectify_point(c, Mat3d::Identity(), K_of(c), port, with, back));
  EXPECT_NEAR(back.x(), c.fx * 0.3 + c.cx, 1e-6);
  EXPECT_NEAR(back.y(), c.fy * 0.2 + c.cy, 1e-6);
}

TEST(Rectify, StereoRectificationPutsEpipolarLinesOnRows) {
  const PinholeRadTan l = euroc_cam0(), r = euroc_cam1();
  const Pose3 T = euroc_T_left_right();
  Result<StereoRectification> rr = stereo_rectify(l, r, T, 752, 480);
  ASSERT_TRUE(rr.is_ok()) << rr.status().message();
  const StereoRectification& s = *rr;
  EXPECT_NEAR(s.baseline_m, 0.110, 0.002);
  // 3D points in front of the rig: project into both raw images, rectify each point, compare rows.
  const Pose3 T_rl = T.inverse();
  double worst_dy = 0, worst_dd = 0;
  int n = 0;
  for (double z : {1.5, 4.0, 20.0})
    for (double x = -0.8; x <= 0.8; x += 0.2)
      for (double y = -0.5; y <= 0.5; y += 0.2) {
        const Vec3d pl(x * z, y * z, z);
        const Vec3d pr = T_rl.apply(pl);
        Vec2d ql, qr, ol, orr;
        if (!project(l, FlatPortRefraction{}, pl, ql) || !project(r, FlatPortRefraction{}, pr, qr)) continue;
        if (ql.x() < 0 || ql.y() < 0 || ql.x() > 751 || ql.y() > 479 || qr.x() < 0 || qr.y() < 0 || qr.x() > 751 || qr.y() > 479)
          continue;
        ASSERT_TRUE(rectify_point(l, s.R_left, s.K, FlatPortRefraction{}, ql, ol));
        ASSERT_TRUE(rectify_point(r, s.R_right, s.K, FlatPortRefraction{}, qr, orr));
        worst_dy = std::max(worst_dy, std::fabs(ol.y() - orr.y()));
        // Disparity = f b / depth along the rectified optical axis.
        const double zr = (s.R_left.transpose() * pl).z();
        worst_dd = std::max(worst_dd, std::fabs((ol.x() - orr.x()) - s.K(0, 0) * s.baseline_m / zr));
        ++n;
      }
  EXPECT_GT(n, 100);
  EXPECT_LT(worst_dy, 1e-6);
  EXPECT_LT(worst_dd, 1e-6);
  // The rectified view keeps most of the image valid.
  RemapConfig rc;
  rc.max_width = 752;
  rc.max_height = 480;
  ArenaStorage arena(752 * 480 * 8);
  RemapTable t;
  ASSERT_TRUE(t.init(rc, arena).is_ok());
  ASSERT_TRUE(t.build(l, s.K, s.R_left, FlatPortRefraction{}, 752, 480).is_ok());
  EXPECT_GT(t.valid_pixels(), 752u * 480u * 8 / 10);
}

TEST(Rectify, StridedSourceGivesTheSameOutputAsPacked) {
  PinholeRadTan c = euroc_cam0();
  c.fx /= 4;
  c.fy /= 4;
  c.cx /= 4;
  c.cy /= 4;
  c.width /= 4;
  c.height /= 4;
  const int W = c.width, H = c.height, S = W + 13;
  std::vector<std::uint8_t> packed(static_cast<std::size_t>(W * H)), strided(static_cast<std::size_t>(S * H), 0xEE);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const auto v = static_cast<std::uint8_t>((x * 7 + y * 13 + (x * y) % 11) % 256);
      packed[static_cast<std::size_t>(y * W + x)] = v;
      strided[static_cast<std::size_t>(y * S + x)] = v;
    }
  RemapConfig rc;
  rc.max_width = W;
  rc.max_height = H;
  rc.fill_value = 7;
  ArenaStorage arena(static_cast<std::size_t>(W * H) * 8 + 64);
  RemapTable t;
  ASSERT_TRUE(t.init(rc, arena).is_ok());
  FlatPortRefraction port;
  port.enabled = true;  // refraction narrows the view: some output pixels get the fill value
  ASSERT_TRUE(t.build_undistort(c, port).is_ok());
  ASSERT_LT(t.valid_pixels(), static_cast<std::size_t>(W * H));
  std::vector<std::uint8_t> a(packed.size()), b(packed.size());
  ASSERT_TRUE(t.apply(ConstImageViewU8::make(packed.data(), W, H).value(), ImageViewU8::make(a.data(), W, H).value()).is_ok());
  ASSERT_TRUE(t.apply(ConstImageViewU8::make(strided.data(), W, H, S).value(), ImageViewU8::make(b.data(), W, H).value()).is_ok());
  EXPECT_EQ(a, b);
  EXPECT_EQ(a[0], 7);  // the corner ray, refracted, lands outside the raw image: fill value
}

TEST(Rectify, BadCalibrationIsRejected) {
  PinholeRadTan c = euroc_cam0();
  c.k1 = std::nan("");
  EXPECT_EQ(validate(c), StatusCode::kInvalidArgument);
  c = euroc_cam0();
  c.fx = 0;
  EXPECT_EQ(validate(c), StatusCode::kDegenerate);
  c = euroc_cam0();
  c.width = 0;
  EXPECT_EQ(validate(c), StatusCode::kInvalidArgument);
  Pose3 T = euroc_T_left_right();
  T.R(0, 0) = 2.0;
  EXPECT_EQ(stereo_rectify(euroc_cam0(), euroc_cam1(), T, 752, 480).status(), StatusCode::kInvalidArgument);
  T = euroc_T_left_right();
  T.t.setZero();
  EXPECT_EQ(stereo_rectify(euroc_cam0(), euroc_cam1(), T, 752, 480).status(), StatusCode::kDegenerate);
  T = euroc_T_left_right();
  T.t = Vec3d(0, 0, 0.1);
  EXPECT_EQ(stereo_rectify(euroc_cam0(), euroc_cam1(), T, 752, 480).status(), StatusCode::kDegenerate);

  RemapTable t;
  std::uint8_t px[16] = {};
  EXPECT_EQ(t.build_undistort(euroc_cam0(), FlatPortRefraction{}), StatusCode::kNotReady);
  EXPECT_EQ(t.apply(ConstImageViewU8::make(px, 4, 4).value(), ImageViewU8::make(px, 4, 4).value()), StatusCode::kNotReady);
  RemapConfig rc;
  rc.max_width = 100;
  rc.max_height = 100;
  ArenaStorage arena(100 * 100 * 8);
  ASSERT_TRUE(t.init(rc, arena).is_ok());
  EXPECT_EQ(t.build_undistort(euroc_cam0(), FlatPortRefraction{}), StatusCode::kInvalidArgument);  // 752 > 100
  Mat3d K = K_of(euroc_cam0());
  K(1, 1) = 0;
  EXPECT_EQ(t.build(euroc_cam0(), K, Mat3d::Identity(), FlatPortRefraction{}, 50, 50), StatusCode::kDegenerate);
  K = K_of(euroc_cam0());
  K(0, 2) = std::nan("");
  EXPECT_EQ(t.build(euroc_cam0(), K, Mat3d::Identity(), FlatPortRefraction{}, 50, 50), StatusCode::kInvalidArgument);
  Mat3d notR = Mat3d::Identity();
  notR(2, 2) = -1;  // a reflection
  EXPECT_EQ(t.build(euroc_cam0(), K_of(euroc_cam0()), notR, FlatPortRefraction{}, 50, 50), StatusCode::kInvalidArgument);
  FlatPortRefraction bad;
  bad.enabled = true;
  bad.index_ratio = std::nan("");
  EXPECT_EQ(t.build(euroc_cam0(), K_of(euroc_cam0()), Mat3d::Identity(), bad, 50, 50), StatusCode::kInvalidArgument);
  ASSERT_TRUE(t.build(euroc_cam0(), K_of(euroc_cam0()), Mat3d::Identity(), FlatPortRefraction{}, 50, 50).is_ok());
  std::vector<std::uint8_t> big(752 * 480), out(50 * 50);
  EXPECT_EQ(t.apply(ConstImageViewU8::make(big.data(), 751, 480).value(), ImageViewU8::make(out.data(), 50, 50).value()),
            StatusCode::kInvalidArgument);
  EXPECT_EQ(t.apply(ConstImageViewU8::make(big.data(), 752, 480).value(), ImageViewU8::make(out.data(), 49, 50).value()),
            StatusCode::kInvalidArgument);
  EXPECT_TRUE(t.apply(ConstImageViewU8::make(big.data(), 752, 480).value(), ImageViewU8::make(out.data(), 50, 50).value()).is_ok());
}

}  // namespace
}  // namespace qnav::vision
