// SimVehicle: qnavd's sim backend -- the vehicle around the daemon, inside the I/O thread. It flies
// the configured mission (sim.pass) and plays every peer on the daemon's buses as the real ones would.
// This class is the mission and its autopilot's mode handshake; its parts produce the samples:
//   - the autopilot on the CAN bus (in process, or sim.can_interface): QNAV_MODE_CMD before each pass
//     (mode, reverse, route id) and Idle after it, waiting for QNAV_NAV_STATUS to report the commanded
//     state (or a refusal; 5 s of mission time at most);
//   - SimSensors (sim_sensors.hpp): the AHRS and the DVL, sim.candump, and the injected faults
//     (sim.stall, sim.fault); the AHRS reports once per ping and every 100 ms between passes, and with
//     mavlink.enabled also between pings on the ODOMETRY grid (ahrs_tick);
//   - SimSonar (sim_sonar.hpp): the simulated side-scan pass and the ping pool;
//   - SimCameras (sim_cameras.hpp): the rover of a `vo` pass, a `map` pass's downward frames, and
//     recorded stereo pairs, into the frame pool;
//   - SimPlayback (sim_playback.hpp): recorded passes (XTF/JSF pings, candump, DVL, stereo logs);
//   - SimClosedLoop (sim_closed_loop.hpp): the autopilot steering on qnavd's guidance in a
//     closed-loop pass, and its dead-reckoning twin.
// Time is simulated (SimClock): sample stamps are mission time. The vehicle runs in lockstep with the
// nav worker at every speed (at most two pings or one frame in flight, so nothing is dropped); with
// sim.speed > 0 each step also waits for its deadline on the wall clock (SimPacer: absolute deadlines
// from the mission's start, late steps counted, never skipped), and while a pass's next sample waits,
// mission time follows the wall up to just before it, so the daemon's periodic outputs keep their
// periods in wall time too.
// Memory: init() allocates the seabed, simulator and recordings; step() allocates nothing, except when
// a closed-loop pass starts (sim_closed_loop.hpp). Time: one sample per step (see the parts).
#pragma once

#include <cstdint>
#include <cstdio>
#include <memory>

#include "drivers/qnavcan/messages.hpp"
#include "firmware/qnavd/config.hpp"
#include "firmware/qnavd/io_backend.hpp"
#include "firmware/qnavd/messages.hpp"
#include "firmware/qnavd/sim_cameras.hpp"
#include "firmware/qnavd/sim_pacer.hpp"
#include "firmware/qnavd/sim_playback.hpp"
#include "firmware/qnavd/sim_sensors.hpp"
#include "firmware/qnavd/sim_sonar.hpp"
#include "hal/core/clock.hpp"
#include "hal/core/serial.hpp"
#include "hal/sim/fault_file_store.hpp"
#include "hal/sim/sim_can.hpp"
#include "hal/sim/sim_gpio.hpp"
#include "nav/core/spsc_ring.hpp"

namespace qnav::daemon {

class SimClosedLoop;

class SimVehicle {
 public:
  using StepResult = SimStep;

