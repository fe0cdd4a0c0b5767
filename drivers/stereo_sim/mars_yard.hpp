// Synthetic Mars-yard stereo scene with exact ground truth, for evaluating the stereo visual odometry.
//
// MarsYardTerrain: procedural heightfield + albedo, defined everywhere (no storage): gentle undulations
// (2 m / 0.5 m wavelengths), sand grains (value noise down to 8 mm wavelength, which a 320x256 pixel
// of ~3 mm still resolves) and rocks (one per 0.25 m cell with probability rock_probability, radius
// 2-7 cm, smooth bump h = H (1 - r^2/R^2)^2 with slope < 0.8 so ray casting converges). Lambertian
// shading under a configurable sun. Deterministic from the seed.
//
// StereoBench: the paper's bench (800 mm high, 70 deg down, f 8 mm, baseline 50 mm, 1280x1024 sensor of
// 6 um cells subsampled by 4 -> 320x256, rectilinear rig). Camera frame x right, y down, z forward;
// rover frame x forward, y left, z up; world frame z up. The right camera is at +baseline along x.
//
// render_stereo(): ray casting of both cameras (fixed-point intersection with the heightfield,
// kRayIterations iterations, each ray's point on the terrain is exact to < 0.1 mm for slopes < 0.8),
// then 8-bit quantisation with Gaussian sensor noise. Cost O(W*H*kRayIterations) noise evaluations per
// image (~30 ms per 320x256 pair on the dev host); no heap.
//
// MarsYardTrajectory: rectilinear rover path (the paper builds long runs by integrating steps along a
// straight line): steps of 150-250 mm, heading wander around the path direction, roll/pitch of the rover
// on rough ground, 0.02 m/s (one 200 mm step = 10 s of sensor time).
#pragma once

#include <cstdint>

#include "drivers/stereo_sim/noise_model.hpp"
#include "nav/core/geometry.hpp"
#include "nav/core/image.hpp"
#include "nav/core/status.hpp"

namespace qnav::sim {

struct MarsYardConfig {
  std::uint64_t seed = 7;
  double undulation_amplitude_m = 0.03;
  double grain_amplitude_m = 0.0015;
  double rock_cell_m = 0.25;
  double rock_probability = 0.35;
  double rock_radius_min_m = 0.02;
  double rock_radius_max_m = 0.07;
  Vec3d sun_direction = Vec3d(0.4, 0.3, 0.866);  // towards the sun, world frame
  double ambient = 0.35;
};

class MarsYardTerrain {
 public:
  explicit MarsYardTerrain(const MarsYardConfig& config = MarsYardConfig{}) noexcept : config_(config) {}
  double height_m(double x_m, double y_m) const noexcept;
  double albedo(double x_m, double y_m) const noexcept;  // 0..1
  Vec3d normal(double x_m, double y_m) const noexcept;
  double radiance(double x_m, double y_m) const noexcept;  // albedo * shading, 0..1
  const MarsYardConfig& config() const noexcept { return config_; }

 private:
  double rock_height_m(double x_m, double y_m, double* rock_albedo) const noexcept;
  MarsYardConfig config_;
};

struct StereoBench {
  double height_m = 0.8;
  double tilt_down_rad = deg_to_rad(70.0);
  double focal_mm = 8.0;
  double baseline_m = 0.05;
  double cell_um = 6.0;
  int sensor_width = 1280;
  int sensor_height = 1024;
  int subsample = 4;
  double sensor_noise_dn = 1.5;

  int width() const noexcept { return sensor_width / subsample; }
  int height() const noexcept { return sensor_height / subsample; }
  double focal_px() const noexcept { return focal_mm * 1000.0 / (cell_um * subsample); }
  double cu_px() const noexcept { return 0.5 * width() - 0.5; }
  double cv_px() const noexcept { return 0.5 * height() - 0.5; }
  // Pose of the left camera in the rover frame.
  Pose3 rover_T_left() const noexcept;
};

constexpr int kRayIterations = 10;

// Renders the left and right images for the left camera pose world_T_left. Images must be
// bench.width() x bench.height(). frame_seed varies the sensor noise. Errors: kInvalidArgument.
Status render_stereo(const MarsYardTerrain& terrain, const StereoBench& bench, const Pose3& world_T_left,
                     std::uint64_t frame_seed, ImageViewU8 left, ImageViewU8 right) noexcept;

// Terrain point seen by pixel (u, v) of a camera at world_T_cam (for tests); false if the ray misses.
bool cast_ray(const MarsYardTerrain& terrain, const StereoBench& bench, const Pose3& world_T_cam, double u_px,
              double v_px, Vec3d& world_point) noexcept;

struct TrajectoryConfig {
  std::uint64_t seed = 11;
  double step_min_m = 0.15;
  double step_max_m = 0.25;
  double speed_m_s = 0.02;
  double heading_wander_rad = deg_to_rad(2.0);  // per-step heading noise (mean-reverting to the path)
  double roll_pitch_rad = deg_to_rad(1.5);      // rover attitude on rough ground, per step
};

struct RoverSample {
  Pose3 world_T_rover;
  double time_s = 0.0;
  double path_m = 0.0;
};

class MarsYardTrajectory {
 public:
  explicit MarsYardTrajectory(const TrajectoryConfig& config = TrajectoryConfig{}) noexcept;
  const RoverSample& current() const noexcept { return cur_; }
  const RoverSample& next() noexcept;  // advances one step

 private:
  TrajectoryConfig config_;
  Pcg32 rng_;
  RoverSample cur_;
  double heading_rad_ = 0.0;
  double x_m_ = 0.0, y_m_ = 0.0;
};

}  // namespace qnav::sim
