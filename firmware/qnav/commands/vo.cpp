// qnav vo: stereo visual odometry (Mars paper) on the synthetic Mars yard, KITTI and EuRoC sequences.
//
//   qnav vo eval [--json] [--quick] [--noise small|moderate|none] [--configs main|att|all] [--seed N]
//                [--seeds N,M,... | --seeds A-B]
//                [--traj-dir DIR] [--length-27 M] [--length-100 M] [--calib-27 M] [--verbose]
//                tuning knobs: [--nt X] [--sigma-m-deg D] [--dsig PX] [--nsig N] [--app W] [--lat-px PX]
//                attitude filter knobs: [--att-vo-scale X] [--att-rate-scale X] [--att-no-step-rot] [--att-iso]
//                [--att-filtered]
//                track refinement knobs: [--no-refine] [--no-refine-disparity] [--ref-lat-px PX] [--track-radius R]
//       Synthetic evaluation with exact ground truth: a 27 m run (attitude drifting, no recalibration)
//       and a 100 m run (attitude recalibrated every 2 m), paper's noise model (n_t = 10 %, small
//       attitude noise), frames rendered once and fed to every configuration. Prints one JSON object
//       (--json) or a table. --quick: 6 m and 10 m (for the demo). --traj-dir writes per-config CSVs
//       (path_m, err_m, primary seed) for scripts/vo_plot.py. --seeds runs every seed (the first is the
//       primary: rel_error_pct_27m / _100m), and reports per-seed lists, max and mean, and per
//       configuration the visual step rotation's error over the 27 m runs (step_rot_rms_deg /
//       step_rot_mean_deg per camera axis; 6D modes and 3D with the attitude filter).
//       Configurations: main = 3D-fc-fast-att (3D-VME with the attitude drift filter, the default),
//       3D-fc-fast (the paper's 3D-VME), 6D-fc-fast; att = the first only; all = + full fc / fb.
//   qnav vo --kitti DIR [--calib FILE] --out poses.txt [--frames N] [--peer FILE] [--weighted] [--max-depth M]
//       Rectified KITTI-layout sequence; no attitude sensor: 6D-VME with a constant-velocity prior.
//       Writes the KITTI pose format (row-major 3x4 per frame, left camera in frame-0 coordinates),
//       prints per-frame time; with --peer compares path and end point against a peer trajectory.
//   qnav vo --euroc DIR --out poses.txt [--frames N]
//       Raw EuRoC pairs: rectified with nav/vision's RemapTable, 6D-VME, zero-motion prior; prints the
//       drift against groundtruth_tum.txt when present.
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "drivers/stereo_sim/mars_yard.hpp"
#include "drivers/stereo_sim/noise_model.hpp"
#include "firmware/cli/cli_app.hpp"
#include "firmware/qnav/command.hpp"
#include "firmware/pipeline/vo_defaults.hpp"
#include "firmware/pipeline/vo_odometry.hpp"
#include "firmware/tools/image_reader.hpp"
#include "firmware/tools/sequence_reader.hpp"
#include "nav/vision/rectify.hpp"
#include "nav/vo/stereo_vo.hpp"

