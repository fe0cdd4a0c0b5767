// tools/mosaic: the frames of the synthetic downward sequence (drivers/downward_sim, exact ground
// truth) chained by nav/topo's HomographyChain and pasted into frame 0's grid must show the seabed
// where it really is; the canvas is bounded (downscaled beyond its limit); drawing is clipped.
#include "firmware/tools/mosaic.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "drivers/downward_sim/seabed_scene.hpp"
#include "nav/core/arena.hpp"
#include "nav/topo/homography_chain.hpp"

namespace qnav::tools {
namespace {

using sim::downward::Camera;
using sim::downward::CameraPose;
using sim::downward::Seabed;

// The seabed grey level under mosaic point m (frame 0's pixel grid): through frame 0's true pose.
double seabed_at(const Seabed& s, const Camera& cam, const CameraPose& p0, const Vec2d& m) {
  const double k = p0.altitude_m / cam.f, c = std::cos(p0.yaw_rad), sn = std::sin(p0.yaw_rad);
  const double du = m.x() - cam.cx, dv = m.y() - cam.cy;
  return s.sample(p0.x_m + k * (c * du - sn * dv), p0.y_m + k * (sn * du + c * dv));
}

struct Sequence {
  Camera cam;
  Seabed seabed;
  std::vector<ImageU8> frames;
  std::vector<Mat3d> H;  // the chain's H_0<-k
};

// 16 frames of the nav/topo test path (4 cm forward and 1 deg a frame, 2 m rising), chained.
const Sequence& sequence() {
  static const Sequence seq = [] {
    Sequence q;
    topo::HomographyChainConfig c;
    c.max_width = q.cam.width;
    c.max_height = q.cam.height;
    c.camera.fx = c.camera.fy = q.cam.f;
    c.camera.cx = q.cam.cx;
    c.camera.cy = q.cam.cy;
    ArenaStorage arena(topo::HomographyChain::arena_bytes(c));
    topo::HomographyChain chain;
    EXPECT_TRUE(chain.init(c, arena).is_ok());
    for (int k = 0; k < 16; ++k) {
      Result<ImageU8> img = ImageU8::allocate(q.cam.width, q.cam.height);
      EXPECT_TRUE(img.is_ok());
      sim::downward::render(q.seabed, q.cam, sim::downward::path_pose(k), img->view());
      topo::ChainStep step;
      EXPECT_TRUE(chain.process(ConstImageViewU8(img->view()), sim::downward::path_pose(k).altitude_m, step).is_ok());
      EXPECT_EQ(step.status, topo::StepStatus::kOk) << "frame " << k;
      q.H.push_back(step.pose.H_0_cur);
      q.frames.push_back(std::move(img.value()));
    }
    return q;
  }();
  return seq;
}

// Mean absolute grey difference between the canvas and the seabed at the true position of every
// covered canvas pixel, with the truth shifted by `shift` mosaic pixels (0: the real comparison).
double mean_error(const MosaicCanvas& m, const Sequence& q, const Vec2d& shift, int* covered) {
  double sum = 0.0;
  int n = 0;
  const CameraPose p0 = sim::downward::path_pose(0);
  for (int r = 0; r < m.geometry.height; ++r)
    for (int c = 0; c < m.geometry.width; ++c) {
      const std::size_t i = static_cast<std::size_t>(r) * static_cast<std::size_t>(m.geometry.width) + static_cast<std::size_t>(c);
      if (!m.covered[i]) continue;
      sum += std::abs(m.grey[i] - seabed_at(q.seabed, q.cam, p0, m.geometry.to_mosaic(Vec2d(c, r)) + shift));
      ++n;
    }
  if (covered != nullptr) *covered = n;
  return n > 0 ? sum / n : 1e9;
}

TEST(Mosaic, PastedFramesShowTheSeabedAtItsTruePosition) {
  const Sequence& q = sequence();
  Result<MosaicGeometry> g = mosaic_geometry(q.H, q.cam.width, q.cam.height, 1600);
  ASSERT_TRUE(g.is_ok());
  EXPECT_FALSE(g->downscaled());
  // The path moves ~0.6 m = ~90 px up the mosaic and turns 15 deg: the canvas holds all frames.
  EXPECT_GT(g->height, q.cam.height + 60);
  EXPECT_LT(g->width, 2 * q.cam.width);
  MosaicCanvas m(g.value());
  for (std::size_t k = 0; k < q.frames.size(); ++k) ASSERT_TRUE(m.paste(ConstImageViewU8(q.frames[k].view()), q.H[k]));
  int covered = 0;
  const double err = mean_error(m, q, Vec2d::Zero(), &covered);
  const double err_shifted = mean_error(m, q, Vec2d(3.0, 0.0), nullptr);
  std::printf("mosaic %dx%d, %d px covered: mean |canvas - seabed| %.2f grey levels (truth shifted 3 px: %.2f)\n", g->width,
              g->height, covered, err, err_shifted);
  EXPECT_GT(covered, q.cam.width * q.cam.height);
  // Rendering (2 x 2 samples a pixel) vs one bilinear sample of the raster, the chain's sub-pixel
  // error (< 1.5 mm on this path) and bilinear resampling: measured 1.45 grey levels on a texture whose
  // rectangles step by up to 160; the same mosaic 3 px off the truth: 11.3.
  EXPECT_LT(err, 3.0);
  EXPECT_GT(err_shifted, 4.0 * err);
}

TEST(Mosaic, TheLastFramesPatchMatchesTheSeabedUnderIt) {
  const Sequence& q = sequence();
  // Only the last frame pasted: its patch alone, at the chain's pose, against the truth.
  const std::vector<Mat3d> last{q.H.back()};
  Result<MosaicGeometry> g = mosaic_geometry(last, q.cam.width, q.cam.height, 1600);
  ASSERT_TRUE(g.is_ok());
  MosaicCanvas m(g.value());
  ASSERT_TRUE(m.paste(ConstImageViewU8(q.frames.back().view()), q.H.back()));
  int covered = 0;
  const double err = mean_error(m, q, Vec2d::Zero(), &covered);
  std::printf("last frame alone: %d px, mean |canvas - seabed| %.2f grey levels\n", covered, err);
  EXPECT_NEAR(covered, q.cam.width * q.cam.height, 0.1 * q.cam.width * q.cam.height);
  EXPECT_LT(err, 3.0);  // measured 1.35
}

TEST(Mosaic, CanvasIsBoundedAndDownscaledBeyondItsLimit) {
  const Sequence& q = sequence();
  Result<MosaicGeometry> g = mosaic_geometry(q.H, q.cam.width, q.cam.height, 200);
  ASSERT_TRUE(g.is_ok());
  EXPECT_TRUE(g->downscaled());
  EXPECT_LE(g->width, 200);
  EXPECT_LE(g->height, 200);
  MosaicCanvas m(g.value());
  for (std::size_t k = 0; k < q.frames.size(); ++k) ASSERT_TRUE(m.paste(ConstImageViewU8(q.frames[k].view()), q.H[k]));
  // Every frame's principal point lands inside the canvas.
  for (const Mat3d& H : q.H) {
    const Vec3d p = H * Vec3d(q.cam.cx, q.cam.cy, 1.0);
    const Vec2d c = g->to_canvas(Vec2d(p.x() / p.z(), p.y() / p.z()));
    EXPECT_TRUE(c.x() >= 0 && c.y() >= 0 && c.x() < g->width && c.y() < g->height);
  }
  // Bad input is refused, not drawn.
  EXPECT_FALSE(mosaic_geometry({}, 320, 240, 1600).is_ok());
  EXPECT_FALSE(mosaic_geometry(q.H, 0, 240, 1600).is_ok());
  Mat3d vanishing = Mat3d::Identity();
  vanishing(2, 0) = -0.01;  // w <= 0 over part of the frame
  EXPECT_FALSE(mosaic_geometry({vanishing}, 320, 240, 1600).is_ok());
  EXPECT_FALSE(m.paste(ConstImageViewU8(q.frames[0].view()), vanishing));
  EXPECT_FALSE(m.paste(ConstImageViewU8(q.frames[0].view()), Mat3d::Zero()));
}

TEST(Mosaic, DrawingIsClippedToTheImage) {
  const int w = 40, h = 30;
  std::vector<std::uint8_t> rgb(static_cast<std::size_t>(w * h * 3), 0);
  draw_line(rgb, w, h, Vec2d(-100, -100), Vec2d(500, 400), {255, 0, 0}, 3.0);
  draw_disc(rgb, w, h, Vec2d(20, 15), 2.0, {0, 255, 0});
  draw_ring(rgb, w, h, Vec2d(0, 0), 48.5, {0, 0, 255});
  draw_line(rgb, w, h, Vec2d(0, 29), Vec2d(1e12, 29), {255, 255, 255});  // clipped: 40 pixels drawn, not 1e12
  EXPECT_EQ(rgb[(15 * w + 20) * 3 + 1], 255);  // the disc's centre
  EXPECT_EQ(rgb[(10 * w + 32) * 3 + 0], 255);  // on the line: y = -100 + (x + 100) 5/6 passes (32, 10)
  EXPECT_EQ(rgb[(29 * w + 39) * 3 + 2], 255);  // the ring of radius 48.5 about (0, 0) grazes the far corner
  EXPECT_EQ(rgb[(29 * w + 5) * 3 + 0], 255);   // the clipped horizontal line
  EXPECT_EQ(rgb[(25 * w + 2) * 3 + 0], 0);     // untouched
}

}  // namespace
}  // namespace qnav::tools
