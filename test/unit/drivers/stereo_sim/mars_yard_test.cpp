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
