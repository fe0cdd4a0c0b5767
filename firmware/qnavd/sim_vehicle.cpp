#include "firmware/qnavd/sim_vehicle.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "drivers/dronecan/ahrs.hpp"
#include "drivers/dronecan/transfer.hpp"
#include "drivers/dvl/wl_parser.hpp"
#include "hal/core/candump.hpp"
#include "nav/core/geometry.hpp"

namespace qnav::daemon {

namespace qc = drivers::qnavcan;

namespace {
constexpr std::int64_t kIdleTickNs = 100000000;      // the AHRS streams between passes (10 Hz)
constexpr std::int64_t kStateTimeoutNs = 5000000000;  // 5 s of mission time for NAV_STATUS to confirm
constexpr double kTwoPi = 6.283185307179586;
}  // namespace

SimVehicle::~SimVehicle() {
  if (candump_) std::fclose(candump_);
}

bool SimVehicle::stalled(const char* sensor, std::int64_t t_ns) const noexcept {
  if (cfg_.sim_stall != sensor || static_cast<int>(pass_) != cfg_.sim_stall_pass) return false;
  const double since_s = static_cast<double>(t_ns - pass_start_ns_) * 1e-9;
  return since_s >= cfg_.sim_stall_start_s && since_s < cfg_.sim_stall_start_s + cfg_.sim_stall_s;
}

void SimVehicle::record(const hal::CanFrame& f, std::int64_t t_ns) noexcept {
  if (!candump_) return;
  hal::CanLogRecord r;
  r.frame = f;
  r.has_time = true;
  r.time_us = t_ns / 1000;
  std::memcpy(r.interface, "vcan0", 6);
  char line[hal::kMaxCanLogLine];
  if (hal::format_can_log_line(r, line, sizeof line) > 0) std::fprintf(candump_, "%s\n", line);
}

Status SimVehicle::init(hal::SimCanBus& autopilot, hal::SerialPort& dvl_out) {
  if (!cfg_.sim_candump.empty()) {
    candump_ = std::fopen(cfg_.sim_candump.c_str(), "w");
    if (!candump_) return Status(StatusCode::kIoError, "sim: cannot write sim.candump");
  }
  bus_ = &autopilot;
  dvl_ = &dvl_out;
  survey_ = std::make_unique<pipeline::SimSurvey>();
  QNAV_RETURN_IF_ERROR(survey_->init(cfg_.sim_length_m, cfg_.sim_seed));
  sonar_ = std::make_unique<sidescan::SideScanSimulator>();
  QNAV_RETURN_IF_ERROR(sonar_->init(survey_->sonar, &survey_->seabed));  // sized here; each pass re-seeds it without allocating
  if (cfg_.sim_mission.size() == 0) return Status(StatusCode::kInvalidArgument, "sim: the mission has no [[sim.pass]]");
  phase_ = Phase::kCommand;
  wall_start_ns_ = wall_.now_ns();
  sim_start_ns_ = clock_.now_ns();
  next_idle_att_ns_ = clock_.now_ns();
  return Status::ok();
}

void SimVehicle::drain_bus() noexcept {
  hal::CanRxFrame rx;
  while (bus_->receive(rx, 0)) {
    if (observer_) observer_(observer_ctx_, rx);
    record(rx.frame, rx.stamp.sample_ns);
    if (rx.frame.id == qc::kIdNavStatus) {
      qc::NavStatus ns;
      if (qc::decode(rx.frame, ns)) {
        reported_state_ = ns.state;
        reported_reject_ = ns.mode_reject;
        status_seen_since_cmd_ = true;
      }
    }
  }
}

void SimVehicle::send_mode(qc::Mode m, bool reverse) noexcept {
  qc::ModeCmd cmd;
  cmd.mode = m;
  cmd.reverse = reverse;
  cmd.route_id = cfg_.route_id;
  cmd.counter = ++mode_counter_;
  hal::CanFrame f;
  if (qc::encode(cmd, f) && bus_->send(f)) record(f, clock_.now_ns());
  status_seen_since_cmd_ = false;
  phase_start_ns_ = clock_.now_ns();
}

void SimVehicle::send_attitude(double heading_rad) noexcept {
  last_heading_ = heading_rad;
  const std::int64_t now = clock_.now_ns();
  if (stalled("attitude", now) || now == last_att_ns_) return;  // one AHRS sample per instant
  last_att_ns_ = now;
  double h = std::fmod(heading_rad, kTwoPi);
  if (h < 0) h += kTwoPi;
  if (cfg_.sim_ahrs == "dronecan") {
    // uavcan.equipment.ahrs.Solution from node 42: yaw about NED down as a quaternion.
    namespace dc = drivers::dronecan;
    dc::AhrsSolution sol;
    sol.timestamp_us = static_cast<std::uint64_t>(now / 1000);
    sol.orientation_xyzw[2] = static_cast<float>(std::sin(h / 2));
    sol.orientation_xyzw[3] = static_cast<float>(std::cos(h / 2));
    sol.linear_accel_mps2[2] = -9.81f;
    std::uint8_t payload[dc::kSolutionMaxBytes];
    const std::size_t n = dc::encode_solution(sol, true, payload, sizeof payload);
    hal::CanFrame frames[16];
    const std::size_t k = dc::split_transfer(dc::kSolutionSignature, dc::make_message_id(16, dc::kSolutionId, 42), att_counter_++, payload, n,
                                             frames, 16);
    for (std::size_t j = 0; j < k; ++j)
      if (bus_->send(frames[j])) record(frames[j], now);
    return;
  }
  qc::AttitudeIn a;
  a.heading_rad = std::fmin(h, 6.2832);
  a.valid = true;
  a.counter = att_counter_++;
  hal::CanFrame f;
  if (qc::encode(a, f) && bus_->send(f)) record(f, clock_.now_ns());
}

void SimVehicle::send_dvl(double fwd, double stbd, std::int64_t t_ns) noexcept {
  if (stalled("dvl", t_ns)) return;
  long long tov = t_ns / 1000;
  if (tov <= last_tov_us_) tov = last_tov_us_ + 1;
  last_tov_us_ = tov;
  char body[200], line[240];
  std::snprintf(body, sizeof body, "wrz,%.4f,%.4f,0.000,y,%.2f,0.002,1e-05;0;0;0;1e-05;0;0;0;1e-05,%lld,%lld,125.00,0", fwd, stbd,
                pass_cfg_.altitude_m, tov, tov);
  const std::size_t n = drivers::dvl::wl_with_checksum(body, line, sizeof line);
  static_cast<void>(dvl_->write(Span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(line), n)));
}

