#include "nav/topo/homography_chain.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "test/support/alloc_guard.hpp"
#include "drivers/downward_sim/seabed_scene.hpp"

namespace qnav::topo {
namespace test = qnav::sim::downward;  // the downward-camera scene
namespace {

using test::Camera;
using test::CameraPose;
using test::Seabed;

const Seabed& seabed() {
  static const Seabed s;
  return s;
}

HomographyChainConfig chain_config(const Camera& cam) {
  HomographyChainConfig c;
  c.max_width = cam.width;
  c.max_height = cam.height;
  c.camera.fx = c.camera.fy = cam.f;
  c.camera.cx = cam.cx;
  c.camera.cy = cam.cy;
  return c;
}

struct Rig {
  Camera cam;
  std::vector<std::byte> block;
  Arena arena;
  HomographyChain chain;
  ImageU8 frame;
  explicit Rig(const HomographyChainConfig& c)
      : block(HomographyChain::arena_bytes(c)), arena(Span<std::byte>(block.data(), block.size())),
        frame(ImageU8::allocate(cam.width, cam.height).value()) {
    const Status s = chain.init(c, arena);
    EXPECT_TRUE(s.is_ok()) << s.message();
  }
  ChainStep see(const CameraPose& p, bool give_altitude = true) {
    test::render(seabed(), cam, p, frame.view());
    ChainStep step;
    EXPECT_TRUE(chain.process(frame.view(), give_altitude ? p.altitude_m : -1.0, step).is_ok());
    return step;
  }
  ChainStep see(ConstImageViewU8 img) {
    ChainStep step;
    EXPECT_TRUE(chain.process(img, step).is_ok());
    return step;
  }
};

// Truth in frame 0's camera axes (frame 0 has yaw 0 on the test path).
Vec2d truth_m(int k) {
  const CameraPose p0 = test::path_pose(0), pk = test::path_pose(k);
  return Vec2d(pk.x_m - p0.x_m, pk.y_m - p0.y_m);
}
double path_length_m(int k) {
  double len = 0.0;
  for (int i = 1; i <= k; ++i) len += (truth_m(i) - truth_m(i - 1)).norm();
  return len;
}

TEST(HomographyChain, ChainedPoseFollowsKnownMotionWithinOnePercentOfPath) {
  Rig rig(chain_config(Camera{}));
  constexpr int kFrames = 30;
  double max_err_m = 0.0, max_yaw_err = 0.0;
  for (int k = 0; k < kFrames; ++k) {
    const ChainStep s = rig.see(test::path_pose(k));
    ASSERT_EQ(s.status, StepStatus::kOk) << "frame " << k << " " << to_string(s.status) << " kp " << s.keypoints << " m "
                                         << s.matches << " in " << s.inliers;
    EXPECT_EQ(s.reference, k == 0);
    if (k > 0) {
      EXPECT_GE(s.inliers, 60u) << "frame " << k;
      EXPECT_LT(s.rms_px, 1.0) << "frame " << k;
    }
    ASSERT_TRUE(s.pose.metric);
    max_err_m = std::max(max_err_m, (s.pose.position_m - truth_m(k)).norm());
    max_yaw_err = std::max(max_yaw_err, std::abs(s.pose.heading_rad - test::path_pose(k).yaw_rad));
  }
  const double path = path_length_m(kFrames - 1);
  std::printf("synthetic chain: %d frames, path %.3f m, max position error %.4f m (%.2f %% of path), max yaw error %.3f deg, "
              "%u keyframes, %.5f m/px (truth %.5f)\n",
              kFrames, path, max_err_m, 100.0 * max_err_m / path, rad_to_deg(max_yaw_err), rig.chain.keyframes(),
              rig.chain.metres_per_px(), 2.0 / 300.0);
  // Keypoints are located to ~0.3 px and each keyframe link carries the error of one homography
  // (a few hundredths of a pixel at the centre, more in scale and rotation): 1 % of a 1.2 m path is
  // 12 mm = 1.8 px at 6.7 mm/px.
  EXPECT_LT(max_err_m, 0.01 * path);
  EXPECT_LT(rad_to_deg(max_yaw_err), 0.3);
  EXPECT_NEAR(rig.chain.metres_per_px(), 2.0 / 300.0, 0.01 * 2.0 / 300.0);
  // Keyframes: more than the reference (the camera leaves the first view), far fewer than the frames.
  EXPECT_GE(rig.chain.keyframes(), 2u);
  EXPECT_LE(rig.chain.keyframes(), static_cast<std::uint32_t>(kFrames / 3));
}

TEST(HomographyChain, WithoutAltitudeThePoseIsInPixelsOnly) {
  Rig rig(chain_config(Camera{}));
  for (int k = 0; k < 6; ++k) {
    const ChainStep s = rig.see(test::path_pose(k), false);
    ASSERT_EQ(s.status, StepStatus::kOk);
    EXPECT_FALSE(s.pose.metric);
    EXPECT_EQ(s.pose.position_m, Vec2d::Zero());
  }
  // Pixels: truth / (h0 / f) from the principal point.
  const Vec2d px = rig.chain.pose().position_px - Vec2d(159.5, 119.5);
  EXPECT_LT((px - truth_m(5) * (300.0 / 2.0)).norm(), 1.0);
}

TEST(HomographyChain, KeyframeOnlyWhenOverlapOrInliersDrop) {
  // A still camera: every frame registers against the reference, which stays the only keyframe, and
  // the pose stays at the identity.
  Rig still(chain_config(Camera{}));
  for (int k = 0; k < 8; ++k) {
    const ChainStep s = still.see(test::path_pose(3));
    ASSERT_EQ(s.status, StepStatus::kOk);
    EXPECT_EQ(s.new_keyframe, k == 0);
    EXPECT_EQ(s.keyframe_index, 0u);
    EXPECT_GT(s.overlap, 0.99);
  }
  EXPECT_EQ(still.chain.keyframes(), 1u);
  EXPECT_LT((still.chain.pose().position_px - Vec2d(159.5, 119.5)).norm(), 0.05);
  EXPECT_LT(std::abs(still.chain.pose().heading_rad), 1e-3);

  // Moving: a new keyframe exactly when the overlap falls under min_overlap (inliers stay high).
  HomographyChainConfig c = chain_config(Camera{});
  c.keyframe_min_inliers = 20;
  Rig moving(c);
  std::uint32_t key = 0;
  for (int k = 0; k < 16; ++k) {
    const ChainStep s = moving.see(test::path_pose(k));
    ASSERT_EQ(s.status, StepStatus::kOk) << k;
    if (k > 0) {
      EXPECT_EQ(s.keyframe_index, key) << k;
      EXPECT_EQ(s.new_keyframe, s.overlap < c.min_overlap) << "frame " << k << " overlap " << s.overlap;
    }
    if (s.new_keyframe) key = s.frame_index;
  }
  EXPECT_GE(moving.chain.keyframes(), 2u);

  // max_keyframe_gap = 1: every frame is a keyframe (the frame-to-frame chain).
  c.max_keyframe_gap = 1;
  Rig every(c);
  for (int k = 0; k < 6; ++k) EXPECT_TRUE(every.see(test::path_pose(k)).new_keyframe) << k;
  EXPECT_EQ(every.chain.keyframes(), 6u);
}

void expect_pose_equal(const ChainPose& a, const ChainPose& b) {
  EXPECT_EQ(a.H_0_cur, b.H_0_cur);
  EXPECT_EQ(a.position_px, b.position_px);
  EXPECT_EQ(a.position_m, b.position_m);
  EXPECT_EQ(a.heading_rad, b.heading_rad);
}

TEST(HomographyChain, BadFramesAreFlaggedAndLeaveThePoseIntact) {
  Rig rig(chain_config(Camera{}));
  const Camera cam;
  ImageU8 black = ImageU8::allocate(cam.width, cam.height).value();  // zero-initialised
  ImageU8 white = ImageU8::allocate(cam.width, cam.height).value();
  ImageU8 flat = ImageU8::allocate(cam.width, cam.height).value();
  ImageU8 noise = ImageU8::allocate(cam.width, cam.height).value();
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      white.view()(x, y) = 255;
      flat.view()(x, y) = static_cast<std::uint8_t>(120 + ((x + y) & 1));  // +-1 grey level
      noise.view()(x, y) = static_cast<std::uint8_t>(test::hash32(x, y, 99) & 0xFF);
    }
  ImageU8 small = ImageU8::allocate(cam.width / 2, cam.height).value();

