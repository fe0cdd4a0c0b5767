// bench_vo: one VO step (frame t-1 -> t) on two rendered Mars-yard frames at 320x256, 300 corners.
// Each iteration processes the reference frame (untimed) then the current one (timed): Harris +
// stereo + matching + 3D/6D-VME + IRLS + ICP. Also the geometric matcher alone on the same landmarks.
#include <benchmark/benchmark.h>
#include "firmware/pipeline/vo_defaults.hpp"
#include "firmware/tools/shared_dir.hpp"

#include <memory>
#include <string>
#include <vector>

#include "drivers/stereo_sim/mars_yard.hpp"
#include "firmware/tools/image_reader.hpp"
#include "nav/vo/stereo_vo.hpp"

namespace {

using namespace qnav;

struct Frames {
  sim::StereoBench bench;
  Image<std::uint8_t> l[2], r[2];
  Pose3 step;
  Frames() {
    const sim::MarsYardTerrain terrain;
    sim::MarsYardTrajectory traj;
    const Pose3 c0 = traj.current().world_T_rover.compose(bench.rover_T_left());
    const Pose3 c1 = traj.next().world_T_rover.compose(bench.rover_T_left());
    step = c0.inverse().compose(c1);
    for (int i = 0; i < 2; ++i) {
      l[i] = std::move(Image<std::uint8_t>::allocate(bench.width(), bench.height()).value());
      r[i] = std::move(Image<std::uint8_t>::allocate(bench.width(), bench.height()).value());
      (void)sim::render_stereo(terrain, bench, i == 0 ? c0 : c1, 5 + i, l[i].view(), r[i].view());
    }
  }
};

const Frames& frames() {
  static const Frames f;
  return f;
}

vo::VoConfig config(vo::VmeMode mode, match::MatchScoreKind score, bool fast) {
  vo::VoConfig c = pipeline::vo_config_for_bench(sim::StereoBench{});
  c.max_corners = 300;
  c.mode = mode;
  c.match.score = score;
  c.match.fast = fast;
  return c;
}

void BM_VoStep(benchmark::State& state, vo::VmeMode mode, match::MatchScoreKind score, bool fast) {
  const Frames& f = frames();
  const vo::VoConfig c = config(mode, score, fast);
  ArenaStorage arena(vo::StereoVo::arena_bytes(c));
  vo::StereoVo v;
  if (!v.init(c, arena)) {
    state.SkipWithError("init failed");
    return;
  }
  vo::VoInput in0, in1;
  in0.left = f.l[0].view();
  in0.right = f.r[0].view();
  in1.left = f.l[1].view();
  in1.right = f.r[1].view();
  in1.R_prev_cur = f.step.R;
  in1.has_translation_prior = true;
  in1.t_prev_cur_prior_m = 1.1 * f.step.t;
  in1.t_prior_sigma_m = 0.04;
  std::size_t matches = 0;
  match::MatchStats stats;
  for (auto _ : state) {
    state.PauseTiming();
    v.reset();
    (void)v.process(in0);
    state.ResumeTiming();
    Result<vo::VoStep> s = v.process(in1);
    matches = s ? s->matches : 0;
    if (s) stats = s->match_stats;
  }
  state.counters["rounds"] = static_cast<double>(stats.rounds);
  state.counters["candidates"] = static_cast<double>(stats.candidates);
  state.counters["pair_evals"] = static_cast<double>(stats.pair_evaluations);
  state.counters["matches"] = static_cast<double>(matches);
  state.counters["arena_bytes"] = static_cast<double>(vo::StereoVo::arena_bytes(c));
  state.counters["matcher_bytes"] = static_cast<double>(v.matcher_bytes());
}

BENCHMARK_CAPTURE(BM_VoStep, 3D_fc_fast, vo::VmeMode::k3D, match::MatchScoreKind::kContinuous, true)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_VoStep, 6D_fc_fast, vo::VmeMode::k6D, match::MatchScoreKind::kContinuous, true)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_VoStep, 3D_fc, vo::VmeMode::k3D, match::MatchScoreKind::kContinuous, false)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_VoStep, 3D_fb, vo::VmeMode::k3D, match::MatchScoreKind::kBinary, false)->Unit(benchmark::kMillisecond);

// One KITTI step (1242x375, 400 corners, 6D-VME, the `qnav vo --kitti` configuration) on frames 10 -> 11
// of the shared city sequence; skipped when the data is absent.
void BM_KittiStep(benchmark::State& state) {
  const std::string dir = qnav::tools::shared_dir() + "/data/stereo/kitti_raw_2011_09_26_0013_city100/";
  Result<ImageU8> l0 = tools::read_image_gray8((dir + "left/0000000010.png").c_str());
  Result<ImageU8> r0 = tools::read_image_gray8((dir + "right/0000000010.png").c_str());
  Result<ImageU8> l1 = tools::read_image_gray8((dir + "left/0000000011.png").c_str());
  Result<ImageU8> r1 = tools::read_image_gray8((dir + "right/0000000011.png").c_str());
  if (!l0 || !r0 || !l1 || !r1) {
    state.SkipWithError("KITTI data not found");
    return;
  }
  // The KITTI preset of `qnav vo --kitti` (pipeline/vo_defaults), unweighted as the tool runs it.
  vo::VoConfig c = pipeline::kitti_vo_config(1242, 375, 721.5377, 609.5593, 172.8540, 0.537150);
  c.weighted = false;
  c.max_rms_residual_m = 0.5;
  c.max_step_m = 4.0;
  ArenaStorage arena(vo::StereoVo::arena_bytes(c));
  vo::StereoVo v;
  if (!v.init(c, arena)) {
    state.SkipWithError("init failed");
    return;
  }
  vo::VoInput in0, in1;
  in0.left = l0->view();
  in0.right = r0->view();
  in1.left = l1->view();
  in1.right = r1->view();
  in1.has_translation_prior = true;
  in1.t_prev_cur_prior_m = Vec3d(0.0, 0.0, 1.17);  // constant-velocity prior, as in the tool
  in1.t_prior_sigma_m = 0.33;
  std::size_t matches = 0;
  for (auto _ : state) {
    state.PauseTiming();
    v.reset();
    (void)v.process(in0);
    state.ResumeTiming();
    Result<vo::VoStep> s = v.process(in1);
    matches = s ? s->matches : 0;
  }
  state.counters["matches"] = static_cast<double>(matches);
  state.counters["arena_bytes"] = static_cast<double>(vo::StereoVo::arena_bytes(c));
}
BENCHMARK(BM_KittiStep)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
