#include "firmware/qnavd/sim_sensors.hpp"

#include <cerrno>
#include <cmath>
#include <cstring>

#include "drivers/dronecan/ahrs.hpp"
#include "drivers/dronecan/transfer.hpp"
#include "drivers/dvl/wl_parser.hpp"
#include "drivers/qnavcan/messages.hpp"
#include "hal/core/candump.hpp"

namespace qnav::daemon {

SimSensors::~SimSensors() {
  if (candump_) std::fclose(candump_);
}

Status SimSensors::init(hal::CanBus& bus, hal::SerialPort& dvl) {
  if (!cfg_.sim_candump.empty()) {
    candump_ = std::fopen(cfg_.sim_candump.c_str(), "w");
    if (!candump_) {
      std::fprintf(stderr, "qnavd: sim.candump %s: %s\n", cfg_.sim_candump.c_str(), std::strerror(errno));
      return Status(StatusCode::kIoError, "sim: cannot write sim.candump (see the line above)");
    }
  }
  bus_ = &bus;
  dvl_ = &dvl;
  return Status::ok();
}

bool SimSensors::stalled(const char* sensor, std::int64_t t_ns) const noexcept {
  if (cfg_.sim_stall != sensor || static_cast<int>(pass_) != cfg_.sim_stall_pass) return false;
  const double since_s = static_cast<double>(t_ns - pass_start_ns_) * 1e-9;
  return since_s >= cfg_.sim_stall_start_s && since_s < cfg_.sim_stall_start_s + cfg_.sim_stall_s;
}

bool SimSensors::faulty(const char* kind, std::int64_t t_ns) const noexcept {
  if (cfg_.sim_fault != kind || static_cast<int>(pass_) != cfg_.sim_fault_pass || !flying_) return false;
  const double since_s = static_cast<double>(t_ns - pass_start_ns_) * 1e-9;
  return since_s >= cfg_.sim_fault_start_s && since_s < cfg_.sim_fault_start_s + cfg_.sim_fault_s;
}

void SimSensors::inject_bus_faults(std::int64_t t) noexcept {
  const std::uint8_t data[8] = {};
  if (net_ != nullptr && faulty("can_error_frames", t)) {
    net_->inject_error(hal::can_error::kProtocol | hal::can_error::kBusError, data);
    count_fault();
  }
  if (net_ != nullptr && cfg_.sim_fault == "can_bus_off") {
    const bool off = faulty("can_bus_off", t);
    if (off && !bus_off_) {
      net_->inject_error(hal::can_error::kBusOff, data);
      count_fault();
    } else if (!off && bus_off_) {
      net_->inject_error(hal::can_error::kRestarted, data);
    }
    bus_off_ = off;
  }
  if (leak_line_ != nullptr && cfg_.sim_fault == "leak") {  // water at the detector for the window
    const bool wet = faulty("leak", t);
    if (wet != wet_) {
      leak_line_->inject_level(wet, t);
      if (wet) count_fault();
      wet_ = wet;
    }
  }
  if (store_ != nullptr && cfg_.sim_fault == "disk_full") {
    const bool full = faulty("disk_full", t);
    if (full && !store_->full()) count_fault();
    store_->set_full(full);
  }
}

void SimSensors::record(const hal::CanFrame& f, std::int64_t t_ns) noexcept {
  if (!candump_) return;
  hal::CanLogRecord r;
  r.frame = f;
  r.has_time = true;
  r.time_us = t_ns / 1000;
  // The interface the frames are on (sim.can_interface; names are at most 15 characters), else vcan0.
  const char* name = cfg_.sim_can_interface.empty() ? "vcan0" : cfg_.sim_can_interface.c_str();
  std::strncpy(r.interface, name, sizeof r.interface - 1);
  char line[hal::kMaxCanLogLine];
  if (hal::format_can_log_line(r, line, sizeof line) > 0) std::fprintf(candump_, "%s\n", line);
}

void SimSensors::send_attitude(double heading_rad, double roll_rad, double pitch_rad) noexcept {
  namespace qc = drivers::qnavcan;
  last_heading_ = heading_rad;
  if (no_ahrs_) return;
  const std::int64_t now = clock_.now_ns();
  if (stalled("attitude", now) || now == last_att_ns_) return;  // one AHRS sample per instant
  last_att_ns_ = now;
  const qc::AttitudeIn a = qc::attitude_from_heading(heading_rad, roll_rad, pitch_rad, att_counter_++);
  if (cfg_.sim_ahrs == "dronecan") {
    // uavcan.equipment.ahrs.Solution from node 42: yaw about NED down as a quaternion.
    namespace dc = drivers::dronecan;
    dc::AhrsSolution sol;
    sol.timestamp_us = static_cast<std::uint64_t>(now / 1000);
    const Eigen::Quaterniond q(rotation_from_rpy(roll_rad, pitch_rad, a.heading_rad));
    sol.orientation_xyzw[0] = static_cast<float>(q.x());
    sol.orientation_xyzw[1] = static_cast<float>(q.y());
    sol.orientation_xyzw[2] = static_cast<float>(q.z());
    sol.orientation_xyzw[3] = static_cast<float>(q.w());
    sol.linear_accel_mps2[2] = -9.81f;
    std::uint8_t payload[dc::kSolutionMaxBytes];
    const std::size_t n = dc::encode_solution(sol, true, payload, sizeof payload);
    hal::CanFrame frames[16];
    const std::size_t k = dc::split_transfer(dc::kSolutionSignature, dc::make_message_id(16, dc::kSolutionId, 42), a.counter, payload, n,
                                             frames, 16);
    for (std::size_t j = 0; j < k; ++j)
      if (bus_->send(frames[j])) record(frames[j], now);
    return;
  }
  hal::CanFrame f;
  if (!qc::encode(a, f)) return;
  if (faulty("attitude_out_of_range", now)) {
    f.data[4] = 0xFF;  // Heading (bits 32..47): 6.5535 rad, beyond the DBC's [0, 6.2832]
    f.data[5] = 0xFF;
    count_fault();
  }
  if (bus_->send(f)) record(f, clock_.now_ns());
  if (faulty("attitude_duplicate", now) && bus_->send(f)) {  // the same frame again (same counter)
    record(f, clock_.now_ns());
    count_fault();
  }
}

void SimSensors::send_dvl(double fwd, double stbd, std::int64_t t_ns) noexcept {
  if (stalled("dvl", t_ns)) return;
  long long tov = t_ns / 1000;
  if (tov <= last_tov_us_) tov = last_tov_us_ + 1;
  last_tov_us_ = tov;
  const bool nan = faulty("dvl_nan", t_ns), back = faulty("dvl_time_back", t_ns);
  const long long stamp = back ? tov - 5000000 : tov;  // 5 s in the past
  char line[240];
  const std::size_t n = drivers::dvl::wl_velocity_report(nan ? std::nan("") : fwd, stbd, 0.0, dvl_altitude_m_, stamp, stamp, line, sizeof line);
  if (faulty("dvl_line_noise", t_ns)) {
    // A burst of line noise ending in a line break: a line of its own, before the real sentence.
    std::uint8_t noise[24];
    for (std::uint8_t& b : noise) {
      noise_seed_ = noise_seed_ * 1103515245u + 12345u;
      b = static_cast<std::uint8_t>(0x20 + (noise_seed_ >> 16) % 0x5F);
    }
    noise[sizeof noise - 1] = '\n';
    static_cast<void>(dvl_->write(Span<const std::uint8_t>(noise, sizeof noise)));
    count_fault();
  }
  static_cast<void>(dvl_->write(Span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(line), n)));
  if (nan || back) count_fault();
  if (faulty("dvl_duplicate", t_ns)) {
    static_cast<void>(dvl_->write(Span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(line), n)));
    count_fault();
  }
}

void SimSensors::replay_can(const hal::CanFrame& f, std::int64_t t) noexcept {
  if (f.error && net_ != nullptr) {
    std::uint8_t data[8] = {};
    std::memcpy(data, f.data, 8);
    net_->inject_error(f.id, data);
  } else if (!stalled("attitude", t) && bus_->send(f)) {
    record(f, t);
  }
}

void SimSensors::replay_dvl(const char* text, std::size_t length, std::int64_t t) noexcept {
  if (!stalled("dvl", t)) static_cast<void>(dvl_->write(Span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(text), length)));
}

}  // namespace qnav::daemon