  int k = 0;
  for (; k < 5; ++k) ASSERT_EQ(rig.see(test::path_pose(k)).status, StepStatus::kOk);
  const ChainPose before = rig.chain.pose();
  const std::uint32_t keys = rig.chain.keyframes();

  ChainStep s = rig.see(black.view());
  EXPECT_EQ(s.status, StepStatus::kBadInput);
  EXPECT_TRUE(s.bad_input & kFrameDark);
  s = rig.see(white.view());
  EXPECT_EQ(s.status, StepStatus::kBadInput);
  EXPECT_TRUE(s.bad_input & kFrameSaturated);
  s = rig.see(flat.view());
  EXPECT_EQ(s.status, StepStatus::kBadInput);
  EXPECT_TRUE(s.bad_input & kFrameTextureless);
  s = rig.see(small.view());
  EXPECT_EQ(s.status, StepStatus::kBadInput);
  EXPECT_TRUE(s.bad_input & kFrameSize);
  s = rig.see(ConstImageViewU8());
  EXPECT_EQ(s.status, StepStatus::kBadInput);
  // Texture but nothing in common with the keyframe: keypoints, no consistent matches.
  s = rig.see(noise.view());
  EXPECT_TRUE(s.status == StepStatus::kFewMatches || s.status == StepStatus::kDegenerate) << to_string(s.status);
  EXPECT_GT(s.keypoints, 50u);
  // Another part of the seabed, far from the keyframe: not registered.
  CameraPose away = test::path_pose(k);
  away.x_m += 1.5;
  s = rig.see(away);
  EXPECT_NE(s.status, StepStatus::kOk);
  expect_pose_equal(s.pose, before);
  expect_pose_equal(rig.chain.pose(), before);
  EXPECT_EQ(rig.chain.keyframes(), keys);

