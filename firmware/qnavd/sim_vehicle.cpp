#include "firmware/qnavd/sim_vehicle.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "firmware/pipeline/dead_reckoner.hpp"
#include "firmware/qnavd/sim_closed_loop.hpp"

namespace qnav::daemon {

namespace qc = drivers::qnavcan;

namespace {
constexpr std::int64_t kIdleTickNs = 100000000;      // the AHRS streams between passes (10 Hz)
constexpr std::int64_t kStateTimeoutNs = 5000000000;  // 5 s of mission time for NAV_STATUS to confirm
constexpr double kTwoPi = 6.283185307179586;
}  // namespace

SimVehicle::SimVehicle(const DaemonConfig& config, SimClock& clock, hal::Clock& wall) noexcept
    : cfg_(config), clock_(clock), pacer_(wall, config.sim_speed), sensors_(config, clock), cameras_(clock, pacer_, sensors_), playback_(config) {
  sensors_.set_dvl_altitude(sonar_.altitude_m());  // until the first simulated pass
}

SimVehicle::~SimVehicle() = default;

void SimVehicle::set_log(std::FILE* log) noexcept {
  log_ = log;
  if (cl_) cl_->set_log(log);
}

Status SimVehicle::init(hal::CanBus& autopilot, hal::SerialPort& dvl_out) {
  if (cfg_.mavlink_enabled && cfg_.mavlink_odometry_hz > 0.0) ahrs_tick_ns_ = static_cast<std::int64_t>(1e9 / cfg_.mavlink_odometry_hz);
  QNAV_RETURN_IF_ERROR(sensors_.init(autopilot, dvl_out));
  QNAV_RETURN_IF_ERROR(sonar_.init(cfg_.sim_length_m, cfg_.sim_seed));
  if (cfg_.sim_mission.size() == 0) return Status(StatusCode::kInvalidArgument, "sim: the mission has no [[sim.pass]]");
  std::size_t index = 0;
  for (const SimPass& p : cfg_.sim_mission) {
    QNAV_RETURN_IF_ERROR(cameras_.add_map_pass(p));
    QNAV_RETURN_IF_ERROR(playback_.add_sensors(p, index++, cameras_));
    // A stereo sequence replayed without its CAN log is a rig without an attitude sensor: the
    // simulated AHRS stays silent for the whole mission (the VO runs as `qnav vo --kitti` does).
    if (p.mode == qc::Mode::kVo && !p.images.empty() && p.candump.empty()) sensors_.set_no_ahrs();
    // A recorded DVL stamps its sentences with its own clock: the simulated one (mission time) stays
    // silent between passes, or its sentences would step that clock back.
    if (!p.dvl_log.empty()) no_sim_dvl_ = true;
    QNAV_RETURN_IF_ERROR(cameras_.add_rover(p));
    QNAV_RETURN_IF_ERROR(playback_.add_recording(p));
  }
  for (const SimPass& p : cfg_.sim_mission) {
    if (!p.closed_loop || cl_) continue;
    cl_ = std::make_unique<SimClosedLoop>(cfg_, clock_);
    cl_->set_log(log_);
    QNAV_RETURN_IF_ERROR(cl_->init());
  }
  set_phase(Phase::kCommand);
  next_idle_att_ns_ = clock_.now_ns();
  return Status::ok();
}

void SimVehicle::drain_bus() noexcept {
  hal::CanRxFrame rx;
  while (sensors_.bus().receive(rx, 0)) {
    if (observer_) observer_(observer_ctx_, rx);
    sensors_.record(rx.frame, rx.stamp.sample_ns);
    // A closed-loop pass: the autopilot steers on the guidance it hears (bad frames are counted by it).
    if (cl_ && cl_->active()) cl_->on_frame(rx.frame);
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
  if (qc::encode(cmd, f) && sensors_.bus().send(f)) sensors_.record(f, clock_.now_ns());
  status_seen_since_cmd_ = false;
  phase_start_ns_ = clock_.now_ns();
}

// Between two pings of a pass (mavlink.enabled): the AHRS sample at the next instant of the
// odometry grid (multiples of ahrs_tick_ns_ in mission time, the grid MavlinkEndpoint publishes on)
// before the held ping, its heading interpolated between the two pings' (the shorter way round). The
// dead reckoning is unchanged: each DVL sample still comes with the heading of its own instant.
bool SimVehicle::ahrs_tick() noexcept {
  if (ahrs_tick_ns_ <= 0 || !have_prev_ || playback_.replays_attitude() || !has_held_) return false;
  const std::int64_t tick = (clock_.now_ns() / ahrs_tick_ns_ + 1) * ahrs_tick_ns_;
  if (tick <= last_sample_ns_ || tick >= held_.t_ns) return false;
  clock_.set(tick);
  sensors_.inject_bus_faults(tick);
  const double f = static_cast<double>(tick - last_sample_ns_) / static_cast<double>(held_.t_ns - last_sample_ns_);
  const double dh = std::remainder(held_.nav.heading_rad - prev_nav_.heading_rad, kTwoPi);
  sensors_.send_attitude(prev_nav_.heading_rad + f * dh);
  return true;
}

// Between passes the vehicle is alive: time passes and the AHRS streams.
void SimVehicle::idle_tick() noexcept {
  if (!worker_caught_up_) return;  // lockstep (set_worker_caught_up)
  const std::int64_t t = clock_.now_ns() + kIdleTickNs / 10;
  if (!pacer_.pace(clock_, t, false, io_)) return;  // the handshake's ticks keep their mission-time lengths (no following)
  clock_.set(t);
  if (t >= next_idle_att_ns_) {
    sensors_.send_attitude(sensors_.last_heading());
    if (!no_sim_dvl_) sensors_.send_dvl(0.0, 0.0, t);  // the DVL streams too (the vehicle waits between passes)
    next_idle_att_ns_ = t + kIdleTickNs;
  }
}

Status SimVehicle::start_pass() {
  const SimPass& p = cfg_.sim_mission[pass_];
  playback_.select(pass_);
  have_prev_ = false;
  pass_start_ns_ = clock_.now_ns();
  sensors_.set_pass(pass_, pass_start_ns_);
  // The autopilot logs its taught track in a simulated teach pass.
  if (cl_) cl_->begin_pass(p.mode == qc::Mode::kTeach && !playback_.has_pings() && !playback_.has_sensors());
  if (p.mode == qc::Mode::kMap) {
    cameras_.start_map_pass(clock_.now_ns() + kSimPassLeadNs);
    return Status::ok();
  }
  if (p.mode == qc::Mode::kVo && playback_.has_pairs()) {
    playback_.align(clock_.now_ns());
    return Status::ok();
  }
  if (p.mode == qc::Mode::kVo) {
    // The rover's first pair one step after the last sample between passes.
    cameras_.start_rover(cfg_.sim_seed + pass_, p.length_m, clock_.now_ns() + kSimPassLeadNs);
    return Status::ok();
  }
  if (playback_.has_pings()) {
    QNAV_RETURN_IF_ERROR(playback_.start_pings(p));
    if (playback_.has_sensors()) playback_.align(clock_.now_ns());
    return Status::ok();
  }
  if (playback_.has_sensors()) {  // recorded sensors without a side-scan file: no pings in this pass
    playback_.align(clock_.now_ns());
    return Status::ok();
  }
  const std::uint64_t seed = pass_ == 0 ? pipeline::teach_pass_seed(cfg_.sim_seed) : pipeline::repeat_pass_seed(cfg_.sim_seed) + pass_;
  const Status started = sonar_.start_pass(p, seed, clock_.now_ns());
  sensors_.set_dvl_altitude(sonar_.altitude_m());
  QNAV_RETURN_IF_ERROR(started);
  if (p.closed_loop) {
    const Status st = cl_->start(pass_, seed, sonar_.survey(), sensors_.store());
    if (!st) std::fprintf(stderr, "sim autopilot: pass %u: %s; skipping the pass\n", pass_, st.message());
    return st;
  }
  return Status::ok();
}

SimVehicle::StepResult SimVehicle::emit(const SimSample& smp, SpscRing<std::uint32_t>& free_slots, float* pool, std::size_t stride,
                                        IoCounters& io) noexcept {
  const std::int64_t t = smp.t_ns;
  clock_.set(t);
  sensors_.inject_bus_faults(t);
  // AHRS: the compass heading (with the DVL + compass errors of the pass) at the ping time, unless
  // the pass replays the recorded one (sim.pass.candump), or the DVL (sim.pass.dvl_log).
  if (!playback_.replays_attitude()) sensors_.send_attitude(smp.nav.heading_rad);
  // DVL: the dead-reckoned displacement since the previous ping, in the body frame of that heading.
  // The pass's first sample sends zero: nothing travelled since the last sample between passes
  // (whose time depends on how fast the daemon answered the mode command), so every pass is flown
  // the same.
  double fwd_mps = 0.0, stbd_mps = 0.0;
  if (have_prev_ && t > last_sample_ns_)
    pipeline::body_velocity_between(prev_nav_, smp.nav, static_cast<double>(t - last_sample_ns_) * 1e-9, fwd_mps, stbd_mps);
  if (!playback_.replays_dvl()) sensors_.send_dvl(fwd_mps, stbd_mps, t);
  prev_nav_ = smp.nav;
  have_prev_ = true;
  last_sample_ns_ = t;
  // Side-scan: render (or copy the recorded ping) into a free slot of the pool.
  return sonar_.emit_ping(smp, t, sensors_, free_slots, pool, stride, io);
}

// A pass with recorded sensors: the next sample of any source, in time order, on the mission clock
// (never backwards: a source whose clock steps back plays at the current time).
SimVehicle::StepResult SimVehicle::fly_replay(SpscRing<std::uint32_t>& free_slots, float* pool, std::size_t stride, IoCounters& io) noexcept {
  using Source = SimPlayback::Source;
  std::int64_t best = 0;
  const Source which = playback_.next(best);
  if (which == Source::kNone) {
    set_phase(Phase::kEndPass);
    return StepResult::kWaiting;
  }
  const std::int64_t t = std::max(best, clock_.now_ns());
  if (which == Source::kPair && cameras_.busy()) return StepResult::kWaiting;  // the consumer sets the pace
  if (!pacer_.pace(clock_, t, true, io_)) return StepResult::kWaiting;
  switch (which) {
    case Source::kPing: {
      SimSample smp;
      if (!playback_.next_recorded(smp, pass_start_ns_, last_sample_ns_)) return StepResult::kWaiting;
      smp.t_ns = std::max(t, last_sample_ns_ + 1000);  // the recorded timing, aligned with the logs
      return emit(smp, free_slots, pool, stride, io);
    }
    case Source::kCan:
      clock_.set(t);
      sensors_.inject_bus_faults(t);
      sensors_.replay_can(playback_.take_can(), t);
      return StepResult::kProduced;
    case Source::kDvl: {
      clock_.set(t);
      const ReplayDvlReport& r = playback_.take_dvl();
      sensors_.replay_dvl(playback_.dvl_text(r), r.length, t);
      return StepResult::kProduced;
    }
    case Source::kPair: {
      clock_.set(t);
      sensors_.inject_bus_faults(t);
      std::uint32_t seq = 0;
      const tools::StereoFrame& pf = playback_.take_pair(seq);
      return cameras_.replay_pair(pf, seq, t, io);
    }
    case Source::kNone: break;
  }
  return StepResult::kWaiting;
}

// A pass in flight: the next sample of its kind (map, recorded, vo, side-scan), or kWaiting.
SimVehicle::StepResult SimVehicle::fly(SpscRing<std::uint32_t>& free_slots, float* pool, std::size_t stride, IoCounters& io) noexcept {
  const qc::Mode mode = cfg_.sim_mission[pass_].mode;
  if (mode == qc::Mode::kMap || (mode == qc::Mode::kVo && !playback_.has_sensors())) {  // the cameras' passes
    bool over = false;
    const StepResult r = mode == qc::Mode::kMap ? cameras_.fly_downward(pass_, io, over) : cameras_.fly_rover(io, over);
    if (over) set_phase(Phase::kEndPass);
    return r;
  }
  if (playback_.has_sensors()) return fly_replay(free_slots, pool, stride, io);
  if (!has_held_) {
    bool got = false;
    if (playback_.has_pings()) {
      got = playback_.next_recorded(held_, pass_start_ns_, last_sample_ns_);
    } else if (cl_ && cl_->active()) {
      got = cl_->next(held_, sonar_.render_pose(), sonar_.survey().route.altitude_m, pass_start_ns_);
    } else {
      got = sonar_.next(held_);
      if (got && cl_) cl_->log_teach_pose(held_.nav);
    }
    if (!got) {
      set_phase(Phase::kEndPass);
      return StepResult::kWaiting;
    }
    has_held_ = true;
  }
  if (ahrs_tick_ns_ > 0 && have_prev_ && !playback_.replays_attitude()) {  // the AHRS between pings (mavlink.enabled)
    const std::int64_t tick = (clock_.now_ns() / ahrs_tick_ns_ + 1) * ahrs_tick_ns_;
    if (tick > last_sample_ns_ && tick < held_.t_ns) {
      if (!pacer_.pace(clock_, tick, true, io_)) return StepResult::kWaiting;
      if (ahrs_tick()) return StepResult::kProduced;
    }
  }
  if (!pacer_.pace(clock_, held_.t_ns, true, io_)) return StepResult::kWaiting;
  has_held_ = false;
  return emit(held_, free_slots, pool, stride, io);
}

SimVehicle::StepResult SimVehicle::step(SpscRing<std::uint32_t>& free_slots, SpscRing<PingMsg>& pings, float* pool, std::size_t stride,
                                        IoCounters& io) noexcept {
  io_ = &io;
  sensors_.set_counters(&io);
  if (!pacer_.started()) pacer_.start(clock_.now_ns());  // the pace's anchor: the mission's first step
  drain_bus();
  switch (phase_) {
    case Phase::kCommand: {
      if (pass_ >= cfg_.sim_mission.size()) {
        set_phase(Phase::kDone);
        return StepResult::kDone;
      }
      const SimPass& p = cfg_.sim_mission[pass_];
      sensors_.send_attitude(sensors_.last_heading());  // the AHRS is up before the first command
      send_mode(p.mode, p.reverse);
      set_phase(Phase::kAwaitState);
      return StepResult::kWaiting;
    }
    case Phase::kAwaitState: {
      const SimPass& p = cfg_.sim_mission[pass_];
      if (status_seen_since_cmd_ && reported_state_ == p.mode && reported_reject_ == 0) {
        if (!start_pass()) {
          sensors_.set_pass(++pass_, pass_start_ns_);
          set_phase(Phase::kCommand);
          return StepResult::kWaiting;
        }
        set_phase(Phase::kFly);
        return StepResult::kWaiting;
      }
      if ((status_seen_since_cmd_ && reported_reject_ != 0) || clock_.now_ns() - phase_start_ns_ > kStateTimeoutNs) {
        std::fprintf(stderr, "sim autopilot: pass %u: qnavd did not enter the commanded mode (reject code %u); skipping the pass\n", pass_,
                     reported_reject_);
        sensors_.set_pass(++pass_, pass_start_ns_);
        send_mode(qc::Mode::kIdle, false);
        set_phase(Phase::kAwaitIdle);
        return StepResult::kWaiting;
      }
      idle_tick();
      return StepResult::kWaiting;
    }
    case Phase::kFly:
      if (pings.size() >= 2) return StepResult::kWaiting;  // the consumer sets the pace (every speed: the lockstep)
      // A closed-loop pass flies its next instant only once the daemon has navigated the last one and
      // the frames it published reached the vehicle: the autopilot hears each tile's guidance at the
      // ping after the tile, as in `qnav route follow`, whatever the host's load (without this the
      // frames arrived 0-2 pings late, and one seed's p95 varied 4.3-5.1 m from run to run).
      if (cl_ && cl_->active() && !worker_caught_up_) return StepResult::kWaiting;
      return fly(free_slots, pool, stride, io);
    case Phase::kEndPass:
      // Let the nav worker finish the pass: every slot back (the last ping processed, not only popped).
      if (!sonar_.all_slots_back(free_slots) || !cameras_.all_slots_back()) return StepResult::kWaiting;
      // A fault window ends with its pass at the latest (the disk is free, the bus restarted):
      // out of kFly no window is open.
      set_phase(Phase::kAwaitIdle);
      sensors_.inject_bus_faults(clock_.now_ns());
      send_mode(qc::Mode::kIdle, false);
      sensors_.set_pass(++pass_, pass_start_ns_);
      return StepResult::kWaiting;
    case Phase::kAwaitIdle:
      if (status_seen_since_cmd_ && reported_state_ == qc::Mode::kIdle) {
        set_phase(Phase::kCommand);
        return StepResult::kWaiting;
      }
      idle_tick();
      return StepResult::kWaiting;
    case Phase::kDone: return StepResult::kDone;
  }
  return StepResult::kDone;
}

}  // namespace qnav::daemon
