#include "firmware/qnavd/sim_rover.hpp"

#include <cmath>

namespace qnav::daemon {

namespace {
// Simulator world / rover axes (z up, y left) <-> NED / FRD (z down, y right).
const Mat3d kFlip = Vec3d(1.0, -1.0, -1.0).asDiagonal();
}  // namespace

void SimRover::start(std::uint64_t seed, double length_m, std::int64_t t0_ns) noexcept {
  sim::MarsYardConfig yard;
  yard.seed = seed;
  terrain_ = sim::MarsYardTerrain(yard);
  sim::TrajectoryConfig tc;
  tc.seed = seed + 1;
  tc.speed_m_s = kSpeedMps;
  traj_ = sim::MarsYardTrajectory(tc);
  noise_ = sim::NoiseModel(sim::NoiseConfig::small(), seed + 2);
  seed_ = seed;
  length_m_ = length_m;
  t0_ns_ = t0_ns;
  start_world_T_rover_ = prev_world_T_rover_ = traj_.current().world_T_rover;
  prev_time_s_ = traj_.current().time_s;
  index_ = 0;
  first_ = true;
}

bool SimRover::next(RoverSample& out) noexcept {
  const sim::RoverSample& s = first_ ? traj_.current() : traj_.next();
  first_ = false;
  if (s.path_m > length_m_ + 1e-9) return false;
  world_T_left_ = s.world_T_rover.compose(bench_.rover_T_left());
  noise_.advance_to(s.time_s);
  // The sensor measures the camera's attitude (as in `qnav vo eval`); the AHRS reports the body's.
  const Mat3d meas_cam = noise_.measure_attitude(world_T_left_.R);
  const Mat3d meas_rover = meas_cam * bench_.rover_T_left().R.transpose();
  const Mat3d R_ned_frd = kFlip * meas_rover * kFlip;
  out.heading_rad = std::atan2(R_ned_frd(1, 0), R_ned_frd(0, 0));
  out.pitch_rad = std::asin(std::fmax(-1.0, std::fmin(1.0, -R_ned_frd(2, 0))));
  out.roll_rad = std::atan2(R_ned_frd(2, 1), R_ned_frd(2, 2));
  // Truth in NED from the start position, with the world's axes (not the start heading's).
  out.truth_world_T_body.R = kFlip * s.world_T_rover.R * kFlip;
  out.truth_world_T_body.t = kFlip * (s.world_T_rover.t - start_world_T_rover_.t);
  out.path_m = s.path_m;
  const Vec3d odo = noise_.measure_translation(prev_world_T_rover_.R.transpose() * (s.world_T_rover.t - prev_world_T_rover_.t));
  out.odo_forward_m = odo.x();
  out.odo_right_m = -odo.y();
  out.dt_s = s.time_s - prev_time_s_;
  prev_world_T_rover_ = s.world_T_rover;
  prev_time_s_ = s.time_s;
  out.t_ns = t0_ns_ + static_cast<std::int64_t>(std::llround(s.time_s * 1e9));
  out.index = index_++;
  return true;
}

Status SimRover::render(ImageViewU8 left, ImageViewU8 right) const noexcept {
  return sim::render_stereo(terrain_, bench_, world_T_left_, seed_ * 100000 + index_, left, right);
}

}  // namespace qnav::daemon