  // The chain resumes on the next good frame (the camera moved on meanwhile).
  double max_err = 0.0;
  for (k = 7; k < 14; ++k) {
    const ChainStep g = rig.see(test::path_pose(k));
    ASSERT_EQ(g.status, StepStatus::kOk) << k;
    max_err = std::max(max_err, (g.pose.position_m - truth_m(k)).norm());
  }
  EXPECT_LT(max_err, 0.01 * path_length_m(13));
}

TEST(HomographyChain, FundamentalBothAcceptFilterStillRegisters) {
  HomographyChainConfig c = chain_config(Camera{});
  c.fundamental_filter = true;
  Rig rig(c);
  for (int k = 0; k < 8; ++k) {
    const ChainStep s = rig.see(test::path_pose(k));
    ASSERT_EQ(s.status, StepStatus::kOk) << k;
    if (k > 0) {
      EXPECT_GE(s.fundamental_inliers, s.inliers) << k;
    }
  }
  EXPECT_LT((rig.chain.pose().position_m - truth_m(7)).norm(), 0.01 * path_length_m(7));
}

TEST(HomographyChain, ProcessAllocatesNothing) {
  Rig rig(chain_config(Camera{}));
  const Camera cam;
  std::vector<ImageU8> frames;
  for (int k = 0; k < 6; ++k) {
    frames.push_back(ImageU8::allocate(cam.width, cam.height).value());
    test::render(seabed(), cam, test::path_pose(k), frames.back().view());
  }
  ImageU8 black = ImageU8::allocate(cam.width, cam.height).value();
  ChainStep s;
  {
    qnav::test::AllocationGuard guard;
    qnav::test::EigenMallocForbidden no_eigen_malloc;
    for (int k = 0; k < 6; ++k) {
      (void)rig.chain.process(frames[static_cast<std::size_t>(k)].view(), 2.0, s);
      EXPECT_EQ(s.status, StepStatus::kOk);
    }
    (void)rig.chain.process(black.view(), 2.0, s);
    EXPECT_EQ(guard.allocations(), 0u) << guard.report();
  }
}

TEST(HomographyChain, MisuseAndBadConfiguration) {
  HomographyChain chain;
  ChainStep s;
  const Camera cam;
  ImageU8 img = ImageU8::allocate(cam.width, cam.height).value();
  EXPECT_EQ(chain.process(img.view(), s).code(), StatusCode::kNotReady);
  HomographyChainConfig c = chain_config(cam);
  std::vector<std::byte> block(HomographyChain::arena_bytes(c));
  Arena arena(Span<std::byte>(block.data(), block.size()));
  HomographyChainConfig bad = c;
  bad.min_inliers = 3;
  EXPECT_EQ(chain.init(bad, arena).code(), StatusCode::kInvalidArgument);
  bad = c;
  bad.camera.fx = std::nan("");
  EXPECT_EQ(chain.init(bad, arena).code(), StatusCode::kInvalidArgument);
  bad = c;
  bad.pyramid_levels = 0;
  EXPECT_EQ(chain.init(bad, arena).code(), StatusCode::kInvalidArgument);
  std::vector<std::byte> tiny(1024);
  Arena small(Span<std::byte>(tiny.data(), tiny.size()));
  EXPECT_FALSE(chain.init(c, small).is_ok());
  EXPECT_TRUE(chain.init(c, arena).is_ok());
}

}  // namespace
}  // namespace qnav::topo