  SimVehicle(const DaemonConfig& config, SimClock& clock, hal::Clock& wall) noexcept;
  ~SimVehicle();  // out of line: cl_'s type is sim_closed_loop.hpp's
  SimVehicle(const SimVehicle&) = delete;
  SimVehicle& operator=(const SimVehicle&) = delete;
  // autopilot: this vehicle's node on the daemon's CAN bus (in process, or its end of a SocketCAN
  // interface); dvl_out: the DVL's end of the serial line.
  Status init(hal::CanBus& autopilot, hal::SerialPort& dvl_out);
  // The pace against the wall clock (sim.speed): its counters, and the io thread's sleep to the next deadline.
  SimPacer& pacer() noexcept { return pacer_; }
  const SimPacer& pacer() const noexcept { return pacer_; }
  // Fault injection's reach: the CAN network (error frames) and the route store (a full disk).
  void set_fault_targets(hal::SimCanNetwork* net, hal::FaultFileStore* store) noexcept { sensors_.set_fault_targets(net, store); }
  void set_bus_observer(BusObserver f, void* ctx) noexcept { observer_ = f, observer_ctx_ = ctx; }
  // The io thread's log (the closed-loop passes' summary lines); null = stderr only.
  void set_log(std::FILE* log) noexcept;
  // Lockstep between passes: while the vehicle waits for the daemon to report a commanded mode, its
  // clock moves on (idle_tick) only once the nav worker has taken every input of the last tick and its
  // answer is on the bus (the backend says so before each step). The length of a mode handshake in
  // mission time then does not depend on thread timing, and a replay is reproducible run to run.
  void set_worker_caught_up(bool v) noexcept { worker_caught_up_ = v; }
  // The leak detector's line (sim.fault = "leak" wets it for the fault's window).
  void set_leak_line(hal::SimGpioLine* line) noexcept { sensors_.set_leak_line(line); }
  // The stereo pairs' pool and queues (vo passes need them: vo.enabled).
  void set_frame_pool(const FramePool& frames) noexcept { cameras_.set_frame_pool(frames); }
  // A rendered pair is held back like a ping until its instant's attitude is queued.
  void release_pair(IoCounters& io) noexcept { cameras_.release_pair(io); }
  // One step: produce the next ping (with its attitude frame and DVL sentence) if the nav side has
  // room, or advance the mission's handshake. pool/stride: the ping pool (see messages.hpp).
  // A produced ping is held back until release_ping(), which the I/O thread calls after it has
  // queued the CAN frames and DVL samples of the same instant.
  StepResult step(SpscRing<std::uint32_t>& free_slots, SpscRing<PingMsg>& pings, float* pool, std::size_t stride, IoCounters& io) noexcept;
  void release_ping(SpscRing<PingMsg>& pings, IoCounters& io) noexcept { sonar_.release_ping(pings, io); }
  // Recorded passes: the median slant range of their pings and the distance between tiles
  // (sim.replay_stride pings); false when the mission has no recorded pass.
  bool recorded_geometry(double& range_m, double& spacing_m) const { return playback_.recorded_geometry(range_m, spacing_m); }
  double swath_m() const noexcept { return sonar_.survey().swath_m; }
  double node_spacing_m(int scanline_stride) const noexcept { return sonar_.survey().node_spacing_m(scanline_stride); }

 private:
  enum class Phase : std::uint8_t { kCommand, kAwaitState, kFly, kEndPass, kAwaitIdle, kDone };
  void set_phase(Phase p) noexcept {
    phase_ = p;
    sensors_.set_flying(p == Phase::kFly);
  }
  Status start_pass();
  void drain_bus() noexcept;
  void send_mode(drivers::qnavcan::Mode m, bool reverse) noexcept;
  StepResult fly(SpscRing<std::uint32_t>& free_slots, float* pool, std::size_t stride, IoCounters& io) noexcept;
  StepResult fly_replay(SpscRing<std::uint32_t>& free_slots, float* pool, std::size_t stride, IoCounters& io) noexcept;
  // A ping instant: its attitude, its DVL velocities, its ping.
  StepResult emit(const SimSample& s, SpscRing<std::uint32_t>& free_slots, float* pool, std::size_t stride, IoCounters& io) noexcept;
  bool ahrs_tick() noexcept;  // true when it sent one (the step produced)
  void idle_tick() noexcept;

  const DaemonConfig& cfg_;
  SimClock& clock_;
  SimPacer pacer_;
  SimSensors sensors_;
  SimSonar sonar_;
  SimCameras cameras_;
  SimPlayback playback_;
  std::unique_ptr<SimClosedLoop> cl_;  // created at init when the mission has a closed-loop pass
  std::FILE* log_ = nullptr;
  BusObserver observer_ = nullptr;
  void* observer_ctx_ = nullptr;
  IoCounters* io_ = nullptr;  // set by step()
  Phase phase_ = Phase::kCommand;
  std::uint32_t pass_ = 0;
  std::uint8_t mode_counter_ = 0;
  drivers::qnavcan::Mode reported_state_ = drivers::qnavcan::Mode::kIdle;
  std::uint8_t reported_reject_ = 0;
  bool status_seen_since_cmd_ = false;
  std::int64_t phase_start_ns_ = 0;
  std::int64_t pass_start_ns_ = 0;
  std::int64_t next_idle_att_ns_ = 0;
  bool worker_caught_up_ = true;
  bool no_sim_dvl_ = false;  // the simulated DVL never sends between passes (a recorded DVL keeps its clock)
  // Pacing (sim.speed): a pass's next sample, drawn and held until its deadline (SimPacer::pace).
  bool has_held_ = false;
  SimSample held_{};
  bool have_prev_ = false;
  Pose2 prev_nav_{};
  std::int64_t last_sample_ns_ = 0;
  // mavlink.enabled: the AHRS also streams between a pass's pings on the grid of mavlink.odometry_hz
  // (its period, ns; 0 = one AHRS sample per ping only). In a fast mission the nav worker sees no
  // finer time than its inputs', so ODOMETRY could come no faster than the pings (5 Hz) without it.
  std::int64_t ahrs_tick_ns_ = 0;
};

}  // namespace qnav::daemon
