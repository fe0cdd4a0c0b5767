#include "nav/route/camera_tile.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "test/support/alloc_guard.hpp"

namespace qnav::route {
namespace {

constexpr int kW = 200, kH = 160;
const CameraIntrinsics kK{200.0, 200.0, 99.5, 79.5};

// Camera looking down from (north, east, -altitude) with compass heading and small roll / pitch;
// camera x = starboard, y = aft, z = down (the convention qnav route camera uses).
Pose3 camera_pose(double north, double east, double altitude, double heading, double roll, double pitch) {
  Mat3d body_R_cam;
  body_R_cam << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  return Pose3{rotation_from_rpy(roll, pitch, heading) * body_R_cam, Vec3d(north, east, -altitude)};
}

// The ground point (NED, down = 0) seen by image pixel (u, v): the ray from the camera, independently
// of the projector (which goes the other way, ground -> image).
Vec3d ground_of_pixel(const Pose3& cam, double u, double v) {
  const Vec3d ray = cam.R * Vec3d((u - kK.cu_px) / kK.fx_px, (v - kK.cv_px) / kK.fy_px, 1.0);
  const double s = -cam.t.z() / ray.z();
  return cam.t + s * ray;
}

// A 1 cm raster of 256 x 256 (2.56 m square).
CameraTileConfig config_1cm() {
  CameraTileConfig c;
  c.resolution_m = 0.01;
  c.width_px = c.height_px = 256;
  return c;
}

struct Buffers {
  std::vector<std::uint8_t> img = std::vector<std::uint8_t>(kW * kH, 0);
  std::vector<float> out = std::vector<float>(256 * 256, 0.0f);
  std::vector<std::uint8_t> cov = std::vector<std::uint8_t>(256 * 256, 0);
  ConstImageViewU8 image() const { return ConstImageViewU8::make(img.data(), kW, kH).value(); }
  ImageViewF32 raster() { return ImageViewF32::make(out.data(), 256, 256).value(); }
  ImageViewU8 coverage() { return ImageViewU8::make(cov.data(), 256, 256).value(); }
};

TEST(CameraTile, ABrightSpotLandsOnItsGroundPointWhateverTheAttitude) {
  CameraTileProjector p;
  ASSERT_TRUE(p.init(config_1cm()).is_ok());
  const double headings[] = {0.0, 0.5, 3.0, -2.0};
  for (const double h : headings) {
    const Pose3 cam = camera_pose(10.0, 5.0, 2.0, h, deg_to_rad(5.0), deg_to_rad(-3.0));
    Buffers b;
    const int u0 = 140, v0 = 50;
    for (int dv = -1; dv <= 1; ++dv)
      for (int du = -1; du <= 1; ++du) b.img[static_cast<std::size_t>((v0 + dv) * kW + u0 + du)] = (du == 0 && dv == 0) ? 255 : 120;
    TileGeometry g;
    const Result<double> cov = p.project(b.image(), kK, cam, 0.0, h, b.raster(), b.coverage(), g);
    ASSERT_TRUE(cov.is_ok()) << cov.status().message();
    // The footprint (2 m x 1.6 m at 2 m altitude) lies inside the 2.56 m raster: covered fraction
    // about its area over the raster's (0.49), roll and pitch aside.
    EXPECT_GT(cov.value(), 0.35);
    EXPECT_LT(cov.value(), 0.65);
    // Centroid of the spot in the raster -> NED.
    double sw = 0.0, sc = 0.0, sr = 0.0;
    for (int r = 0; r < 256; ++r)
      for (int col = 0; col < 256; ++col) {
        const double v = static_cast<double>(b.out[static_cast<std::size_t>(r * 256 + col)]);
        if (v > 30.0) {
          sw += v;
          sc += v * col;
          sr += v * r;
        }
      }
    ASSERT_GT(sw, 0.0);
    const double north = g.origin_north_m - (sr / sw + 0.5) * g.resolution_m;
    const double east = g.origin_east_m + (sc / sw + 0.5) * g.resolution_m;
    const Vec3d want = ground_of_pixel(cam, u0, v0);
    EXPECT_NEAR(north, want.x(), 0.01) << "heading " << h;
    EXPECT_NEAR(east, want.y(), 0.01) << "heading " << h;
    // The raster is centred on the optical axis's ground point (the image centre's ray); the tile
    // pose is the camera's nadir (the vehicle's position; roll 5 deg and pitch -3 deg at 2 m put the
    // two ~0.2 m apart), with the given heading.
    const Vec3d centre = ground_of_pixel(cam, kK.cu_px, kK.cv_px);
    EXPECT_NEAR(g.origin_north_m - 0.5 * 256 * g.resolution_m, centre.x(), 1e-9);
    EXPECT_NEAR(g.origin_east_m + 0.5 * 256 * g.resolution_m, centre.y(), 1e-9);
    EXPECT_NEAR(g.pose.x_m, cam.t.x(), 1e-12);
    EXPECT_NEAR(g.pose.y_m, cam.t.y(), 1e-12);
    EXPECT_GT(std::hypot(centre.x() - cam.t.x(), centre.y() - cam.t.y()), 0.15);
    EXPECT_EQ(g.pose.heading_rad, h);
    // North is up in the raster: forward (heading 0) is towards row 0.
    if (h == 0.0) {
      EXPECT_LT(sr / sw, 128.0);  // v0 = 50 is above the image centre: ahead of the vehicle
    }
  }
}

TEST(CameraTile, IntensityIsBilinearInsideTheFootprintAndUncoveredOutside) {
  CameraTileProjector p;
  ASSERT_TRUE(p.init(config_1cm()).is_ok());
  Buffers b;
  for (int v = 0; v < kH; ++v)
    for (int u = 0; u < kW; ++u) b.img[static_cast<std::size_t>(v * kW + u)] = static_cast<std::uint8_t>(u);  // intensity = column
  const Pose3 cam = camera_pose(0.0, 0.0, 2.0, 0.3, 0.0, 0.0);
  TileGeometry g;
  ASSERT_TRUE(p.project(b.image(), kK, cam, 0.0, 0.3, b.raster(), b.coverage(), g).is_ok());
  const Pose3 inv = cam.inverse();
  int covered = 0;
  for (int r = 0; r < 256; ++r)
    for (int col = 0; col < 256; ++col) {
      const Vec3d ground(g.origin_north_m - (r + 0.5) * g.resolution_m, g.origin_east_m + (col + 0.5) * g.resolution_m, 0.0);
      const Vec3d pc = inv.apply(ground);
      const double u = kK.fx_px * pc.x() / pc.z() + kK.cu_px, v = kK.fy_px * pc.y() / pc.z() + kK.cv_px;
      const bool inside = u >= 0.0 && v >= 0.0 && u <= kW - 1 && v <= kH - 1;
      const std::size_t i = static_cast<std::size_t>(r * 256 + col);
      if (std::abs(u - std::round(u)) < 1e-6 || std::abs(v - std::round(v)) < 1e-6) continue;  // on a pixel edge
      EXPECT_EQ(b.cov[i] != 0, inside) << r << "," << col;
      if (inside) {
        ++covered;
        EXPECT_NEAR(static_cast<double>(b.out[i]), u, 1e-3) << r << "," << col;
      } else {
        EXPECT_EQ(b.out[i], 0.0f);
      }
    }
  EXPECT_GT(covered, 20000);
}

TEST(CameraTile, BadInputIsAClearErrorAndCounted) {
  CameraTileProjector p;
  Buffers b;
  TileGeometry g;
  const Pose3 cam = camera_pose(0.0, 0.0, 2.0, 0.0, 0.0, 0.0);
  EXPECT_EQ(p.project(b.image(), kK, cam, 0.0, 0.0, b.raster(), b.coverage(), g).status(), StatusCode::kNotReady);
  CameraTileConfig bad;
  bad.resolution_m = 0.0;
  EXPECT_EQ(p.init(bad), StatusCode::kInvalidArgument);
  bad = CameraTileConfig{};
  bad.width_px = 4;
  EXPECT_EQ(p.init(bad), StatusCode::kInvalidArgument);
  ASSERT_TRUE(p.init(config_1cm()).is_ok());
  // Non-finite pose / intrinsics.
  Pose3 nan_pose = cam;
  nan_pose.t.x() = std::nan("");
  EXPECT_EQ(p.project(b.image(), kK, nan_pose, 0.0, 0.0, b.raster(), b.coverage(), g).status(), StatusCode::kInvalidArgument);
  CameraIntrinsics k0 = kK;
  k0.fx_px = 0.0;
  EXPECT_EQ(p.project(b.image(), k0, cam, 0.0, 0.0, b.raster(), b.coverage(), g).status(), StatusCode::kInvalidArgument);
  EXPECT_EQ(p.counters().get(CameraTileCounter::kBadInput), 2u);
  // Looking up, looking at the horizon, ground above the camera.
  Pose3 up = cam;
  up.R = up.R * rotation_from_rpy(kPi, 0.0, 0.0);
  EXPECT_EQ(p.project(b.image(), kK, up, 0.0, 0.0, b.raster(), b.coverage(), g).status(), StatusCode::kInvalidArgument);
  const Pose3 horizon = camera_pose(0.0, 0.0, 2.0, 0.0, 0.0, deg_to_rad(80.0));
  EXPECT_EQ(p.project(b.image(), kK, horizon, 0.0, 0.0, b.raster(), b.coverage(), g).status(), StatusCode::kInvalidArgument);
  EXPECT_EQ(p.project(b.image(), kK, cam, -3.0, 0.0, b.raster(), b.coverage(), g).status(), StatusCode::kInvalidArgument);
  EXPECT_EQ(p.counters().get(CameraTileCounter::kGroundNotVisible), 3u);
  // Empty image, output smaller than the configured raster.
  EXPECT_EQ(p.project(ConstImageViewU8(), kK, cam, 0.0, 0.0, b.raster(), b.coverage(), g).status(), StatusCode::kInvalidArgument);
  ImageViewF32 small = ImageViewF32::make(b.out.data(), 100, 100).value();
  EXPECT_EQ(p.project(b.image(), kK, cam, 0.0, 0.0, small, b.coverage(), g).status(), StatusCode::kInvalidArgument);
  EXPECT_EQ(p.counters().get(CameraTileCounter::kBadInput), 4u);
  // No raster pixel centre inside the image: a 10 m raster under a 1 cm footprint.
  CameraTileConfig tiny;
  tiny.resolution_m = 10.0;
  tiny.width_px = tiny.height_px = 8;
  ASSERT_TRUE(p.init(tiny).is_ok());
  const Pose3 low = camera_pose(0.0, 0.0, 0.01, 0.0, 0.0, 0.0);  // 1 cm up: footprint 1 cm x 0.8 cm
  EXPECT_EQ(p.project(b.image(), kK, low, 0.0, 0.0, b.raster(), b.coverage(), g).status(), StatusCode::kInvalidArgument);
  EXPECT_EQ(p.counters().get(CameraTileCounter::kEmptyTile), 1u);
}

TEST(CameraTile, ProjectDoesNotAllocate) {
  CameraTileProjector p;
  ASSERT_TRUE(p.init(config_1cm()).is_ok());
  Buffers b;
  TileGeometry g;
  const Pose3 cam = camera_pose(1.0, 2.0, 2.0, 1.0, 0.02, 0.01);
  QNAV_EXPECT_NO_ALLOC({ p.project(b.image(), kK, cam, 0.0, 1.0, b.raster(), b.coverage(), g).status().ignore(); });
}

}  // namespace
}  // namespace qnav::route
