// The tuned stereo VO settings, defined once (moved here from commands/vo.cpp and tools/): the VO
// configuration that matches a simulated stereo bench (drivers/stereo_sim: image size, camera
// intrinsics, baseline, the disparity range of the Mars-yard terrain), the main configuration `qnav vo
// eval` measures (docs/vo.md: 3D-VME, fc matching with fast batches, attitude drift filter, 300 corners)
// and the attitude filter's sensor model. qnavd's [vo] keys start from default_vo_config and
// `qnav vo`, bench_vo, the timing stages and the VO tests use the same functions.
#pragma once

#include <algorithm>
#include <cmath>

#include "drivers/stereo_sim/mars_yard.hpp"
#include "drivers/stereo_sim/noise_model.hpp"
#include "firmware/pipeline/vo_prior.hpp"
#include "nav/vo/stereo_vo.hpp"

namespace qnav::pipeline {

// A VO configuration for a rectified pair of this size and calibration (the rest at VoConfig's defaults).
inline vo::VoConfig vo_config_for_camera(int width, int height, double focal_px, double cu_px, double cv_px, double baseline_m) {
  vo::VoConfig c;
  c.max_width = width;
  c.max_height = height;
  c.camera.focal_px = focal_px;
  c.camera.cu_px = cu_px;
  c.camera.cv_px = cv_px;
  c.camera.baseline_m = baseline_m;
  return c;
}

inline vo::VoConfig vo_config_for_bench(const sim::StereoBench& b) {
  vo::VoConfig c = vo_config_for_camera(b.width(), b.height(), b.focal_px(), b.cu_px(), b.cv_px(), b.baseline_m);
  c.stereo.min_disparity_px = 8;  // terrain at 0.55 .. 1.4 m: d = f b / Z = 12 .. 30 px
  c.stereo.max_disparity_px = 36;
  c.stereo.disparity_sigma_px = 0.15f;
  return c;
}

// Ratio of the true to the predicted (Gauss-Newton, chi2-scaled) rotation sigma of the anisotropic 6D
// step on the Mars yard with refined tracks: rms of (error / predicted sigma) per axis over seeds 3-7,
// 27 m runs (`qnav vo eval --configs att --seed S --length-100 1 --verbose`): 0.49-0.53, mean 0.51
// (0.72 before the track refinement).
constexpr double kVoRotationSigmaScale = 0.51;

// The attitude filter's sensor model from the simulated sensor's noise model (its "datasheet"):
// white noise sigma_m; the drift grows every stability period T_s by the bias (sigma_b, redrawn every
// T_b) plus a random walk (sigma_s per T_s). As continuous densities: drift rate sigma sigma_b / T_s,
// rate walk sqrt(sigma_s^2 / T_s^3 + sigma_b^2 / (T_s^2 T_b)), drift walk (the per-period steps)
// sqrt((sigma_b^2 + sigma_s^2) / T_s). Floors keep it valid for the noise-free preset.
// (Defaults of motion::AttitudeBiasConfig are this function of NoiseConfig::small().)
inline motion::AttitudeBiasConfig attitude_bias_config_for_noise(const sim::NoiseConfig& n) {
  motion::AttitudeBiasConfig c;
  const double floor = deg_to_rad(0.001);
  const double ts = n.stability_period_s, tb = n.bias_period_s;
  const double sb = std::max(n.sigma_b_rad, floor), ss = std::max(n.sigma_s_rad, floor);
  c.sensor_sigma_rad = std::max(n.sigma_m_rad, floor);
  c.initial_drift_sigma_rad = sb;
  c.initial_rate_sigma_rad_s = sb / ts;
  c.rate_walk_rad_s_sqrt_s = std::sqrt(ss * ss / (ts * ts * ts) + sb * sb / (ts * ts * tb));
  c.drift_walk_rad_sqrt_s = std::sqrt((sb * sb + ss * ss) / ts);
  // 5 sigma of the rate after one bias period (bias plus T_b / T_s walk steps).
  c.max_drift_rate_rad_s = 5.0 * std::sqrt(sb * sb + (tb / ts) * ss * ss) / ts;
  return c;
}

// The main configuration (`qnav vo eval`'s "3D-fc-fast-att", the daemon's default): 3D-VME with the
// attitude drift filter, fc matching in fast batches, at most 300 corners, steps up to 0.6 m, for an
// attitude sensor with the noise model `noise` (its datasheet; the eval's default is small()).
inline vo::VoConfig default_vo_config(const sim::StereoBench& b, const sim::NoiseConfig& noise = sim::NoiseConfig::small()) {
  vo::VoConfig c = vo_config_for_bench(b);
  c.max_corners = 300;
  c.max_step_m = 0.6;
  c.mode = vo::VmeMode::k3D;
  c.match.score = match::MatchScoreKind::kContinuous;
  c.match.fast = true;
  c.match.attitude_sigma_rad = 1.5 * noise.sigma_m_rad + deg_to_rad(0.02);
  c.estimate_attitude_bias = true;
  c.attitude_bias = attitude_bias_config_for_noise(noise);
  c.attitude_bias.vo_sigma_scale = kVoRotationSigmaScale;
  return c;
}


// A car's rectified stereo pair without an attitude sensor (KITTI layout: 1242 x 375, 0.54 m baseline,
// depths to 40 m): 6D-VME with a constant-velocity prior, wide gates. The settings `qnav vo --kitti`
// measured against libviso2 (docs/vo.md).
inline vo::VoConfig kitti_vo_config(int width, int height, double focal_px, double cu_px, double cv_px, double baseline_m) {
  vo::VoConfig c = vo_config_for_camera(width, height, focal_px, cu_px, cv_px, baseline_m);
  c.max_corners = 400;
  c.stereo.min_disparity_px = 2;
  c.stereo.max_disparity_px = 120;
  c.max_depth_m = 40.0;
  c.mode = vo::VmeMode::k6D;
  c.lateral_sigma_px = 0.7;
  c.match.attitude_sigma_rad = deg_to_rad(0.7);
  c.match.max_gate_m = 3.0;
  c.match.max_candidates_per_landmark = 16;
  c.match.eps_n_floor_m = 0.05;
  c.match.fast = true;
  c.match.batch_size = 80;
  c.match.min_matches = 40;
  c.irls_config.huber_m = 0.1;
  c.irls_config.inlier_m = 0.3;
  // Unweighted (eq. 8 as printed): 1/sigma^2 weights let the near road points dominate, and their
  // stereo errors pitch the trajectory (measured: 15.5 m end-point difference weighted vs 2.45 m
  // unweighted against libviso2 over the 100 frames).
  c.weighted = false;
  c.max_rms_residual_m = 0.5;
  c.max_step_m = 4.0;
  return c;
}
// The car's translation prior: constant velocity; before the first visual step zero motion within 1 m.
inline VoPriorConfig kitti_vo_prior() {
  VoPriorConfig p;
  p.first_sigma_m = 1.0;
  return p;
}

// A hand-held / drone stereo rig indoors without an attitude sensor (EuRoC: 752 x 480 rectified by
// nav/vision, 0.11 m baseline, depths to 8 m): 6D-VME with a zero-motion prior. What `qnav vo --euroc`
// measures against the motion-capture ground truth (docs/vo.md).
inline vo::VoConfig euroc_vo_config(int width, int height, double focal_px, double cu_px, double cv_px, double baseline_m) {
  vo::VoConfig c = vo_config_for_camera(width, height, focal_px, cu_px, cv_px, baseline_m);
  c.max_corners = 300;
  c.stereo.min_disparity_px = 1;
  c.stereo.max_disparity_px = 80;
  c.max_depth_m = 8.0;
  c.mode = vo::VmeMode::k6D;
  c.match.attitude_sigma_rad = deg_to_rad(0.3);
  c.match.fast = true;
  c.irls_config.huber_m = 0.02;
  c.irls_config.inlier_m = 0.06;
  c.max_rms_residual_m = 0.1;
  return c;
}
// The hovering rig's prior: zero motion within 2 cm.
inline VoPriorConfig euroc_vo_prior() {
  VoPriorConfig p;
  p.zero_motion = true;
  p.first_sigma_m = 0.02;
  return p;
}

}  // namespace qnav::pipeline
