#include "nav/core/geometry.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace qnav {
namespace {

TEST(Geometry, WrapAngleStaysInHalfOpenInterval) {
  EXPECT_NEAR(wrap_angle_rad(3.0 * kPi), kPi, 1e-12);
  EXPECT_NEAR(wrap_angle_rad(-kPi), kPi, 1e-12);
  EXPECT_NEAR(wrap_angle_rad(2.0 * kPi + 0.25), 0.25, 1e-12);
  EXPECT_NEAR(wrap_angle_rad(-0.25), -0.25, 1e-12);
  EXPECT_TRUE(std::isnan(wrap_angle_rad(std::nan(""))));
  EXPECT_TRUE(std::isnan(wrap_angle_rad(std::numeric_limits<double>::infinity())));
}

TEST(Geometry, Pose2ComposeAndInverseRoundTrip) {
  const Pose2 a{1.0, 2.0, deg_to_rad(90.0)};
  const Pose2 b{3.0, 0.0, deg_to_rad(-30.0)};
  const Pose2 ab = a.compose(b);
  // b's translation (3, 0) rotated by 90 deg is (0, 3), plus a's (1, 2).
  EXPECT_NEAR(ab.x_m, 1.0, 1e-12);
  EXPECT_NEAR(ab.y_m, 5.0, 1e-12);
  EXPECT_NEAR(ab.heading_rad, deg_to_rad(60.0), 1e-12);
  const Pose2 id = ab.compose(ab.inverse());
  EXPECT_NEAR(id.x_m, 0.0, 1e-12);
  EXPECT_NEAR(id.y_m, 0.0, 1e-12);
  EXPECT_NEAR(id.heading_rad, 0.0, 1e-12);
}

TEST(Geometry, Pose3InverseAndRpyConvention) {
  const Mat3d R = rotation_from_rpy(0.1, -0.2, 1.3);
  EXPECT_NEAR((R * R.transpose() - Mat3d::Identity()).norm(), 0.0, 1e-12);
  EXPECT_NEAR(R.determinant(), 1.0, 1e-12);
  // Pure yaw of 90 deg maps x to y.
  const Vec3d x = rotation_from_rpy(0, 0, kPi / 2) * Vec3d::UnitX();
  EXPECT_NEAR((x - Vec3d::UnitY()).norm(), 0.0, 1e-12);
  const Pose3 p{R, Vec3d(1, 2, 3)};
  const Pose3 q = p.compose(p.inverse());
  EXPECT_NEAR((q.R - Mat3d::Identity()).norm(), 0.0, 1e-12);
  EXPECT_NEAR(q.t.norm(), 0.0, 1e-12);
  EXPECT_NEAR(rotation_angle_rad(rotation_from_rpy(0, 0, 0.5)), 0.5, 1e-9);
  EXPECT_TRUE(p.is_finite());
}

TEST(Geometry, RectIntersection) {
  const RectI a{0, 0, 10, 10};
  const RectI b{5, -5, 10, 10};
  const RectI c = a.intersect(b);
  EXPECT_EQ(c.x, 5);
  EXPECT_EQ(c.y, 0);
  EXPECT_EQ(c.width, 5);
  EXPECT_EQ(c.height, 5);
  EXPECT_TRUE(a.intersect(RectI{20, 20, 1, 1}).empty());
  EXPECT_TRUE(a.contains(9, 9));
  EXPECT_FALSE(a.contains(10, 9));
}

}  // namespace
}  // namespace qnav
