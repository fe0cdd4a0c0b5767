// NavInputs: the vehicle's own sensors as the nav thread sees them.
// Consumes (ports in): CAN frames from [can_rx] (QNAV_ATTITUDE_IN, QNAV_DEPTH_IN, QNAV_MODE_CMD through
//   QnavCanReceiver; a DroneCAN AHRS Solution on 29-bit frames; the controller's error frames), DVL
//   samples from [dvl], the autopilot's MAVLink ATTITUDE (NavSource hands it over).
// Produces (ports out): the heading and body velocity in the DeadReckoner (the pose at any sample
//   time), the newest full attitude (for the VO and MAVLink), the DVL altitude, the depth, bus-off,
//   and a valid mode command returned from on_can() (NavWorker applies it).
// Every refusal is counted: by the receivers (format, range, stale ...) and here (dr_rejected: a
// sample the dead reckoner refused as out of order or non-finite).
// Memory: fixed members (receivers, dead reckoner); no heap. Time: O(1) per frame or sample.
#pragma once

#include <cstdint>

#include "drivers/dronecan/ahrs_receiver.hpp"
#include "drivers/dvl/dvl_types.hpp"
#include "drivers/qnavcan/receiver.hpp"
#include "firmware/pipeline/dead_reckoner.hpp"
#include "firmware/qnavd/components/component.hpp"
#include "hal/core/can.hpp"
#include "nav/core/geometry.hpp"

namespace qnav::daemon {

class NavInputs {
 public:
  explicit NavInputs(const NavContext& ctx) noexcept : ctx_(ctx) {}

  // A CAN frame. True with *cmd set when it was a valid QNAV_MODE_CMD.
  bool on_can(const hal::CanRxFrame& rx, drivers::qnavcan::ModeCmd* cmd) noexcept;
  // A DVL sample: the body velocity into the dead reckoning, its altitude kept (< 0: none).
  void on_dvl(const drivers::dvl::DvlVelocity& v) noexcept;
  // An attitude from another source (the autopilot's MAVLink ATTITUDE), yaw in [-pi, pi] or [0, 2 pi).
  void on_attitude(std::int64_t sample_ns, double roll_rad, double pitch_rad, double yaw_rad) noexcept;
  // The autopilot set a new navigation origin (QNAV_MODE_CMD ResetNav): distance and position restart.
  void reset_nav() noexcept { dr_.reset(); }

  const pipeline::DeadReckoner& dr() const noexcept { return dr_; }
  // The newest attitude (world NED <- body FRD), if it is at most attitude_stale_s older than t_ns.
  bool attitude_at(std::int64_t t_ns, Mat3d* world_R_body) const noexcept;
  bool has_attitude() const noexcept { return have_att_; }
  const Mat3d& attitude() const noexcept { return att_R_; }
  double dvl_altitude_m() const noexcept { return dvl_altitude_m_; }
  // The vehicle's depth sensor (QNAV_DEPTH_IN), if fresh at now_ns.
  bool depth_m(std::int64_t now_ns, double* depth) const noexcept;
  bool bus_off() const noexcept { return bus_off_; }

  const drivers::qnavcan::QnavCanReceiver& receiver() const noexcept { return receiver_; }
  std::uint64_t can_frames() const noexcept { return can_frames_; }
  std::uint64_t dvl_samples() const noexcept { return dvl_samples_; }
  std::uint32_t dr_rejected() const noexcept { return dr_rejected_; }
  // qnav CAN frames refused by the receiver (format, length, range, invalid, stale, error frames).
  std::uint32_t can_rejected() const noexcept {
    return receiver_.counters().total() - receiver_.counters().get(drivers::qnavcan::RxCounter::kUnknownId);
  }
  // Everything these inputs refused (HEALTH RejectedInputs): frames for other nodes are not refusals.
  std::uint64_t rejected() const noexcept;

 private:
  void set_attitude(std::int64_t sample_ns, const Mat3d& world_R_body) noexcept;

  const NavContext& ctx_;  // the worker's: its log is set in NavWorker::init
  drivers::qnavcan::QnavCanReceiver receiver_;
  drivers::dronecan::DroneCanAhrsReceiver ahrs_;
  pipeline::DeadReckoner dr_;
  bool have_att_ = false;
  std::int64_t att_ns_ = 0;
  Mat3d att_R_ = Mat3d::Identity();
  double dvl_altitude_m_ = -1.0;
  bool bus_off_ = false;
  std::uint64_t can_frames_ = 0, dvl_samples_ = 0;
  std::uint32_t dr_rejected_ = 0;
};

}  // namespace qnav::daemon
