// SimRover: the rover of a simulated `vo` pass (qnavd's sim backend): it drives the Mars-yard
// trajectory (drivers/stereo_sim MarsYardTrajectory, the scene `qnav vo eval` measures on), renders
// the stereo bench's pair at every step (render_stereo) and measures the left camera's attitude with
// the Mars paper's sensor model (NoiseModel::small(): white noise, bias, drift), which the sim AHRS
// sends as the body's roll, pitch and heading, and its wheel odometry (10 % scale error), which the sim
// sends as DVL velocities. The trajectory runs at kSpeedMps (steps of 0.15-0.25 m).
// Frames: the simulator's world (x, y, z up) and rover (x forward, y left, z up) become NED and FRD
// by flipping y and z (S = diag(1, -1, -1)), as a vehicle's AHRS reports them; the truth pose it
// reports is the body's in NED, relative to where the pass started.
// Memory: the terrain and noise model are values; next() and render() allocate nothing.
#pragma once

#include <cstdint>

#include "drivers/stereo_sim/mars_yard.hpp"
#include "drivers/stereo_sim/noise_model.hpp"
#include "nav/core/geometry.hpp"
#include "nav/core/image.hpp"
#include "nav/core/status.hpp"

namespace qnav::daemon {

struct RoverSample {
  std::int64_t t_ns = 0;
  double roll_rad = 0.0, pitch_rad = 0.0, heading_rad = 0.0;  // measured body attitude (NED/FRD)
  Pose3 truth_world_T_body;                                    // NED, from the start of the pass
  double path_m = 0.0;
  std::uint32_t index = 0;
  // Wheel odometry since the previous sample, in the previous body frame (forward, right), with the
  // noise model's scale error (n_t = 10 %, as `qnav vo eval`); the sim sends it as DVL velocities.
  double odo_forward_m = 0.0, odo_right_m = 0.0, dt_s = 0.0;
};

class SimRover {
 public:
  static constexpr double kSpeedMps = 0.4;  // a pair every ~0.5 s of mission time (the DVL stays fresh: dvl.stale_s)

  // The pass's scene and noise from `seed`; the first pair at t0_ns; `length_m` of path.
  void start(std::uint64_t seed, double length_m, std::int64_t t0_ns) noexcept;
  // The next step; false when the pass's length is driven.
  bool next(RoverSample& out) noexcept;
  // The current step's stereo pair into left and right (the bench's size, 320 x 256).
  Status render(ImageViewU8 left, ImageViewU8 right) const noexcept;
  const sim::StereoBench& bench() const noexcept { return bench_; }

 private:
  sim::MarsYardTerrain terrain_{sim::MarsYardConfig{}};
  sim::StereoBench bench_;
  sim::MarsYardTrajectory traj_{sim::TrajectoryConfig{}};
  sim::NoiseModel noise_{sim::NoiseConfig::small(), 0};
  std::uint64_t seed_ = 0;
  double length_m_ = 0.0;
  std::int64_t t0_ns_ = 0;
  Pose3 start_world_T_rover_;
  Pose3 prev_world_T_rover_;
  double prev_time_s_ = 0.0;
  Pose3 world_T_left_;
  std::uint32_t index_ = 0;
  bool first_ = true;
};

}  // namespace qnav::daemon