// Between passes the vehicle is alive: time passes and the AHRS streams.
void SimVehicle::idle_tick() noexcept {
  const std::int64_t t = clock_.now_ns() + kIdleTickNs / 10;
  clock_.set(t);
  if (t >= next_idle_att_ns_) {
    send_attitude(last_heading_);
    send_dvl(0.0, 0.0, t);  // the DVL streams too (the vehicle waits between passes)
    next_idle_att_ns_ = t + kIdleTickNs;
  }
}

Status SimVehicle::start_pass() {
  const SimPass& p = cfg_.sim_mission[pass_];
  const std::uint64_t seed = pass_ == 0 ? pipeline::teach_pass_seed(cfg_.sim_seed) : pipeline::repeat_pass_seed(cfg_.sim_seed) + pass_;
  pass_cfg_ = survey_->pass(p.offset_pct / 100.0 * survey_->swath_m, p.reverse, seed);
  // The first ping one ping period after the last sample between passes (sample times strictly increase).
  pass_cfg_.start_stamp_ns = static_cast<std::uint64_t>(clock_.now_ns() + static_cast<std::int64_t>(1e9 / pass_cfg_.ping_rate_hz));
  QNAV_RETURN_IF_ERROR(traj_.init(pass_cfg_));
  QNAV_RETURN_IF_ERROR(sonar_->init(survey_->sonar_for(pass_cfg_.seed), &survey_->seabed));
  have_prev_ = false;
  pass_start_ns_ = clock_.now_ns();
  return Status::ok();
}

void SimVehicle::release_ping(SpscRing<PingMsg>& pings, IoCounters& io) noexcept {
  if (!has_pending_) return;
  if (!pings.try_push(pending_)) io.ping_overflow.fetch_add(1, std::memory_order_relaxed);
  has_pending_ = false;
}

