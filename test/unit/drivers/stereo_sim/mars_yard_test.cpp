#include "drivers/stereo_sim/mars_yard.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <vector>

namespace qnav::sim {
namespace {

TEST(StereoBench, HasThePapersGeometry) {
  const StereoBench b;
  EXPECT_EQ(b.width(), 320);
  EXPECT_EQ(b.height(), 256);
  EXPECT_NEAR(b.focal_px(), 8.0 / 0.024, 1e-9);  // f / wpix with 4x subsampled 6 um cells
  const Pose3 c = b.rover_T_left();
  EXPECT_NEAR(c.R.determinant(), 1.0, 1e-12);
  // Optical axis 70 degrees below the horizon, looking forward; image x points to the rover's right.
  EXPECT_NEAR(std::asin(-c.R.col(2).z()), deg_to_rad(70.0), 1e-12);
  EXPECT_GT(c.R.col(2).x(), 0.0);
  EXPECT_NEAR(c.R.col(0).y(), -1.0, 1e-12);
  EXPECT_NEAR(c.t.z(), 0.8, 1e-12);
}

TEST(MarsYard, RaysLandOnTheTerrainAndReprojectToTheirPixel) {
  const MarsYardTerrain terrain;
  const StereoBench bench;
  const Pose3 cam = Pose3{Mat3d::Identity(), Vec3d(3.0, -1.0, 0.0)}.compose(bench.rover_T_left());
  int hits = 0;
  for (double v = 5; v < 256; v += 25) {
    for (double u = 5; u < 320; u += 35) {
      Vec3d p;
      ASSERT_TRUE(cast_ray(terrain, bench, cam, u, v, p));
      ++hits;
      EXPECT_NEAR(p.z(), terrain.height_m(p.x(), p.y()), 1e-4);
      const Vec3d pc = cam.inverse().apply(p);
      EXPECT_NEAR(bench.focal_px() * pc.x() / pc.z() + bench.cu_px(), u, 1e-6);
      EXPECT_NEAR(bench.focal_px() * pc.y() / pc.z() + bench.cv_px(), v, 1e-6);
      EXPECT_GT(pc.z(), 0.6);
      EXPECT_LT(pc.z(), 1.4);
    }
  }
  EXPECT_GT(hits, 90);
}

double zncc_at(const Image<std::uint8_t>& a, int xa, const Image<std::uint8_t>& b, int xb, int y, int r) {
  double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
  const int n = (2 * r + 1) * (2 * r + 1);
  for (int dy = -r; dy <= r; ++dy)
    for (int dx = -r; dx <= r; ++dx) {
      const double va = a(xa + dx, y + dy), vb = b(xb + dx, y + dy);
      sa += va;
      sb += vb;
      saa += va * va;
      sbb += vb * vb;
      sab += va * vb;
    }
  const double cov = sab - sa * sb / n, vara = saa - sa * sa / n, varb = sbb - sb * sb / n;
  return cov / std::sqrt(vara * varb + 1e-12);
}

TEST(MarsYard, RenderedPairHasTextureAndTrueDisparities) {
  const MarsYardTerrain terrain;
  const StereoBench bench;
  Result<Image<std::uint8_t>> l = Image<std::uint8_t>::allocate(bench.width(), bench.height());
  Result<Image<std::uint8_t>> r = Image<std::uint8_t>::allocate(bench.width(), bench.height());
  ASSERT_TRUE(l.is_ok() && r.is_ok());
  const Pose3 cam = bench.rover_T_left();
  ASSERT_TRUE(render_stereo(terrain, bench, cam, 1, l->view(), r->view()).is_ok());
  double s = 0, s2 = 0;
  for (int y = 0; y < bench.height(); ++y)
    for (int x = 0; x < bench.width(); ++x) {
      s += (*l)(x, y);
      s2 += double((*l)(x, y)) * (*l)(x, y);
    }
  const double n = bench.width() * bench.height();
  const double stddev = std::sqrt(s2 / n - (s / n) * (s / n));
  EXPECT_GT(stddev, 12.0);
  EXPECT_GT(s / n, 60.0);
  EXPECT_LT(s / n, 200.0);
  // At the true disparity d = f b / Z the right patch matches; 3 px off it does not.
  int good = 0, total = 0;
  for (int y = 30; y < 230; y += 40) {
    for (int x = 60; x < 300; x += 40) {
      Vec3d p;
      ASSERT_TRUE(cast_ray(terrain, bench, cam, x, y, p));
      const double z = cam.inverse().apply(p).z();
      const int d = static_cast<int>(std::lround(bench.focal_px() * bench.baseline_m / z));
      const double at = zncc_at(*l, x, *r, x - d, y, 4);
      const double off = zncc_at(*l, x, *r, x - d - 3, y, 4);
      ++total;
      if (at > 0.8 && at > off + 0.2) ++good;
    }
  }
  EXPECT_GE(good, total * 8 / 10);
  // Deterministic, and the sensor noise depends on the frame seed.
  Result<Image<std::uint8_t>> l2 = Image<std::uint8_t>::allocate(bench.width(), bench.height());
  Result<Image<std::uint8_t>> r2 = Image<std::uint8_t>::allocate(bench.width(), bench.height());
  ASSERT_TRUE(render_stereo(terrain, bench, cam, 1, l2->view(), r2->view()).is_ok());
  EXPECT_EQ(std::memcmp(l->data(), l2->data(), n), 0);
  ASSERT_TRUE(render_stereo(terrain, bench, cam, 2, l2->view(), r2->view()).is_ok());
  EXPECT_NE(std::memcmp(l->data(), l2->data(), n), 0);
  Result<Image<std::uint8_t>> small = Image<std::uint8_t>::allocate(10, 10);
  EXPECT_FALSE(render_stereo(terrain, bench, cam, 1, small->view(), r2->view()).is_ok());
}

TEST(MarsYardTrajectory, StepsAreInThePapersRange) {
  MarsYardTrajectory t;
  Vec3d prev = t.current().world_T_rover.t;
  double time = 0.0;
  for (int i = 0; i < 200; ++i) {
    const RoverSample& s = t.next();
    const double step = (s.world_T_rover.t - prev).norm();
    EXPECT_GE(step, 0.15 - 1e-9);
    EXPECT_LE(step, 0.25 + 1e-9);
    EXPECT_NEAR(s.time_s - time, step / 0.02, 1e-9);
    time = s.time_s;
    prev = s.world_T_rover.t;
  }
  EXPECT_GT(prev.x(), 30.0);             // rectilinear: 200 steps of 0.2 m go ~40 m along x
  EXPECT_LT(std::fabs(prev.y()), 3.0);
}

}  // namespace
}  // namespace qnav::sim
