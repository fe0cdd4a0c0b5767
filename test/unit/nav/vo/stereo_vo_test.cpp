#include "nav/vo/stereo_vo.hpp"

#include <gtest/gtest.h>
#include "firmware/pipeline/vo_defaults.hpp"

#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include "drivers/stereo_sim/mars_yard.hpp"
#include "test/support/alloc_guard.hpp"

namespace qnav::vo {
namespace {

// The paper's bench rendered by drivers/stereo_sim; frames are rendered on first use (rendering
// dominates the cost, and each test runs in its own process under ctest).
struct SimRun {
  sim::MarsYardTerrain terrain;
  sim::StereoBench bench;
  sim::MarsYardTrajectory traj;
  std::vector<Pose3> world_T_cam;
  mutable std::vector<Image<std::uint8_t>> left, right;
  mutable std::vector<bool> rendered;

  explicit SimRun(int frames) : left(frames), right(frames), rendered(frames, false) {
    world_T_cam.push_back(traj.current().world_T_rover.compose(bench.rover_T_left()));
    for (int i = 1; i < frames; ++i) world_T_cam.push_back(traj.next().world_T_rover.compose(bench.rover_T_left()));
  }
  void render(int i) const {
    if (rendered[i]) return;
    left[i] = std::move(Image<std::uint8_t>::allocate(bench.width(), bench.height()).value());
    right[i] = std::move(Image<std::uint8_t>::allocate(bench.width(), bench.height()).value());
    EXPECT_TRUE(sim::render_stereo(terrain, bench, world_T_cam[i], 100 + i, left[i].view(), right[i].view()).is_ok());
    rendered[i] = true;
  }
  Pose3 truth_step(int i) const { return world_T_cam[i - 1].inverse().compose(world_T_cam[i]); }
};

VoConfig bench_config(const sim::StereoBench& b, VmeMode mode, bool fast) {
  VoConfig c = pipeline::vo_config_for_bench(b);
  c.mode = mode;
  c.match.fast = fast;
  return c;
}

struct Vo {
  std::unique_ptr<ArenaStorage> arena;
  StereoVo vo;
  explicit Vo(const VoConfig& c) : arena(new ArenaStorage(StereoVo::arena_bytes(c))) {
    EXPECT_TRUE(vo.init(c, *arena).is_ok());
  }
};

VoInput input(const SimRun& run, int i, bool with_prior) {
  run.render(i);
  VoInput in;
  in.left = run.left[i].view();
  in.right = run.right[i].view();
  if (i > 0) {
    const Pose3 s = run.truth_step(i);
    in.R_prev_cur = s.R;
    in.has_translation_prior = with_prior;
    in.t_prev_cur_prior_m = 1.1 * s.t;  // 10 % wheel slip (paper's n_t)
    in.t_prior_sigma_m = 0.03;
  }
  return in;
}

const SimRun& shared_run() {
  static const SimRun run(5);
  return run;
}

TEST(StereoVo, StepsMatchGroundTruthOnTheMarsYard) {
  const SimRun& run = shared_run();
  for (VmeMode mode : {VmeMode::k3D, VmeMode::k6D}) {
    Vo v(bench_config(run.bench, mode, true));
    for (int i = 0; i < 5; ++i) {
      Result<VoStep> s = v.vo.process(input(run, i, true));
      ASSERT_TRUE(s.is_ok());
      if (i == 0) {
        EXPECT_TRUE(s->flags & kVoFirstFrame);
        continue;
      }
      ASSERT_TRUE(s->visual) << "frame " << i << " flags " << s->flags << " matches " << s->matches;
      const Pose3 truth = run.truth_step(i);
      EXPECT_LT((s->prev_T_cur.t - truth.t).norm(), 0.006) << "frame " << i;  // 200 mm steps, 3 % worst case
      EXPECT_GE(s->matches, 20u);
      if (mode == VmeMode::k6D) {
        EXPECT_LT(rotation_angle_rad(s->prev_T_cur.R * truth.R.transpose()), deg_to_rad(0.6));
      }
    }
    const Pose3 truth_total = run.world_T_cam[0].inverse().compose(run.world_T_cam[4]);
    EXPECT_LT((v.vo.pose().t - truth_total.t).norm(), 0.015);
  }
}

TEST(StereoVo, RefinedTracksMeasureTheStepRotationSeveralTimesBetter) {
  // 6D-VME alone (no attitude) on 8 rendered steps, with and without the track refinement: the Harris
  // jitter between frames limits the unrefined rotation (Mars yard, seeds 3-10: 0.097 -> 0.025 deg rms
  // about x per step, docs/vo.md).
  static const SimRun run(9);
  double sum2[2] = {0.0, 0.0};
  for (int refine = 0; refine < 2; ++refine) {
    VoConfig c = bench_config(run.bench, VmeMode::k6D, true);
    c.refine_tracks = refine == 1;
    Vo v(c);
    for (int i = 0; i < 9; ++i) {
      Result<VoStep> s = v.vo.process(input(run, i, true));
      ASSERT_TRUE(s.is_ok());
      if (i == 0) continue;
      ASSERT_TRUE(s->visual) << "frame " << i;
      if (refine == 1) {
        EXPECT_GE(s->refined_pairs, 40u) << "frame " << i;
      } else {
        EXPECT_EQ(s->refined_pairs, 0u);
      }
      sum2[refine] += motion::rotation_log(run.truth_step(i).R.transpose() * s->prev_T_cur.R).squaredNorm();
    }
    if (refine == 1) {
      EXPECT_EQ(v.vo.counters().get(VoCounter::kStepNotRefined), 0u);
    }
  }
  const double rms_plain = rad_to_deg(std::sqrt(sum2[0] / 8.0)), rms_refined = rad_to_deg(std::sqrt(sum2[1] / 8.0));
  EXPECT_LT(rms_refined, 0.5 * rms_plain) << rms_refined << " vs " << rms_plain << " deg";
  EXPECT_LT(rms_refined, 0.06);
}

TEST(StereoVo, TheAppearanceTermGetsDescriptorsAndStillMatches) {
  // fc-matching's optional appearance term (eq. 7 times (1 - w) + w ncc): StereoVo fills each landmark's
  // 3x3 block-mean descriptor when the weight is set.
  const SimRun& run = shared_run();
  VoConfig c = bench_config(run.bench, VmeMode::k3D, true);
  c.match.appearance_weight = 0.5;
  Vo v(c);
  for (int i = 0; i < 3; ++i) {
    Result<VoStep> s = v.vo.process(input(run, i, true));
    ASSERT_TRUE(s.is_ok());
    std::size_t with = 0;
    for (const match::Landmark3& l : v.vo.current_landmarks()) {
      if (!l.has_appearance) continue;
      ++with;
      double norm = 0.0, sum = 0.0;
      for (float a : l.appearance) {
        norm += static_cast<double>(a) * static_cast<double>(a);
        sum += static_cast<double>(a);
      }
      EXPECT_NEAR(norm, 1.0, 1e-4);
      EXPECT_NEAR(sum, 0.0, 1e-4);
    }
    EXPECT_GT(with, 9 * v.vo.current_landmarks().size() / 10);
    if (i == 0) continue;
    ASSERT_TRUE(s->visual);
    EXPECT_LT((s->prev_T_cur.t - run.truth_step(i).t).norm(), 0.006);
  }
}

TEST(StereoVo, BadInputIsFlaggedNeverNaNAndTheNextGoodFrameRecovers) {
  const SimRun& run = shared_run();
  Vo v(bench_config(run.bench, VmeMode::k3D, true));
  ASSERT_TRUE(v.vo.process(input(run, 0, true)).is_ok());
  // NaN attitude: flagged, pose unchanged and finite.
  VoInput bad = input(run, 1, true);
  bad.R_prev_cur(1, 1) = std::nan("");
  Result<VoStep> s = v.vo.process(bad);
  ASSERT_TRUE(s.is_ok());
  EXPECT_TRUE(s->flags & kVoBadInput);
  EXPECT_TRUE(s->flags & kVoLost);
  EXPECT_TRUE(s->world_T_cur.is_finite());
  EXPECT_EQ(v.vo.counters().get(VoCounter::kBadAttitude), 1u);
  // The chain was broken: frame 1 restarts; frame 2 is a good visual step again.
  s = v.vo.process(input(run, 1, true));
  EXPECT_TRUE(s->flags & kVoFirstFrame);
  s = v.vo.process(input(run, 2, true));
  ASSERT_TRUE(s->visual);
  EXPECT_LT((s->prev_T_cur.t - run.truth_step(2).t).norm(), 0.006);
  // Empty frame (attitude fine): lost, reference kept, priors chained; frame 4 then matches frame 2.
  VoInput empty = input(run, 3, true);
  empty.left = ConstImageViewU8();
  s = v.vo.process(empty);
  EXPECT_TRUE(s->flags & kVoBadInput);
  s = v.vo.process(input(run, 4, true));
  ASSERT_TRUE(s->visual) << s->flags;
  const Pose3 two_steps = run.world_T_cam[2].inverse().compose(run.world_T_cam[4]);
  EXPECT_LT((s->prev_T_cur.t - two_steps.t).norm(), 0.01);
  EXPECT_EQ(v.vo.counters().get(VoCounter::kBadImage), 1u);
}

TEST(StereoVo, ZeroMatchesAreALostStepDeadReckonedWithOdometry) {
  const SimRun& run = shared_run();
  Vo v(bench_config(run.bench, VmeMode::k3D, false));
  ASSERT_TRUE(v.vo.process(input(run, 0, true)).is_ok());
  // A flat grey frame has no corners: lost, and the odometry prior is integrated instead.
  std::vector<std::uint8_t> grey(run.bench.width() * run.bench.height(), 128);
  VoInput in = input(run, 1, true);
  in.left = ConstImageViewU8::make(grey.data(), run.bench.width(), run.bench.height()).value();
  in.right = in.left;
  Result<VoStep> s = v.vo.process(in);
  ASSERT_TRUE(s.is_ok());
  EXPECT_TRUE(s->flags & kVoLost);
  EXPECT_FALSE(s->visual);
  EXPECT_TRUE(s->world_T_cur.is_finite());
  // The reference (frame 0) was kept: frame 2 (two steps, < 0.5 m) still overlaps it.
  s = v.vo.process(input(run, 2, true));
  EXPECT_TRUE(s->visual) << s->flags;
  // A wrong attitude (23 deg about the optical axis): near neighbours exist in the dense cloud, but their
  // residuals fill the gate (normalised residual ~1.8 against ~0.5 for true steps): flagged, dead-reckoned.
  VoInput wrong = input(run, 4, true);
  wrong.R_prev_cur = rotation_from_rpy(0.0, 0.0, 0.4);
  wrong.t_prior_sigma_m = 0.01;
  s = v.vo.process(wrong);
  ASSERT_TRUE(s.is_ok());
  EXPECT_FALSE(s->visual) << "matches " << s->matches << " normalized residual " << s->normalized_residual;
  EXPECT_TRUE(s->flags & (kVoFewMatches | kVoHighResidual | kVoImplausible));
  EXPECT_TRUE(s->flags & kVoDeadReckoned);
  EXPECT_TRUE(v.vo.pose().is_finite());
}

TEST(StereoVo, ProcessDoesNotAllocate) {
  const SimRun& run = shared_run();
  Vo v(bench_config(run.bench, VmeMode::k6D, true));
  ASSERT_TRUE(v.vo.process(input(run, 0, true)).is_ok());
  const VoInput in1 = input(run, 1, true);  // renders outside the guarded region
  bool visual = false;
  QNAV_EXPECT_NO_ALLOC(visual = v.vo.process(in1).value().visual);
  EXPECT_TRUE(visual);
}

TEST(StereoVo, ProcessWithTheAttitudeFilterDoesNotAllocate) {
  const SimRun& run = shared_run();
  Vo v(bench_config(run.bench, VmeMode::k3D, true));
  ASSERT_TRUE(v.vo.config().estimate_attitude_bias);
  VoInput in0 = input(run, 0, true);
  in0.has_absolute_attitude = true;
  in0.world_R_cam = run.world_T_cam[0].R;
  ASSERT_TRUE(v.vo.process(in0).is_ok());
  VoInput in1 = input(run, 1, true);
  in1.has_absolute_attitude = true;
  in1.world_R_cam = run.world_T_cam[1].R;
  bool corrected = false;
  QNAV_EXPECT_NO_ALLOC(corrected = v.vo.process(in1).value().attitude_corrected);
  EXPECT_TRUE(corrected);
  EXPECT_EQ(v.vo.attitude_filter().vo_steps(), 1u);
}

// A sensor whose drift grows steadily (0.06 / 0.03 / 0.08 deg per frame about camera x / y / z, plus
// 0.05 deg white noise) over 16 frames (~3 m): 3D-VME with the raw sensor bends the path; with the
// attitude filter the end error is smaller. NaN attitude resets the filter, which restarts from the
// next good sample.
TEST(StereoVo, AttitudeFilterReducesTheErrorOfADriftingSensor) {
  static const SimRun run(16);
  const Vec3d drift_per_frame = Vec3d(0.06, 0.03, 0.08) * (kPi / 180.0);
  std::mt19937 rng(5);
  std::normal_distribution<double> n01(0.0, 1.0);
  std::vector<Mat3d> meas;
  for (int i = 0; i < 16; ++i) {
    const Vec3d noise = Vec3d(n01(rng), n01(rng), n01(rng)) * deg_to_rad(0.05);
    meas.push_back(run.world_T_cam[i].R * motion::rotation_exp(drift_per_frame * i + noise));
  }
  double end_err[2] = {0.0, 0.0};
  for (int with = 0; with < 2; ++with) {
    VoConfig c = bench_config(run.bench, VmeMode::k3D, true);
    c.estimate_attitude_bias = with == 1;
    c.attitude_bias.sensor_sigma_rad = deg_to_rad(0.05);
    c.attitude_bias.initial_rate_sigma_rad_s = deg_to_rad(0.01);  // this sensor drifts ~0.01 deg/s
    c.attitude_bias.max_drift_rate_rad_s = deg_to_rad(0.05);
    Vo v(c);
    for (int i = 0; i < 16; ++i) {
      VoInput in = input(run, i, true);
      in.has_absolute_attitude = true;
      in.world_R_cam = meas[i];
      if (i > 0) in.R_prev_cur = meas[i - 1].transpose() * meas[i];
      if (i == 0) v.vo.reset(Pose3{meas[0], run.world_T_cam[0].t});
      Result<VoStep> s = v.vo.process(in);
      ASSERT_TRUE(s.is_ok());
      ASSERT_TRUE(s->world_T_cur.is_finite());
      if (i > 0) {
        EXPECT_TRUE(s->visual) << "frame " << i << " flags " << s->flags;
      }
      EXPECT_EQ(s->attitude_corrected, with == 1);
    }
    end_err[with] = (v.vo.pose().t - run.world_T_cam[15].t).norm();
    if (with == 1) {
      EXPECT_EQ(v.vo.attitude_filter().vo_steps(), 15u);
      // NaN attitude: flagged, the filter is reset and restarts from the next good sample.
      VoInput bad = input(run, 15, true);
      bad.has_absolute_attitude = true;
      bad.world_R_cam = meas[15];
      bad.world_R_cam(2, 2) = std::nan("");
      Result<VoStep> s = v.vo.process(bad);
      ASSERT_TRUE(s.is_ok());
      EXPECT_TRUE(s->flags & kVoBadInput);
      EXPECT_TRUE(s->world_T_cur.is_finite());
      EXPECT_FALSE(v.vo.attitude_filter().initialised());
      VoInput good = input(run, 15, true);
      good.has_absolute_attitude = true;
      good.world_R_cam = meas[15];
      s = v.vo.process(good);
      ASSERT_TRUE(s.is_ok());
      EXPECT_TRUE(s->flags & kVoFirstFrame);
      EXPECT_TRUE(v.vo.attitude_filter().initialised());
      EXPECT_TRUE(v.vo.attitude_filter().corrected().isApprox(meas[15]));
    }
  }
  std::printf("drifting sensor, 16 frames: end error %.1f mm raw, %.1f mm with the attitude filter\n",
              1e3 * end_err[0], 1e3 * end_err[1]);
  EXPECT_LT(end_err[1], 0.6 * end_err[0]);
}

TEST(StereoVo, InitRejectsBadConfigAndProcessBeforeInitIsAnError) {
  StereoVo vo;
  EXPECT_FALSE(vo.process(VoInput{}).is_ok());
  VoConfig c = bench_config(sim::StereoBench{}, VmeMode::k3D, true);
  c.max_corners = 0;
  ArenaStorage a(1 << 20);
  EXPECT_FALSE(vo.init(c, a).is_ok());
  c = bench_config(sim::StereoBench{}, VmeMode::k3D, true);
  c = bench_config(sim::StereoBench{}, VmeMode::k3D, true);
  c.attitude_bias.gate_sigma = -1.0;
  EXPECT_FALSE(vo.init(c, a).is_ok());
  c.attitude_bias.gate_sigma = 5.0;
  c.frame_period_s = 0.0;
  EXPECT_FALSE(vo.init(c, a).is_ok());
  c = bench_config(sim::StereoBench{}, VmeMode::k3D, true);
  c.track_refine.normal_neighbours = 1;
  EXPECT_EQ(vo.init(c, a).code(), StatusCode::kInvalidArgument);
  c = bench_config(sim::StereoBench{}, VmeMode::k3D, true);
  c.refined_lateral_sigma_px = 0.0;
  EXPECT_EQ(vo.init(c, a).code(), StatusCode::kInvalidArgument);
  c = bench_config(sim::StereoBench{}, VmeMode::k3D, true);
  // The reference image for the track refinement is part of the arena.
  VoConfig no_refine = c;
  no_refine.refine_tracks = false;
  EXPECT_GE(StereoVo::arena_bytes(c), StereoVo::arena_bytes(no_refine) + 320u * 256u);
  ArenaStorage small(1024);
  EXPECT_EQ(vo.init(c, small).code(), StatusCode::kCapacityExceeded);
  EXPECT_LT(StereoVo::arena_bytes(c), std::size_t{4} << 20);  // VO working set budget (4 MB) at 320x256
}

}  // namespace
}  // namespace qnav::vo