namespace qnav::topo {
namespace test = qnav::sim::downward;  // the downward-camera scene
namespace {

struct ChainRun {
  double final_err_m = 0.0, final_yaw_err_deg = 0.0, final_scale = 0.0;
  std::uint32_t keyframes = 0;
};
ChainRun run_path(const HomographyChainConfig& c, int frames) {
  Rig rig(c);
  ChainRun r;
  for (int k = 0; k < frames; ++k) {
    const ChainStep s = rig.see(test::path_pose(k));
    EXPECT_EQ(s.status, StepStatus::kOk) << k;
  }
  r.final_err_m = (rig.chain.pose().position_m - truth_m(frames - 1)).norm();
  r.final_yaw_err_deg = rad_to_deg(std::abs(rig.chain.pose().heading_rad - test::path_pose(frames - 1).yaw_rad));
  r.final_scale = rig.chain.pose().scale;
  r.keyframes = rig.chain.keyframes();
  return r;
}

TEST(HomographyChain, KeyframesAccumulateLessThanTheFrameToFrameChain) {
  constexpr int kFrames = 40;
  HomographyChainConfig c = chain_config(Camera{});
  const ChainRun key = run_path(c, kFrames);
  c.max_keyframe_gap = 1;
  const ChainRun f2f = run_path(c, kFrames);
  std::printf("%d frames, path %.3f m: keyframes (%u): final error %.4f m, yaw %.3f deg, scale %.5f; frame-to-frame (%u): "
              "%.4f m, yaw %.3f deg, scale %.5f (truth scale %.5f)\n",
              kFrames, path_length_m(kFrames - 1), key.keyframes, key.final_err_m, key.final_yaw_err_deg, key.final_scale,
              f2f.keyframes, f2f.final_err_m, f2f.final_yaw_err_deg, f2f.final_scale,
              test::path_pose(kFrames - 1).altitude_m / test::path_pose(0).altitude_m);
  // The frame-to-frame chain multiplies 39 noisy homographies; the keyframe chain 3 or 4 (measured:
  // 0.4 mm / 0.01 deg vs 31 mm / 0.9 deg; scale 0.2 % vs 2.7 % off).
  EXPECT_LE(key.keyframes, 8u);
  EXPECT_EQ(f2f.keyframes, static_cast<std::uint32_t>(kFrames));
  EXPECT_LT(key.final_err_m, 0.25 * f2f.final_err_m);
  EXPECT_LT(key.final_err_m, 0.003 * path_length_m(kFrames - 1));
  EXPECT_LT(key.final_yaw_err_deg, 0.1);
  const double truth_scale = test::path_pose(kFrames - 1).altitude_m / test::path_pose(0).altitude_m;
  EXPECT_NEAR(key.final_scale, truth_scale, 0.005 * truth_scale);
}

}  // namespace
}  // namespace qnav::topo