SimVehicle::StepResult SimVehicle::step(SpscRing<std::uint32_t>& free_slots, SpscRing<PingMsg>& pings, float* pool, std::size_t stride,
                                        IoCounters& io) noexcept {
  drain_bus();
  switch (phase_) {
    case Phase::kCommand: {
      if (pass_ >= cfg_.sim_mission.size()) {
        phase_ = Phase::kDone;
        return StepResult::kDone;
      }
      const SimPass& p = cfg_.sim_mission[pass_];
      send_attitude(last_heading_);  // the AHRS is up before the first command
      send_mode(p.mode, p.reverse);
      phase_ = Phase::kAwaitState;
      return StepResult::kWaiting;
    }
    case Phase::kAwaitState: {
      const SimPass& p = cfg_.sim_mission[pass_];
      if (status_seen_since_cmd_ && reported_state_ == p.mode && reported_reject_ == 0) {
        if (!start_pass()) {
          ++refusals_;
          ++pass_;
          phase_ = Phase::kCommand;
          return StepResult::kWaiting;
        }
        phase_ = Phase::kFly;
        return StepResult::kWaiting;
      }
      if ((status_seen_since_cmd_ && reported_reject_ != 0) || clock_.now_ns() - phase_start_ns_ > kStateTimeoutNs) {
        std::fprintf(stderr, "sim autopilot: pass %u: qnavd did not enter the commanded mode (reject code %u); skipping the pass\n", pass_,
                     reported_reject_);
        ++refusals_;
        ++pass_;
        send_mode(qc::Mode::kIdle, false);
        phase_ = Phase::kAwaitIdle;
        return StepResult::kWaiting;
      }
      idle_tick();
      return StepResult::kWaiting;
    }
    case Phase::kFly: {
      if (pings.size() >= 2 && cfg_.sim_speed == SimSpeed::kFast) return StepResult::kWaiting;  // replay waits for the consumer
      sidescan::TrajectorySample s;
      if (cfg_.sim_speed == SimSpeed::kRecorded) {
        // next ping's time = now + 1 / ping rate; wait for the wall clock to catch up
        const std::int64_t sim_elapsed = clock_.now_ns() - sim_start_ns_;
        if (wall_.now_ns() - wall_start_ns_ < sim_elapsed) return StepResult::kWaiting;
      }
      if (!traj_.next(s)) {
        phase_ = Phase::kEndPass;
        return StepResult::kWaiting;
      }
      const std::int64_t t = static_cast<std::int64_t>(s.stamp_ns);
      clock_.set(t);
      // AHRS: the compass heading (with the DVL + compass errors of the pass) at the ping time.
      send_attitude(s.nav.heading_rad);
      // DVL: the dead-reckoned displacement since the previous ping, in the body frame of that heading.
      if (have_prev_) {
        const double dt = 1.0 / pass_cfg_.ping_rate_hz;
        const double dn = (s.nav.x_m - prev_nav_.x_m) / dt, de = (s.nav.y_m - prev_nav_.y_m) / dt;
        const double c = std::cos(s.nav.heading_rad), sn = std::sin(s.nav.heading_rad);
        send_dvl(c * dn + sn * de, -sn * dn + c * de, t);
      } else {
        // The pass starts here: nothing travelled since the last sample between passes (whose time
        // depends on how fast the daemon answered the mode command), so every pass is flown the same.
        send_dvl(0.0, 0.0, t);
      }
      prev_nav_ = s.nav;
      have_prev_ = true;
      // Side-scan: render into a free slot of the pool.
      if (stalled("sonar", t)) return StepResult::kProduced;
      std::uint32_t slot = 0;
      if (spare_slot_ >= 0) {
        slot = static_cast<std::uint32_t>(spare_slot_);
        spare_slot_ = -1;
      } else if (!free_slots.try_pop(slot)) {
        io.ping_overflow.fetch_add(1, std::memory_order_relaxed);
        return StepResult::kProduced;
      }
      const std::size_t n = static_cast<std::size_t>(survey_->sonar.samples_per_side);
      float* port = pool + static_cast<std::size_t>(slot) * stride;
      float* stbd = port + stride / 2;
      PingMsg m;
      m.slot = slot;
      if (n > stride / 2 || !sonar_->ping(s.truth, s.altitude_m, s.index, Span<float>(port, n), Span<float>(stbd, n))) {
        io.sonar_rejected.fetch_add(1, std::memory_order_relaxed);
        spare_slot_ = slot;  // kept for the next ping (the nav worker is the only producer of free_slots)
        return StepResult::kProduced;
      }
      m.ping_number = s.index;
      m.port_samples = m.stbd_samples = static_cast<std::uint32_t>(n);
      m.slant_range_m = survey_->sonar.slant_range_m;
      m.altitude_m = s.altitude_m;
      m.device_stamp_ns = s.stamp_ns;
      m.stamp.sample_ns = m.stamp.arrival_ns = t;
      m.has_truth = true;
      m.truth.along_m = s.along_route_m;
      m.truth.pose = s.truth;
      m.truth.lateral_m = pass_cfg_.lateral_offset_m;
      // Held until the I/O thread has queued this instant's attitude frame and DVL sentence
      // (release_ping), as a real sonar's ping arrives with the navigation of its time.
      pending_ = m;
      has_pending_ = true;
      return StepResult::kProduced;
    }
    case Phase::kEndPass:
      // Let the nav worker finish the pass: every slot back (the last ping processed, not only popped).
      if (free_slots.size() + (spare_slot_ >= 0 ? 1u : 0u) < free_slots.capacity()) return StepResult::kWaiting;
      send_mode(qc::Mode::kIdle, false);
      ++pass_;
      phase_ = Phase::kAwaitIdle;
      return StepResult::kWaiting;
    case Phase::kAwaitIdle:
      if (status_seen_since_cmd_ && reported_state_ == qc::Mode::kIdle) {
        phase_ = Phase::kCommand;
        return StepResult::kWaiting;
      }
      idle_tick();
      return StepResult::kWaiting;
    case Phase::kDone: return StepResult::kDone;
  }
  return StepResult::kDone;
}

}  // namespace qnav::daemon