namespace {

using namespace qnav;
using Clock = std::chrono::steady_clock;
// `qnav vo eval`'s tuning knobs: each starts at the value of pipeline::default_vo_config (what the
// daemon runs); the command line moves them for an experiment.
struct EvalKnobs {
  bool verbose = false;
  double dsig = 0.15, nsig = 3.0, app = 0.0;
  double att_vo_scale = pipeline::kVoRotationSigmaScale, att_rate_scale = 1.0, lat_px = -1.0;
  bool att_step_rot = true, att_aniso = true, att_filtered = false;
  bool refine = true, refine_disp = true;
  double ref_lat_px = -1.0, track_radius = 0.0;
};

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// One configuration of the evaluation: the VO component qnavd's vo mode runs (pipeline::VoOdometry),
// the camera as the body.
struct VoBox {
  pipeline::VoOdometry odo;
  bool init(const vo::VoConfig& c) {
    const Status s = odo.init(c, Pose3{});
    if (!s) std::fprintf(stderr, "vo: init failed: %s\n", s.message());
    return s.is_ok();
  }
  const vo::StereoVo& vo() const { return odo.vo(); }
};

// ---------------------------------------------------------------------------------------------------
// Synthetic evaluation
struct EvalConfig {
  const char* name;
  vo::VmeMode mode;
  match::MatchScoreKind score;
  bool fast;
  bool attitude_bias;  // AttitudeBiasFilter on (3D only)
};

// The first entry is the main configuration (reported as rel_error_pct_27m / _100m).
const EvalConfig kMain = {"3D-fc-fast-att", vo::VmeMode::k3D, match::MatchScoreKind::kContinuous, true, true};
const EvalConfig kMainSet[] = {
    kMain,
    {"3D-fc-fast", vo::VmeMode::k3D, match::MatchScoreKind::kContinuous, true, false},
    {"6D-fc-fast", vo::VmeMode::k6D, match::MatchScoreKind::kContinuous, true, false},
};
const EvalConfig kAll[] = {
    kMain,
    {"3D-fc-fast", vo::VmeMode::k3D, match::MatchScoreKind::kContinuous, true, false},
    {"3D-fc", vo::VmeMode::k3D, match::MatchScoreKind::kContinuous, false, false},
    {"3D-fb", vo::VmeMode::k3D, match::MatchScoreKind::kBinary, false, false},
    {"6D-fc-fast", vo::VmeMode::k6D, match::MatchScoreKind::kContinuous, true, false},
    {"6D-fc", vo::VmeMode::k6D, match::MatchScoreKind::kContinuous, false, false},
    {"6D-fb", vo::VmeMode::k6D, match::MatchScoreKind::kBinary, false, false},
};

struct RunResult {
  double path_m = 0.0;
  double end_error_m = 0.0;
  double max_error_m = 0.0;
  std::vector<double> step_ms;
  std::size_t frames = 0, lost = 0;
  std::vector<double> trace_path, trace_err;
  // Error of the visual step rotation per axis (camera frame, deg): the attitude filter's 6D rotation in
  // 3D-att mode, the integrated step in 6D mode (3D mode without the filter has none).
  Vec3d rot_sum_deg = Vec3d::Zero(), rot_sum2_deg = Vec3d::Zero();
  std::size_t rot_n = 0;
};

struct Scenario {
  const char* name;
  double length_m;
  double calib_every_m;  // <= 0: never
};

// Renders the run once and feeds every configuration.
bool run_scenario(const Scenario& sc, const std::vector<EvalConfig>& cfgs, const sim::NoiseConfig& noise_cfg, const EvalKnobs& knobs,
                  std::uint64_t seed, std::vector<RunResult>& results) {
  sim::MarsYardConfig yard;
  yard.seed = seed;
  const sim::MarsYardTerrain terrain(yard);
  const sim::StereoBench bench;
  sim::TrajectoryConfig tc;
  tc.seed = seed + 1;
  sim::MarsYardTrajectory traj(tc);
  sim::NoiseModel noise(noise_cfg, seed + 2);
  std::vector<std::unique_ptr<VoBox>> vos;
  for (const EvalConfig& e : cfgs) {
    vo::VoConfig c = pipeline::default_vo_config(bench, noise_cfg);  // the main configuration, then this one's
    c.mode = e.mode;
    c.match.score = e.score;
    c.match.fast = e.fast;
    c.stereo.disparity_sigma_px = static_cast<float>(knobs.dsig);
    c.match.n_sigma = knobs.nsig;
    c.match.appearance_weight = knobs.app;
    c.estimate_attitude_bias = e.attitude_bias;
    c.attitude_bias.vo_sigma_scale = knobs.att_vo_scale;
    c.attitude_bias.initial_rate_sigma_rad_s *= knobs.att_rate_scale;
    c.attitude_bias.rate_walk_rad_s_sqrt_s *= knobs.att_rate_scale;
    c.corrected_step_rotation = knobs.att_step_rot;
    c.anisotropic_vo_rotation = knobs.att_aniso;
    c.use_filtered_orientation = knobs.att_filtered;
    if (knobs.lat_px > 0.0) c.lateral_sigma_px = knobs.lat_px;
    c.refine_tracks = knobs.refine;
    c.refine_disparity = knobs.refine_disp;
    if (knobs.ref_lat_px > 0.0) c.refined_lateral_sigma_px = knobs.ref_lat_px;
    if (knobs.track_radius > 0.0) c.track_refine.align.radius = static_cast<int>(knobs.track_radius);
    std::unique_ptr<VoBox> b(new VoBox);
    if (!b->init(c)) return false;
    vos.push_back(std::move(b));
  }
  results.assign(cfgs.size(), RunResult{});
  Image<std::uint8_t> left = std::move(Image<std::uint8_t>::allocate(bench.width(), bench.height()).value());
  Image<std::uint8_t> right = std::move(Image<std::uint8_t>::allocate(bench.width(), bench.height()).value());
  Pose3 prev_cam, start_cam;
  double last_calib_m = 0.0;
  for (std::size_t frame = 0;; ++frame) {
    const sim::RoverSample& s = frame == 0 ? traj.current() : traj.next();
    if (s.path_m > sc.length_m + 1e-9) break;
    const Pose3 cam = s.world_T_rover.compose(bench.rover_T_left());
    noise.advance_to(s.time_s);
    bool recalibrated = false;
    if (sc.calib_every_m > 0.0 && s.path_m - last_calib_m >= sc.calib_every_m - 1e-9) {
      noise.calibrate();
      last_calib_m = s.path_m;
      recalibrated = true;
    }
    const Mat3d meas = noise.measure_attitude(cam.R);
    if (!sim::render_stereo(terrain, bench, cam, seed * 100000 + frame, left.view(), right.view())) return false;
    // The attitude sensor's sample (the rotation prior is the component's: the relative attitude) and
    // the odometry step measured from the truth (noise model), in the previous camera frame.
    pipeline::VoFrameInput in;
    in.left = left.view();
    in.right = right.view();
    in.has_attitude = true;
    in.world_R_body = meas;
    in.attitude_recalibrated = recalibrated;
    in.stamp_ns = static_cast<std::uint64_t>(std::llround(s.time_s * 1e9)) + 1;  // never 0 (0 = no stamp)
    if (frame == 0) {
      start_cam = cam;
      for (auto& v : vos) v->odo.reset(cam, true);  // the chain starts on the true pose
    } else {
      const Pose3 truth_step = prev_cam.inverse().compose(cam);
      in.has_camera_translation_prior = true;
      in.t_prev_cur_cam_m = noise.measure_translation(truth_step.t);
      in.camera_translation_sigma_m = 0.01 + 1.5 * noise_cfg.translation_noise * truth_step.t.norm();
    }
    for (std::size_t k = 0; k < vos.size(); ++k) {
      const Clock::time_point t0 = Clock::now();
      Result<vo::VoStep> r = vos[k]->odo.step(in);
      const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
      RunResult& rr = results[k];
      ++rr.frames;
      if (frame > 0) rr.step_ms.push_back(ms);
      if (knobs.verbose && frame > 0 && r) {
        const Pose3 ts = prev_cam.inverse().compose(cam);
        const Vec3d d = r->prev_T_cur.t - ts.t;
        const Mat3d& Rv = r->has_vo_rotation ? r->vo_R_prev_cur : r->prev_T_cur.R;
        const Vec3d rot_err = motion::rotation_log(ts.R.transpose() * Rv);
        const Mat3d rc = r->has_vo_rotation ? r->vo_rotation_cov_right
                                            : Mat3d(Rv.transpose() * r->covariance.topLeftCorner<3, 3>() * Rv);
        const Vec3d att_err = motion::rotation_log(cam.R.transpose() * vos[k]->vo().pose().R);
        std::printf("%s f%zu %s corners %zu stereo %zu matches %zu rms %.4f step %.4f err %+.4f %+.4f %+.4f flags 0x%x  "
                    "step_rot_err %+.4f %+.4f %+.4f deg pred_sigma %.4f %.4f %.4f deg  att_err %+.4f %+.4f %+.4f deg "
                    "drift %+.4f %+.4f %+.4f est %+.4f %+.4f %+.4f deg true_rot %+.4f %+.4f %+.4f\n",
                    cfgs[k].name, frame, sc.name, r->corners, r->stereo_points, r->matches, r->rms_residual_m,
                    ts.t.norm(), d.x(), d.y(), d.z(), r->flags, rad_to_deg(rot_err.x()), rad_to_deg(rot_err.y()),
                    rad_to_deg(rot_err.z()), rad_to_deg(std::sqrt(std::max(0.0, rc(0, 0)))),
                    rad_to_deg(std::sqrt(std::max(0.0, rc(1, 1)))), rad_to_deg(std::sqrt(std::max(0.0, rc(2, 2)))),
                    rad_to_deg(att_err.x()), rad_to_deg(att_err.y()), rad_to_deg(att_err.z()),
                    rad_to_deg(noise.drift_rad().x()), rad_to_deg(noise.drift_rad().y()),
                    rad_to_deg(noise.drift_rad().z()), rad_to_deg(r->attitude_drift_rad.x()),
                    rad_to_deg(r->attitude_drift_rad.y()), rad_to_deg(r->attitude_drift_rad.z()),
                    rad_to_deg(motion::rotation_log(ts.R).x()), rad_to_deg(motion::rotation_log(ts.R).y()),
                    rad_to_deg(motion::rotation_log(ts.R).z()));
      }
      if (!r || (frame > 0 && !r->visual)) ++rr.lost;
      if (r && frame > 0 && r->visual && (r->has_vo_rotation || cfgs[k].mode == vo::VmeMode::k6D)) {
        const Mat3d& Rv = r->has_vo_rotation ? r->vo_R_prev_cur : r->prev_T_cur.R;
        const Vec3d e = motion::rotation_log(prev_cam.inverse().compose(cam).R.transpose() * Rv) * (180.0 / M_PI);
        rr.rot_sum_deg += e;
        rr.rot_sum2_deg += e.cwiseAbs2();
        ++rr.rot_n;
      }
      const double err = (vos[k]->vo().pose().t - cam.t).norm();
      rr.max_error_m = std::max(rr.max_error_m, err);
      rr.end_error_m = err;
      rr.path_m = s.path_m;
      rr.trace_path.push_back(s.path_m);
      rr.trace_err.push_back(err);
    }
    prev_cam = cam;
  }
  if (knobs.verbose) {
    for (std::size_t k = 0; k < vos.size(); ++k) {
      std::printf("%s %s counters:", cfgs[k].name, sc.name);
      const auto& vc = vos[k]->vo().counters();
      for (std::size_t i = 0; i < vc.size(); ++i)
        if (vc.count_at(i) != 0) std::printf(" %s=%u", vc.name_at(i), vc.count_at(i));
      const auto& ac = vos[k]->vo().attitude_filter().counters();
      for (std::size_t i = 0; i < ac.size(); ++i)
        if (ac.count_at(i) != 0) std::printf(" %s=%u", ac.name_at(i), ac.count_at(i));
      std::printf("\n");
    }
  }
  return true;
}

// Every vo option (one invocation per process), declared in setup_vo below. NaN: "not given".
struct VoOptions {
  bool json = false, quick = false;
  EvalKnobs knobs;
  std::string noise = "small", configs = "main", traj_dir, seeds;
  long seed = 3;
  double nt = std::nan(""), sigma_m_deg = std::nan(""), len27 = std::nan(""), len100 = std::nan(""), calib27 = 0.0;
  bool no_refine = false, no_refine_disp = false, att_no_step_rot = false, att_iso = false;
  std::string kitti, euroc, calib, out, peer;
  long frames = 100000;
  double max_depth = std::nan("");
  bool weighted = false;
};
VoOptions g_opt;

// --seeds: a comma list ("3,4,5") or an inclusive range ("3-7"), at most 100; empty: none.
bool parse_seeds(const std::string& text, std::vector<long>& seeds) {
  if (text.empty()) return true;
  const char* ss = text.c_str();
  long a = 0, b = 0;
  char dash = 0;
  if (std::sscanf(ss, "%ld%c%ld", &a, &dash, &b) == 3 && dash == '-' && a >= 0 && b >= a && b - a < 100) {
    for (long v = a; v <= b; ++v) seeds.push_back(v);
    return true;
  }
  const char* p = ss;
  while (*p != 0) {
    char* e = nullptr;
    const long v = std::strtol(p, &e, 10);
    if (e == p || v < 0 || seeds.size() >= 100) return false;
    seeds.push_back(v);
    p = (*e == ',') ? e + 1 : e;
    if (*e != ',' && *e != 0) return false;
  }
  return true;
}

// res[s][i][k]: seed s, scenario i (27 m, 100 m), configuration k.
using EvalResults = std::vector<std::array<std::vector<RunResult>, 2>>;

double end_pct(const RunResult& r) { return r.path_m > 0.0 ? 100.0 * r.end_error_m / r.path_m : 0.0; }
double max_pct(const RunResult& r) { return r.path_m > 0.0 ? 100.0 * r.max_error_m / r.path_m : 0.0; }

// One configuration's figure over the seeds.
struct SeedStats {
  std::vector<double> v;
  double max() const { return v.empty() ? 0.0 : *std::max_element(v.begin(), v.end()); }
  double mean() const {
    double s = 0.0;
    for (double x : v) s += x;
    return v.empty() ? 0.0 : s / static_cast<double>(v.size());
  }
  void print() const {
    std::printf("[");
    for (std::size_t j = 0; j < v.size(); ++j) std::printf("%s%.3f", j ? "," : "", v[j]);
    std::printf("]");
  }
};
SeedStats end_pct_over_seeds(const EvalResults& res, std::size_t k, int i) {
  SeedStats st;
  for (const auto& r : res) st.v.push_back(end_pct(r[i][k]));
  return st;
}
std::vector<double> step_ms_over_seeds(const EvalResults& res, std::size_t k) {
  std::vector<double> ms;
  for (const auto& r : res)
    for (int i = 0; i < 2; ++i) ms.insert(ms.end(), r[i][k].step_ms.begin(), r[i][k].step_ms.end());
  return ms;
}
std::size_t lost_over_seeds(const EvalResults& res, std::size_t k, int i) {
  std::size_t n = 0;
  for (const auto& r : res) n += r[i][k].lost;
  return n;
}

void print_eval_json(const EvalResults& res, const std::vector<EvalConfig>& cfgs, const std::vector<long>& seeds, const char* noise_name) {
  const SeedStats s27 = end_pct_over_seeds(res, 0, 0), s100 = end_pct_over_seeds(res, 0, 1);
  std::printf("{\"noise\":\"%s\",\"seed\":%ld,\"seeds\":[", noise_name, seeds[0]);
  for (std::size_t si = 0; si < seeds.size(); ++si) std::printf("%s%ld", si ? "," : "", seeds[si]);
  std::printf("],\"main\":\"%s\",\"rel_error_pct_27m\":%.3f,\"rel_error_pct_100m\":%.3f,\"rel_error_pct_27m_seeds\":",
              cfgs[0].name, end_pct(res[0][0][0]), end_pct(res[0][1][0]));
  s27.print();
  std::printf(",\"rel_error_pct_27m_max\":%.3f,\"rel_error_pct_27m_mean\":%.3f,\"rel_error_pct_100m_seeds\":", s27.max(),
              s27.mean());
  s100.print();
  std::printf(",\"rel_error_pct_100m_max\":%.3f,\"rel_error_pct_100m_mean\":%.3f,\"step_ms_median\":%.3f,"
              "\"image\":\"320x256\",\"length_27m_m\":%.2f,\"length_100m_m\":%.2f,\"configs\":[",
              s100.max(), s100.mean(), median(step_ms_over_seeds(res, 0)), res[0][0][0].path_m, res[0][1][0].path_m);
  for (std::size_t k = 0; k < cfgs.size(); ++k) {
    const SeedStats a = end_pct_over_seeds(res, k, 0), b = end_pct_over_seeds(res, k, 1);
    // Step rotation error over every seed's 27 m run.
    Vec3d rs = Vec3d::Zero(), rs2 = Vec3d::Zero();
    std::size_t rn = 0;
    for (std::size_t si = 0; si < seeds.size(); ++si) {
      rs += res[si][0][k].rot_sum_deg;
      rs2 += res[si][0][k].rot_sum2_deg;
      rn += res[si][0][k].rot_n;
    }
    const double nn = rn > 0 ? static_cast<double>(rn) : 1.0;
    std::printf("%s{\"name\":\"%s\",\"step_rot_steps\":%zu,\"step_rot_rms_deg\":[%.4f,%.4f,%.4f],"
                "\"step_rot_mean_deg\":[%.4f,%.4f,%.4f],",
                k ? "," : "", cfgs[k].name, rn, std::sqrt(rs2.x() / nn), std::sqrt(rs2.y() / nn), std::sqrt(rs2.z() / nn),
                rs.x() / nn, rs.y() / nn, rs.z() / nn);
    std::printf("\"rel_error_pct_27m\":%.3f,\"max_error_pct_27m\":%.3f,\"rel_error_pct_100m\":%.3f,"
                "\"max_error_pct_100m\":%.3f,\"rel_error_pct_27m_seeds\":",
                end_pct(res[0][0][k]), max_pct(res[0][0][k]), end_pct(res[0][1][k]),
                max_pct(res[0][1][k]));
    a.print();
    std::printf(",\"rel_error_pct_27m_max\":%.3f,\"rel_error_pct_27m_mean\":%.3f,\"rel_error_pct_100m_seeds\":", a.max(),
                a.mean());
    b.print();
    std::printf(",\"rel_error_pct_100m_max\":%.3f,\"step_ms_median\":%.3f,\"lost_27m\":%zu,\"lost_100m\":%zu}", b.max(),
                median(step_ms_over_seeds(res, k)), lost_over_seeds(res, k, 0), lost_over_seeds(res, k, 1));
  }
  std::printf("]}\n");
}

void print_eval_text(const EvalResults& res, const std::vector<EvalConfig>& cfgs, const std::vector<long>& seeds, const char* noise_name) {
  std::printf("synthetic Mars yard, noise %s, 320x256, 300 corners\n", noise_name);
  std::printf("%-15s %5s %10s %10s %10s %10s %8s %6s\n", "config", "seed", "end%27m", "end%100m", "max%27m", "max%100m",
              "ms/step", "lost");
  for (std::size_t k = 0; k < cfgs.size(); ++k) {
    for (std::size_t si = 0; si < seeds.size(); ++si) {
      const RunResult& a = res[si][0][k];
      const RunResult& b = res[si][1][k];
      std::vector<double> ms = a.step_ms;
      ms.insert(ms.end(), b.step_ms.begin(), b.step_ms.end());
      std::printf("%-15s %5ld %10.3f %10.3f %10.3f %10.3f %8.2f %6zu\n", cfgs[k].name, seeds[si], end_pct(a), end_pct(b),
                  max_pct(a), max_pct(b), median(ms), a.lost + b.lost);
    }
    if (seeds.size() > 1) {
      const SeedStats a = end_pct_over_seeds(res, k, 0), b = end_pct_over_seeds(res, k, 1);
      std::printf("%-15s %5s %10.3f %10.3f   (mean %.3f / %.3f)\n", cfgs[k].name, "max", a.max(), b.max(), a.mean(),
                  b.mean());
    }
  }
}

int run_eval() {
  const bool json = g_opt.json;
  const bool quick = g_opt.quick;
  EvalKnobs knobs = g_opt.knobs;
  const char* noise_name = g_opt.noise.c_str();
  const char* configs = g_opt.configs.c_str();
  const char* traj_dir = g_opt.traj_dir.empty() ? nullptr : g_opt.traj_dir.c_str();
  long seed = g_opt.seed;
  if (traj_dir != nullptr) {
    if (const std::string e = qnav::cli::make_dirs(traj_dir); !e.empty()) {
      std::fprintf(stderr, "vo eval: %s\n", e.c_str());
      return 1;
    }
  }
  sim::NoiseConfig noise = sim::NoiseConfig::small();
  if (std::strcmp(noise_name, "moderate") == 0) noise = sim::NoiseConfig::moderate();
  else if (std::strcmp(noise_name, "none") == 0) noise = sim::NoiseConfig::none();
  else if (std::strcmp(noise_name, "small") != 0) {
    std::fprintf(stderr, "vo eval: --noise small|moderate|none\n");
    return 2;
  }
  double nt = noise.translation_noise, sm_deg = rad_to_deg(noise.sigma_m_rad);
  if (!std::isnan(g_opt.nt)) nt = g_opt.nt;
  if (!std::isnan(g_opt.sigma_m_deg)) sm_deg = g_opt.sigma_m_deg;
  noise.translation_noise = nt;
  knobs.refine = !g_opt.no_refine;
  knobs.refine_disp = !g_opt.no_refine_disp;
  knobs.att_step_rot = !g_opt.att_no_step_rot;
  knobs.att_aniso = !g_opt.att_iso;
  noise.sigma_m_rad = deg_to_rad(sm_deg);
  std::vector<EvalConfig> cfgs;
  if (std::strcmp(configs, "main") == 0) {
    for (const EvalConfig& e : kMainSet) cfgs.push_back(e);
  } else if (std::strcmp(configs, "att") == 0) {
    cfgs.push_back(kMain);
  } else {
    for (const EvalConfig& e : kAll) cfgs.push_back(e);
  }
  double len27 = quick ? 6.0 : 27.0, len100 = quick ? 10.0 : 100.0;
  if (!std::isnan(g_opt.len27)) len27 = g_opt.len27;
  if (!std::isnan(g_opt.len100)) len100 = g_opt.len100;
  if (!(len27 > 0.5) || !(len100 > 0.5)) {
    std::fprintf(stderr, "vo eval: --length-27 / --length-100 want metres > 0.5\n");
    return 2;
  }
  const double calib27 = g_opt.calib27;  // the 27 m run lets the attitude drift unless told otherwise
  const Scenario scen[2] = {{"27m", len27, calib27}, {"100m", len100, 2.0}};
  std::vector<long> seeds;
  if (!parse_seeds(g_opt.seeds, seeds)) {
    std::fprintf(stderr, "vo eval: --seeds wants N,M,... or A-B (non-negative)\n");
    return 2;
  }
  if (seeds.empty()) seeds.push_back(seed);
  // res[s][i][k]: seed s, scenario i, configuration k.
  EvalResults res(seeds.size());
  for (std::size_t si = 0; si < seeds.size(); ++si) {
    for (int i = 0; i < 2; ++i) {
      if (!run_scenario(scen[i], cfgs, noise, knobs, static_cast<std::uint64_t>(seeds[si]) + 10 * static_cast<std::uint64_t>(i),
                        res[si][i])) {
        std::fprintf(stderr, "vo eval: scenario %s failed\n", scen[i].name);
        return 1;
      }
    }
  }
  if (traj_dir != nullptr) {
    for (int i = 0; i < 2; ++i)
      for (std::size_t k = 0; k < cfgs.size(); ++k) {
        const std::string path = std::string(traj_dir) + "/vo_" + scen[i].name + "_" + cfgs[k].name + ".csv";
        FILE* f = std::fopen(path.c_str(), "w");
        if (f == nullptr) {
          std::fprintf(stderr, "vo eval: cannot write %s\n", path.c_str());
          return 1;
        }
        std::fprintf(f, "path_m,err_m\n");
        const RunResult& rr = res[0][i][k];  // primary seed
        for (std::size_t j = 0; j < rr.trace_path.size(); ++j) std::fprintf(f, "%.4f,%.5f\n", rr.trace_path[j], rr.trace_err[j]);
        std::fclose(f);
      }
  }
  if (json)
    print_eval_json(res, cfgs, seeds, noise_name);
  else
    print_eval_text(res, cfgs, seeds, noise_name);
  return 0;
}

// ---------------------------------------------------------------------------------------------------
// Real sequences
void write_kitti_pose(FILE* f, const Pose3& p) {
  std::fprintf(f, "%.9g %.9g %.9g %.9g %.9g %.9g %.9g %.9g %.9g %.9g %.9g %.9g\n", p.R(0, 0), p.R(0, 1), p.R(0, 2),
               p.t.x(), p.R(1, 0), p.R(1, 1), p.R(1, 2), p.t.y(), p.R(2, 0), p.R(2, 1), p.R(2, 2), p.t.z());
}

bool read_kitti_poses(const char* path, std::vector<Pose3>& out) {
  FILE* f = std::fopen(path, "r");
  if (f == nullptr) return false;
  double v[12];
  while (std::fscanf(f, "%lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf", &v[0], &v[1], &v[2], &v[3], &v[4], &v[5],
                     &v[6], &v[7], &v[8], &v[9], &v[10], &v[11]) == 12) {
    Pose3 p;
    p.R << v[0], v[1], v[2], v[4], v[5], v[6], v[8], v[9], v[10];
    p.t = Vec3d(v[3], v[7], v[11]);
    out.push_back(p);
  }
  std::fclose(f);
  return true;
}

struct SequenceRun {
  std::vector<Pose3> poses;
  std::vector<double> ms;
  std::size_t lost = 0;
};

// Runs 6D-VME over rectified pairs with no attitude sensor, through pipeline::VoOdometry (the wiring
// qnavd runs; the camera is the body) with the preset's prior (pipeline/vo_defaults: constant velocity
// for the car, zero motion for a hover).
template <typename LoadPair>
bool run_sequence(vo::VoConfig c, std::size_t frames, LoadPair load, const pipeline::VoPriorConfig& prior, bool verbose,
                  SequenceRun& run) {
  pipeline::VoOdometry odo;
  const Status init = odo.init(c, Pose3{}, prior);
  if (!init) {
    std::fprintf(stderr, "vo: init failed: %s\n", init.message());
    return false;
  }
  for (std::size_t i = 0; i < frames; ++i) {
    ImageU8 l, r;
    if (!load(i, l, r)) return false;
    pipeline::VoFrameInput in;
    in.left = l.view();
    in.right = r.view();
    const Clock::time_point t0 = Clock::now();
    Result<vo::VoStep> s = odo.step(in);
    const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    if (!s) return false;
    if (i > 0) run.ms.push_back(ms);
    if (i > 0 && !s->visual) ++run.lost;
    run.poses.push_back(odo.vo().pose());
    if (verbose)
      std::printf("frame %3zu  %6.2f ms  corners %3zu stereo %3zu matches %3zu  rms %.4f m  flags 0x%03x  t %.3f %.3f %.3f\n",
                  i, ms, s->corners, s->stereo_points, s->matches, s->rms_residual_m, s->flags, odo.vo().pose().t.x(),
                  odo.vo().pose().t.y(), odo.vo().pose().t.z());
  }
  return true;
}

double path_length(const std::vector<Pose3>& p) {
  double s = 0.0;
  for (std::size_t i = 1; i < p.size(); ++i) s += (p[i].t - p[i - 1].t).norm();
  return s;
}

bool write_poses(const char* out, const std::vector<Pose3>& poses) {
  FILE* f = std::fopen(out, "w");
  if (f == nullptr) return false;
  for (const Pose3& p : poses) write_kitti_pose(f, p);
  return std::fclose(f) == 0;
}

// --out is required with --kitti / --euroc; its folder is created.
bool check_out(const char* what) {
  if (g_opt.out.empty()) {
    std::fprintf(stderr, "qnav vo: %s needs --out poses.txt (qnav help vo)\n", what);
    return false;
  }
  if (const std::string e = qnav::cli::make_parent_dirs(g_opt.out); !e.empty()) {
    std::fprintf(stderr, "qnav vo: %s\n", e.c_str());
    return false;
  }
  return true;
}

int run_kitti() {
  const char* dir = g_opt.kitti.c_str();
  if (!check_out("--kitti")) return 2;
  const char* out = g_opt.out.c_str();
  const std::string calib_path = g_opt.calib.empty() ? std::string(dir) + "/calib.txt" : g_opt.calib;
  const char* peer = g_opt.peer.empty() ? nullptr : g_opt.peer.c_str();
  const long max_frames = g_opt.frames;
  if (const std::string e = qnav::cli::input_dir_problem(dir); !e.empty()) {
    std::fprintf(stderr, "qnav vo: --kitti %s\n", e.c_str());
    return 1;
  }
  std::vector<tools::StereoFrame> frames;
  Status s = tools::read_kitti_sequence(dir, frames);
  Result<tools::KittiCalib> calib = tools::read_kitti_calib(calib_path);
  if (!s || !calib) {
    std::fprintf(stderr, "qnav vo: %s: cannot read the KITTI sequence/calibration: %s\n", dir, !s ? s.message() : calib.status().message());
    return 1;
  }
  const std::size_t n = std::min<std::size_t>(frames.size(), static_cast<std::size_t>(max_frames));
  vo::VoConfig c = pipeline::kitti_vo_config(calib->width, calib->height, calib->f_px, calib->cu_px, calib->cv_px, calib->baseline_m);
  if (!std::isnan(g_opt.max_depth)) c.max_depth_m = g_opt.max_depth;
  if (g_opt.weighted) c.weighted = true;  // the preset is unweighted (vo_defaults)
  SequenceRun run;
  auto load = [&](std::size_t i, ImageU8& l, ImageU8& r) {
    Result<ImageU8> a = tools::read_image_gray8(frames[i].left_path.c_str());
    Result<ImageU8> b = tools::read_image_gray8(frames[i].right_path.c_str());
    if (!a || !b) {
      std::fprintf(stderr, "vo: cannot read frame %zu\n", i);
      return false;
    }
    l = std::move(a.value());
    r = std::move(b.value());
    return true;
  };
  if (!run_sequence(c, n, load, pipeline::kitti_vo_prior(), true, run)) return 1;
  if (!write_poses(out, run.poses)) {
    std::fprintf(stderr, "vo: cannot write %s\n", out);
    return 1;
  }
  const Pose3& end = run.poses.back();
  std::printf("kitti: %zu frames, step median %.2f ms, lost %zu, path %.2f m, end (%.2f, %.2f, %.2f) m\n", n,
              median(run.ms), run.lost, path_length(run.poses), end.t.x(), end.t.y(), end.t.z());
  if (peer != nullptr) {
    std::vector<Pose3> p;
    if (!read_kitti_poses(peer, p) || p.size() < n) {
      std::fprintf(stderr, "vo: cannot read peer trajectory %s\n", peer);
      return 1;
    }
    p.resize(n);
    const double peer_path = path_length(p);
    double max_diff = 0.0;
    for (std::size_t i = 0; i < n; ++i) max_diff = std::max(max_diff, (p[i].t - run.poses[i].t).norm());
    std::printf("peer (libviso2, not ground truth): path %.2f m, end (%.2f, %.2f, %.2f) m; end-point difference %.2f m "
                "(%.2f %% of path), max difference %.2f m, path-length difference %.2f %%\n",
                peer_path, p.back().t.x(), p.back().t.y(), p.back().t.z(), (p.back().t - end.t).norm(),
                100.0 * (p.back().t - end.t).norm() / peer_path, max_diff,
                100.0 * (path_length(run.poses) - peer_path) / peer_path);
  }
  return 0;
}

int run_euroc() {
  const std::string dir = g_opt.euroc;
  if (!check_out("--euroc")) return 2;
  const char* out = g_opt.out.c_str();
  const long max_frames = g_opt.frames;
  if (const std::string e = qnav::cli::input_dir_problem(dir); !e.empty()) {
    std::fprintf(stderr, "qnav vo: --euroc %s\n", e.c_str());
    return 1;
  }
  std::vector<tools::StereoFrame> frames;
  const Status s = tools::read_euroc_sequence(dir, frames);
  Result<tools::EurocCamera> c0 = tools::read_euroc_camera(dir + "/cam0/sensor.yaml");
  Result<tools::EurocCamera> c1 = tools::read_euroc_camera(dir + "/cam1/sensor.yaml");
  if (!s || !c0 || !c1) {
    std::fprintf(stderr, "qnav vo: %s: cannot read the EuRoC sequence: %s\n", dir.c_str(),
                 !s ? s.message() : !c0 ? c0.status().message() : c1.status().message());
    return 1;
  }
  const int w = c0->model.width, h = c0->model.height;
  Result<vision::StereoRectification> rect =
      vision::stereo_rectify(c0->model, c1->model, tools::euroc_stereo_extrinsics(c0.value(), c1.value()), w, h);
  if (!rect) {
    std::fprintf(stderr, "vo: rectification failed: %s\n", rect.status().message());
    return 1;
  }
  vision::RemapConfig rc;
  rc.max_width = w;
  rc.max_height = h;
  ArenaStorage rect_arena(2 * vision::RemapTable::arena_bytes(rc));
  vision::RemapTable map_l, map_r;
  if (!map_l.init(rc, rect_arena) || !map_r.init(rc, rect_arena) ||
      !map_l.build(c0->model, rect->K, rect->R_left, vision::FlatPortRefraction{}, w, h) ||
      !map_r.build(c1->model, rect->K, rect->R_right, vision::FlatPortRefraction{}, w, h)) {
    std::fprintf(stderr, "vo: remap table failed\n");
    return 1;
  }
  const std::size_t n = std::min<std::size_t>(frames.size(), static_cast<std::size_t>(max_frames));
  const vo::VoConfig c = pipeline::euroc_vo_config(w, h, rect->K(0, 0), rect->K(0, 2), rect->K(1, 2), rect->baseline_m);
  SequenceRun run;
  auto load = [&](std::size_t i, ImageU8& l, ImageU8& r) {
    Result<ImageU8> a = tools::read_image_gray8(frames[i].left_path.c_str());
    Result<ImageU8> b = tools::read_image_gray8(frames[i].right_path.c_str());
    Result<ImageU8> la = Image<std::uint8_t>::allocate(w, h), ra = Image<std::uint8_t>::allocate(w, h);
    if (!a || !b || !la || !ra || !map_l.apply(a->view(), la->view()) || !map_r.apply(b->view(), ra->view())) {
      std::fprintf(stderr, "vo: cannot read/rectify frame %zu\n", i);
      return false;
    }
    l = std::move(la.value());
    r = std::move(ra.value());
    return true;
  };
  if (!run_sequence(c, n, load, pipeline::euroc_vo_prior(), true, run)) return 1;
  if (!write_poses(out, run.poses)) {
    std::fprintf(stderr, "vo: cannot write %s\n", out);
    return 1;
  }
  double max_disp = 0.0, max_rot = 0.0;
  for (const Pose3& p : run.poses) {
    max_disp = std::max(max_disp, p.t.norm());
    max_rot = std::max(max_rot, rotation_angle_rad(p.R));
  }
  const Pose3& end = run.poses.back();
  std::printf("euroc: %zu frames, step median %.2f ms, lost %zu, end drift %.4f m, max displacement %.4f m, max rotation "
              "%.3f deg, VO path %.4f m (ground truth for these frames: max displacement 1.9 mm, path 6.5 mm, "
              "max rotation 0.22 deg)\n",
              n, median(run.ms), run.lost, end.t.norm(), max_disp, rad_to_deg(max_rot), path_length(run.poses));
  return 0;
}

int run_vo() {
  if (!g_opt.kitti.empty() && !g_opt.euroc.empty()) {
    std::fprintf(stderr, "qnav vo: give --kitti DIR or --euroc DIR, not both\n");
    return 2;
  }
  if (!g_opt.kitti.empty()) return run_kitti();
  if (!g_opt.euroc.empty()) return run_euroc();
  std::fprintf(stderr, "qnav vo: give `eval`, --kitti DIR or --euroc DIR (qnav help vo; qnav help vo eval)\n");
  return 2;
}

void setup_vo(CLI::App& cmd, qnav::cli::Runner& run) {
  using qnav::cli::add_flag;
  using qnav::cli::add_number;
  using qnav::cli::add_text;
  cmd.require_subcommand(0, 1);
  cmd.footer("Runs: qnav vo eval [...] (synthetic Mars yard), or qnav vo --kitti DIR --out F, or qnav vo --euroc DIR --out F.");
  add_text(cmd, "--kitti", g_opt.kitti, "run a rectified KITTI-layout sequence (6D-VME, constant-velocity prior, no attitude sensor)")
      ->type_name("DIR");
  add_text(cmd, "--euroc", g_opt.euroc, "run raw EuRoC pairs (rectified with RemapTable, 6D-VME, zero-motion prior)")->type_name("DIR");
  add_text(cmd, "--calib", g_opt.calib, "KITTI calibration (default DIR/calib.txt)")->type_name("FILE");
  add_text(cmd, "--out", g_opt.out, "poses in the KITTI format, 3x4 per frame (required with --kitti / --euroc; folders created)")
      ->type_name("FILE");
  add_number(cmd, "--frames", g_opt.frames, "frames to run at most", "", 2, 1e9);
  add_text(cmd, "--peer", g_opt.peer, "KITTI: compare path and end point against this peer trajectory")->type_name("FILE");
  add_flag(cmd, "--weighted", g_opt.weighted, "KITTI: weighted 6D motion estimate (the preset is unweighted)");
  add_number(cmd, "--max-depth", g_opt.max_depth, "KITTI: farthest point used", "m", 0.1, 1e6)
      ->description("KITTI: farthest point used (m; default: the KITTI preset's, pipeline/vo_defaults; 0.1..1e6)");
  run.on(&cmd, run_vo);

  CLI::App* e = cmd.add_subcommand("eval", "synthetic evaluation with exact ground truth: a 27 m run (attitude drifting) and a 100 m run\n"
                                           "(attitude recalibrated every 2 m); one JSON object (--json) or a table");
  add_flag(*e, "--json", g_opt.json, "one JSON object on stdout");
  add_flag(*e, "--quick", g_opt.quick, "6 m and 10 m runs instead of 27 m and 100 m (the demo)");
  add_flag(*e, "--verbose", g_opt.knobs.verbose, "per-frame diagnostics");
  add_text(*e, "--noise", g_opt.noise, "the paper's noise model", {"small", "moderate", "none"});
  add_text(*e, "--configs", g_opt.configs, "main: 3D-fc-fast-att, 3D-fc-fast, 6D-fc-fast; att: the first; all: + full fc / fb",
           {"main", "att", "all"});
  add_number(*e, "--seed", g_opt.seed, "seed of the yard and the noise", "", 0, 2147483647);
  add_text(*e, "--seeds", g_opt.seeds, "run every seed, N,M,... or A-B (at most 100; the first is the primary)")->type_name("LIST");
  add_text(*e, "--traj-dir", g_opt.traj_dir, "write per-configuration CSVs (path_m, err_m) for scripts/vo_plot.py (created)")
      ->type_name("DIR");
  add_number(*e, "--length-27", g_opt.len27, "length of the drifting run", "m", 0.5, 1e5)
      ->description("length of the drifting run (m; default 27, 6 with --quick; > 0.5)");
  add_number(*e, "--length-100", g_opt.len100, "length of the recalibrated run", "m", 0.5, 1e5)
      ->description("length of the recalibrated run (m; default 100, 10 with --quick; > 0.5)");
  add_number(*e, "--calib-27", g_opt.calib27, "attitude recalibration interval on the drifting run (0: never)", "m", 0, 1e5);
  add_number(*e, "--nt", g_opt.nt, "translation noise n_t", "fraction", 0, 10)
      ->description("translation noise n_t (fraction of the step; default from --noise; 0..10)");
  add_number(*e, "--sigma-m-deg", g_opt.sigma_m_deg, "attitude noise sigma_m", "deg", 0, 90)
      ->description("attitude noise sigma_m (deg; default from --noise; 0..90)");
  add_number(*e, "--dsig", g_opt.knobs.dsig, "tuning: disparity sigma", "px", 0, 100);
  add_number(*e, "--nsig", g_opt.knobs.nsig, "tuning: gate in sigmas", "sigma", 0, 100);
  add_number(*e, "--app", g_opt.knobs.app, "tuning: appearance weight", "", -1e6, 1e6);
  add_number(*e, "--lat-px", g_opt.knobs.lat_px, "tuning: lateral sigma of stereo matching (<= 0: the default)", "px", -1, 1e4);
  add_number(*e, "--att-vo-scale", g_opt.knobs.att_vo_scale, "attitude filter: VO rotation sigma scale", "", 0, 1e6);
  add_number(*e, "--att-rate-scale", g_opt.knobs.att_rate_scale, "attitude filter: drift-rate process noise scale", "", 0, 1e6);
  add_flag(*e, "--att-no-step-rot", g_opt.att_no_step_rot, "attitude filter: do not use the visual step rotation");
  add_flag(*e, "--att-iso", g_opt.att_iso, "attitude filter: isotropic instead of anisotropic noise");
  add_flag(*e, "--att-filtered", g_opt.knobs.att_filtered, "attitude filter: feed the filtered attitude back");
  add_flag(*e, "--no-refine", g_opt.no_refine, "track refinement off");
  add_flag(*e, "--no-refine-disparity", g_opt.no_refine_disp, "disparity refinement off");
  add_number(*e, "--ref-lat-px", g_opt.knobs.ref_lat_px, "track refinement: lateral sigma (<= 0: the default)", "px", -1, 1e4);
  add_number(*e, "--track-radius", g_opt.knobs.track_radius, "track refinement: alignment search radius (0: the default)", "px", 0, 1e4);
  run.on(e, run_eval);
}

}  // namespace

QNAV_CLI_COMMAND("vo", "stereo visual odometry: synthetic Mars-yard evaluation, KITTI / EuRoC runs", setup_vo);
