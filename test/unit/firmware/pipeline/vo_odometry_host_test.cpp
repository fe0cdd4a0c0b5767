// VoOdometry's inputs for `qnav vo eval`: a chain that keeps its start attitude (the simulator's true
// pose) instead of the first sensor sample's, and a translation prior given in the previous camera
// frame, used as it is: with them the component runs exactly the bare StereoVo chain the eval ran.
// Host only (test_firmware_pipeline_host): rendering the Mars yard costs seconds under qemu.
#include "firmware/pipeline/vo_odometry.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "drivers/stereo_sim/mars_yard.hpp"
#include "firmware/pipeline/vo_defaults.hpp"
#include "nav/core/geometry.hpp"

namespace {

using namespace qnav;
using namespace qnav::pipeline;

// Two rendered pairs along the rover's trajectory, and the attitude sensor's samples (off the truth).
struct Frames {
  sim::StereoBench bench;
  sim::MarsYardTerrain terrain{sim::MarsYardConfig{}};
  Image<std::uint8_t> left[2], right[2];
  Pose3 cam[2];
  Mat3d sensor[2];
  Frames() {
    sim::MarsYardTrajectory traj(sim::TrajectoryConfig{});
    for (int i = 0; i < 2; ++i) {
      const sim::RoverSample& s = i == 0 ? traj.current() : traj.next();
      cam[i] = s.world_T_rover.compose(bench.rover_T_left());
      sensor[i] = cam[i].R * rotation_from_rpy(0.004 * (i + 1), -0.003, 0.005);
      left[i] = std::move(Image<std::uint8_t>::allocate(bench.width(), bench.height()).value());
      right[i] = std::move(Image<std::uint8_t>::allocate(bench.width(), bench.height()).value());
      EXPECT_TRUE(sim::render_stereo(terrain, bench, cam[i], 100 + static_cast<std::uint64_t>(i), left[i].view(), right[i].view()).is_ok());
    }
  }
};

// The chain qnav vo eval ran before it went through VoOdometry: StereoVo reset on the true start pose,
// the sensor's attitude, the relative attitude as the rotation prior, the camera-frame translation prior.
TEST(VoOdometry, CameraFramePriorAndKeptStartAreTheBareStereoVoChain) {
  const Frames f;
  const vo::VoConfig c = default_vo_config(f.bench);
  VoOdometry odo;
  ASSERT_TRUE(odo.init(c, Pose3{}).is_ok());
  ArenaStorage arena(vo::StereoVo::arena_bytes(c));
  vo::StereoVo bare;
  ASSERT_TRUE(bare.init(c, arena).is_ok());
  odo.reset(f.cam[0], true);
  bare.reset(f.cam[0]);
  const Vec3d t_cam = f.cam[0].inverse().compose(f.cam[1]).t + Vec3d(0.003, -0.002, 0.004);  // a measured step
  for (int i = 0; i < 2; ++i) {
    VoFrameInput in;
    in.left = f.left[i].view();
    in.right = f.right[i].view();
    in.stamp_ns = 1 + static_cast<std::uint64_t>(i) * 100000000u;
    in.has_attitude = true;
    in.world_R_body = f.sensor[i];
    vo::VoInput v;
    v.left = in.left;
    v.right = in.right;
    v.stamp_ns = in.stamp_ns;
    v.has_absolute_attitude = true;
    v.world_R_cam = f.sensor[i];
    if (i == 1) {
      in.has_camera_translation_prior = true;
      in.t_prev_cur_cam_m = t_cam;
      in.camera_translation_sigma_m = 0.02;
      v.R_prev_cur = f.sensor[0].transpose() * f.sensor[1];
      v.has_translation_prior = true;
      v.t_prev_cur_prior_m = t_cam;
      v.t_prior_sigma_m = 0.02;
    }
    const Result<vo::VoStep> a = odo.step(in), b = bare.process(v);
    ASSERT_TRUE(a.is_ok());
    ASSERT_TRUE(b.is_ok());
    EXPECT_EQ(a->flags, b->flags) << "frame " << i;
    EXPECT_EQ(odo.vo().pose().R, bare.pose().R) << "frame " << i;
    EXPECT_EQ(odo.vo().pose().t, bare.pose().t) << "frame " << i;
  }
  EXPECT_EQ(odo.visual_steps(), 1u);  // the second pair registered against the first
}

// Without keep_start_attitude the chain starts in the first sample's attitude instead.
TEST(VoOdometry, StartsInTheSensorsAttitudeUnlessKept) {
  const Frames f;
  const vo::VoConfig c = default_vo_config(f.bench);
  ArenaStorage arena(vo::StereoVo::arena_bytes(c));
  vo::StereoVo bare;
  ASSERT_TRUE(bare.init(c, arena).is_ok());
  VoOdometry odo;
  ASSERT_TRUE(odo.init(c, Pose3{}).is_ok());
  odo.reset(f.cam[0]);
  bare.reset(Pose3{f.sensor[0], f.cam[0].t});
  VoFrameInput in;
  in.left = f.left[0].view();
  in.right = f.right[0].view();
  in.stamp_ns = 1;
  in.has_attitude = true;
  in.world_R_body = f.sensor[0];
  vo::VoInput v;
  v.left = in.left;
  v.right = in.right;
  v.stamp_ns = 1;
  v.has_absolute_attitude = true;
  v.world_R_cam = f.sensor[0];
  ASSERT_TRUE(odo.step(in).is_ok());
  ASSERT_TRUE(bare.process(v).is_ok());
  EXPECT_EQ(odo.vo().pose().R, bare.pose().R);
  EXPECT_EQ(odo.vo().pose().t, bare.pose().t);
}

}  // namespace
