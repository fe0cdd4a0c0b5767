// CameraTilePipeline: the downward camera's tile stage (`qnav route camera`). A frame straight down
// over a textured ground gives keypoints; the navigation frame (nav_T_ground) moves the tile's pose
// and nothing else (the same keypoints in the tile frame); the ground pose is the projection's; a
// frame tilted past the projector's limit is an error.
#include "firmware/pipeline/camera_tile_pipeline.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

namespace {

using namespace qnav;
using namespace qnav::pipeline;

constexpr int kW = 320, kH = 256;

// Blobs of random grey levels (8 px cells, bilinear), a texture Harris finds corners in.
std::vector<std::uint8_t> texture() {
  std::vector<std::uint8_t> px(static_cast<std::size_t>(kW * kH));
  std::uint32_t s = 12345u;
  std::vector<int> cells(static_cast<std::size_t>((kW / 8 + 2) * (kH / 8 + 2)));
  for (int& c : cells) {
    s = s * 1664525u + 1013904223u;
    c = static_cast<int>(s >> 24);
  }
  const int cw = kW / 8 + 2;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const int cx = x / 8, cy = y / 8;
      const double fx = (x % 8) / 8.0, fy = (y % 8) / 8.0;
      const double v = (1 - fx) * (1 - fy) * cells[static_cast<std::size_t>(cy * cw + cx)] +
                       fx * (1 - fy) * cells[static_cast<std::size_t>(cy * cw + cx + 1)] +
                       (1 - fx) * fy * cells[static_cast<std::size_t>((cy + 1) * cw + cx)] +
                       fx * fy * cells[static_cast<std::size_t>((cy + 1) * cw + cx + 1)];
      px[static_cast<std::size_t>(y * kW + x)] = static_cast<std::uint8_t>(v);
    }
  return px;
}

CameraFrame frame_down(const std::vector<std::uint8_t>& px) {
  CameraFrame f;
  f.image = ConstImageViewU8::unchecked(px.data(), kW, kH, kW);
  f.intrinsics.fx_px = f.intrinsics.fy_px = 333.0;
  f.intrinsics.cu_px = kW / 2.0;
  f.intrinsics.cv_px = kH / 2.0;
  Mat3d body_R_cam;
  body_R_cam << 0, -1, 0, 1, 0, 0, 0, 0, 1;  // camera x starboard, y aft, z down; heading north
  f.ned_T_cam = Pose3{body_R_cam, Vec3d(2.0, 1.0, -0.8)};
  f.ground_down_m = 0.0;
  f.heading_rad = 0.0;
  return f;
}

TEST(CameraTilePipeline, NavigationFrameMovesThePoseOnly) {
  CameraTilePipeline p;
  ASSERT_TRUE(p.init(camera_tile_settings()).is_ok());
  const std::vector<std::uint8_t> px = texture();
  CameraFrame f = frame_down(px);
  route::RouteNode a, b;
  Pose2 ground_a, ground_b;
  ASSERT_TRUE(p.push_frame(f, a, &ground_a).is_ok());
  EXPECT_GE(a.keypoints.size(), 16u);
  // The tile pose is the camera nadir: N 2, E 1 (within a raster pixel of 4 mm).
  EXPECT_NEAR(a.meta.pose.x_m, 2.0, 0.004);
  EXPECT_NEAR(a.meta.pose.y_m, 1.0, 0.004);
  EXPECT_EQ(a.meta.pose.x_m, ground_a.x_m);
  f.nav_T_ground = Pose2{3.0, -2.0, 0.5};
  ASSERT_TRUE(p.push_frame(f, b, &ground_b).is_ok());
  EXPECT_EQ(ground_b.x_m, ground_a.x_m);
  EXPECT_EQ(ground_b.y_m, ground_a.y_m);
  const Vec2d want = f.nav_T_ground.apply(Vec2d(ground_a.x_m, ground_a.y_m));
  EXPECT_NEAR(b.meta.pose.x_m, want.x(), 1e-12);
  EXPECT_NEAR(b.meta.pose.y_m, want.y(), 1e-12);
  EXPECT_EQ(b.meta.pose.heading_rad, a.meta.pose.heading_rad);
  ASSERT_EQ(a.keypoints.size(), b.keypoints.size());
  for (std::size_t i = 0; i < a.keypoints.size(); ++i) {
    EXPECT_NEAR(a.keypoints[i].x_m, b.keypoints[i].x_m, 1e-9);
    EXPECT_NEAR(a.keypoints[i].y_m, b.keypoints[i].y_m, 1e-9);
  }
  const route::RouteParams rp = camera_route_params(p.settings(), 0.3, 0.77);
  EXPECT_EQ(rp.sensor, route::SensorKind::kCamera);
  EXPECT_EQ(rp.max_keypoints, 128u);
  EXPECT_FLOAT_EQ(rp.pixel_m, 0.004f);
}

TEST(CameraTilePipeline, TiltedFrameIsAnError) {
  CameraTilePipeline p;
  ASSERT_TRUE(p.init(camera_tile_settings()).is_ok());
  const std::vector<std::uint8_t> px = texture();
  CameraFrame f = frame_down(px);
  const double a = 70.0 * M_PI / 180.0;  // optical axis 70 deg from straight down (limit 60)
  Mat3d tilt;
  tilt << 1, 0, 0, 0, std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a);
  f.ned_T_cam.R = f.ned_T_cam.R * tilt;
  route::RouteNode n;
  EXPECT_FALSE(p.push_frame(f, n).is_ok());
}

}  // namespace
