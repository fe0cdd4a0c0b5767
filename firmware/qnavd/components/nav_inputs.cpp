#include "firmware/qnavd/components/nav_inputs.hpp"

#include <cmath>

namespace qnav::daemon {

namespace qc = drivers::qnavcan;

void NavInputs::set_attitude(std::int64_t sample_ns, const Mat3d& world_R_body) noexcept {
  att_R_ = world_R_body;
  att_ns_ = sample_ns;
  have_att_ = true;
}

bool NavInputs::on_can(const hal::CanRxFrame& rx, qc::ModeCmd* cmd) noexcept {
  ++can_frames_;
  if (rx.frame.extended && !rx.frame.error) {
    // DroneCAN (29-bit): an AHRS Solution's orientation quaternion (NED) gives the compass heading.
    if (ahrs_.on_frame(rx) == drivers::dronecan::AhrsUpdate::kSolution) {
      const float* q = ahrs_.solution().value.orientation_xyzw;
      const double x = static_cast<double>(q[0]), y = static_cast<double>(q[1]), z = static_cast<double>(q[2]), w = static_cast<double>(q[3]);
      double yaw = std::atan2(2.0 * (w * z + x * y), w * w + x * x - y * y - z * z);  // exact for a quaternion of any norm
      if (yaw < 0.0) yaw += 2.0 * kPi;
      if (!dr_.on_heading(ahrs_.solution().stamp.sample_ns, yaw)) ++dr_rejected_;
      const double n = std::sqrt(x * x + y * y + z * z + w * w);
      if (std::isfinite(n) && n > 0.5 && n < 2.0)  // the full attitude, for the visual odometry
        set_attitude(ahrs_.solution().stamp.sample_ns, Eigen::Quaterniond(w / n, x / n, y / n, z / n).toRotationMatrix());
    }
    return false;  // rejections counted by the AHRS receiver
  }
  if (rx.frame.error) {  // the controller's own report: bus-off until it says it restarted
    if (rx.frame.id & hal::can_error::kBusOff) bus_off_ = true;
    if (rx.frame.id & hal::can_error::kRestarted) bus_off_ = false;
  }
  if (!receiver_.on_frame(rx)) return false;  // counted by the receiver
  if (rx.frame.id == qc::kIdAttitudeIn) {
    qc::Stamped<qc::AttitudeIn> a;
    if (receiver_.latest_attitude(rx.stamp.sample_ns, INT64_MAX / 2, a)) {
      if (!dr_.on_heading(a.stamp.sample_ns, a.value.heading_rad)) ++dr_rejected_;
      set_attitude(a.stamp.sample_ns, rotation_from_rpy(a.value.roll_rad, a.value.pitch_rad, a.value.heading_rad));
    }
  } else if (rx.frame.id == qc::kIdModeCmd) {
    *cmd = receiver_.last_mode().value;
    return true;
  }
  return false;
}

void NavInputs::on_dvl(const drivers::dvl::DvlVelocity& v) noexcept {
  ++dvl_samples_;
  if (!dr_.on_velocity(v.stamp.sample_ns, v.vx_mps, v.vy_mps, 10.0, ctx_.cfg->dvl_stale_s)) ++dr_rejected_;
  dvl_altitude_m_ = std::isfinite(v.altitude_m) ? v.altitude_m : -1.0;
}

void NavInputs::on_attitude(std::int64_t sample_ns, double roll_rad, double pitch_rad, double yaw_rad) noexcept {
  double yaw = yaw_rad;
  if (yaw < 0.0) yaw += 2.0 * kPi;
  if (!dr_.on_heading(sample_ns, yaw)) ++dr_rejected_;
  set_attitude(sample_ns, rotation_from_rpy(roll_rad, pitch_rad, yaw));
}

bool NavInputs::attitude_at(std::int64_t t_ns, Mat3d* world_R_body) const noexcept {
  if (!have_att_ || t_ns - att_ns_ > static_cast<std::int64_t>(ctx_.cfg->attitude_stale_s * 1e9)) return false;
  *world_R_body = att_R_;
  return true;
}

bool NavInputs::depth_m(std::int64_t now_ns, double* depth) const noexcept {
  qc::Stamped<qc::DepthIn> d;
  if (!receiver_.latest_depth(now_ns, static_cast<std::int64_t>(ctx_.cfg->depth_stale_s * 1e9), d) || !d.value.depth_valid) return false;
  *depth = d.value.depth_m;
  return true;
}

std::uint64_t NavInputs::rejected() const noexcept {
  std::uint64_t n = 0;
  for (std::size_t i = 0; i < static_cast<std::size_t>(qc::RxCounter::kCount); ++i)
    if (static_cast<qc::RxCounter>(i) != qc::RxCounter::kUnknownId) n += receiver_.counters().get(static_cast<qc::RxCounter>(i));
  n += ahrs_.counters().total() - ahrs_.counters().get(drivers::dronecan::AhrsCounter::kOtherNode);
  return n + dr_rejected_;
}

}  // namespace qnav::daemon
