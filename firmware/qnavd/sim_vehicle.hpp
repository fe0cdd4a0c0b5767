// SimVehicle: qnavd's sim backend -- the vehicle around the daemon, inside the I/O thread. It flies
// the configured mission over pipeline::SimSurvey (the same survey `qnav route eval` uses) and plays
// every peer on the daemon's buses as the real ones would:
//   - the autopilot on the CAN bus (in process, or sim.can_interface): QNAV_MODE_CMD before each pass (mode, reverse, route
//     id) and Idle after it, waiting for QNAV_NAV_STATUS to report the commanded state (or a refusal);
//   - the AHRS on the same bus: QNAV_ATTITUDE_IN with the compass heading, one per ping and every
//     100 ms between passes;
//   - the DVL on an in-process serial line: Water Linked "wrz" sentences (real checksums) with the
//     dead-reckoning velocity (bias, scale error, noise of a DVL + compass), parsed by the real driver;
//   - the side-scan: each rendered ping copied into a free slot of the ping pool;
//   - in a `vo` pass, the rover (SimRover): the Mars-yard stereo pair rendered into a free slot of the
//     frame pool at each step, with the body's measured roll, pitch and heading on QNAV_ATTITUDE_IN
//     (or the DroneCAN AHRS) at the pair's time; no pings and no DVL during the pass.
// Time is simulated (SimClock): sample stamps are mission time. The vehicle runs in lockstep with the
// nav worker at every speed (at most two pings or one frame in flight, so nothing is dropped); with
// sim.speed > 0 each step also waits for its deadline on the wall clock (SimPacer: absolute deadlines
// from the mission's start, late steps counted, never skipped), and while a pass's next sample waits,
// mission time follows the wall up to just before it, so the daemon's periodic outputs keep their
// periods in wall time too. Truth (along-route, lateral, pose) travels with each ping.
// A [[sim.pass]] with a file replays a recorded XTF/JSF pass instead: its pings, its navigation (the
// file's fixes or dead reckoning) as the AHRS heading and DVL velocities, its timing. Recorded sensor
// logs (sim_replay.hpp: a candump log, a DVL capture, a stereo sequence in a vo pass) replace the
// simulated AHRS, DVL and rover; a pass's sources play in the order of their own times, aligned on
// the earliest of them (fly_replay).
// Fault injection (sim.stall): the DVL, the AHRS or the sonar falls silent for a stretch of a pass;
// (sim.fault) damaged or disordered input for a stretch of a pass: NaN, duplicated, backwards or
// noisy DVL sentences, out-of-range or duplicated attitude frames, CAN error frames and
// bus-off, NaN or damaged-range pings, pings stamped in the past, a full disk. Every injected sample
// is counted in IoCounters::faults_injected (the tests compare it with the daemon's rejections).
// sim.candump records every frame on the bus in candump -l format (`qnav can decode` reads it).
// Closed loop (sim.pass.closed_loop, a simulated repeat): the vehicle's autopilot logs its own dead
// reckoning while qnavd teaches (every 10 m) and, when the repeat starts, reads the taught route's
// node poses (the route file: the numbers NAV_STATUS.NodeIndex points at) into its taught track; it
// then steers with pipeline::RouteAutopilot on the QNAV_ROUTE_GUIDANCE / STATUS frames it receives
// on this bus (decoded with drivers/qnavcan), flying pipeline::ClosedLoopVehicle (dynamics, current,
// drifting compass and DVL: pipeline::follow_scenario for sim.seed, as `qnav route follow --sim`);
// each ping is rendered from the TRUE pose, the AHRS and DVL report its dead reckoning (in a DVL
// dropout the velocity through the water, as a DVL in water-track would). A twin flies the same
// start, drift and current on dead reckoning alone (no pings). At the pass's end: one
// `sim_closed_loop` line (truth cross-track of both) on the io log and stderr; sim.closed_loop_csv the
// tracks.
// init() allocates the seabed and simulator; step() allocates nothing, except when a closed-loop pass
// starts (its taught track, the route's node poses, the per-ping records: sim_closed_loop.hpp).
#pragma once

#include <atomic>
#include <cstdio>
#include <cstdint>
#include <memory>
#include <vector>

#include "firmware/qnavd/io_backend.hpp"
#include "drivers/downward_sim/seabed_scene.hpp"
#include "drivers/qnavcan/messages.hpp"
#include "drivers/sidescan/sim_sidescan.hpp"
#include "drivers/sidescan/sim_trajectory.hpp"
#include "firmware/pipeline/sim_survey.hpp"
#include "firmware/qnavd/config.hpp"
#include "firmware/qnavd/messages.hpp"
#include "firmware/qnavd/sim_pacer.hpp"
#include "firmware/qnavd/sim_replay.hpp"
#include "firmware/qnavd/sim_rover.hpp"
#include "firmware/tools/sonar_file.hpp"
#include "hal/core/clock.hpp"
#include "hal/core/serial.hpp"
#include "hal/sim/fault_file_store.hpp"
#include "hal/sim/sim_can.hpp"
#include "hal/sim/sim_gpio.hpp"
#include "nav/core/spsc_ring.hpp"

namespace qnav::daemon {

// Mission time for the sim backend (set by the I/O thread, read by every thread).
class SimClock final : public hal::Clock {
 public:
  std::int64_t now_ns() const noexcept override { return t_ns_.load(std::memory_order_acquire); }
  void set(std::int64_t t) noexcept { t_ns_.store(t, std::memory_order_release); }

 private:
  std::atomic<std::int64_t> t_ns_{1000000000};
};

// A frame the autopilot saw on the bus (the daemon's outputs), for logs and tests.

class SimVehicle {
 public:
  enum class StepResult : std::uint8_t { kProduced, kWaiting, kDone };

  SimVehicle(const DaemonConfig& config, SimClock& clock, hal::Clock& wall) noexcept;  // out of line: cl_'s type is sim_closed_loop.hpp's
  ~SimVehicle();
  SimVehicle(const SimVehicle&) = delete;
  SimVehicle& operator=(const SimVehicle&) = delete;
  // autopilot: this vehicle's node on the daemon's CAN bus (in process, or its end of a SocketCAN
  // interface); dvl_out: the DVL's end of the serial line.
  Status init(hal::CanBus& autopilot, hal::SerialPort& dvl_out);
  // The pace against the wall clock (sim.speed): its counters, and the io thread's sleep to the next deadline.
  SimPacer& pacer() noexcept { return pacer_; }
  const SimPacer& pacer() const noexcept { return pacer_; }
  // Fault injection's reach: the CAN network (error frames) and the route store (a full disk).
  void set_fault_targets(hal::SimCanNetwork* net, hal::FaultFileStore* store) noexcept { net_ = net, store_ = store; }
  void set_bus_observer(BusObserver f, void* ctx) noexcept { observer_ = f, observer_ctx_ = ctx; }
  // The io thread's log (the closed-loop passes' summary lines); null = stderr only.
  void set_log(std::FILE* log) noexcept { log_ = log; }
  // Lockstep between passes: while the vehicle waits for the daemon to report a commanded mode, its
  // clock moves on (idle_tick) only once the nav worker has taken every input of the last tick and its
  // answer is on the bus (the backend says so before each step). The length of a mode handshake in
  // mission time then does not depend on thread timing, and a replay is reproducible run to run.
  void set_worker_caught_up(bool v) noexcept { worker_caught_up_ = v; }
  // The leak detector's line (sim.fault = "leak" wets it for the fault's window).
  void set_leak_line(hal::SimGpioLine* line) noexcept { leak_line_ = line; }
  // The stereo pairs' pool and queues (vo passes need them: vo.enabled).
  void set_frame_pool(const FramePool& frames) noexcept { frames_ = frames; }
  // A rendered pair is held back like a ping until its instant's attitude is queued.
  void release_pair(IoCounters& io) noexcept;
  // One step: produce the next ping (with its attitude frame and DVL sentence) if the nav side has
  // room, or advance the mission's handshake. pool/stride: the ping pool (see messages.hpp).
  // A produced ping is held back until release_ping(), which the I/O thread calls after it has
  // queued the CAN frames and DVL samples of the same instant.
  StepResult step(SpscRing<std::uint32_t>& free_slots, SpscRing<PingMsg>& pings, float* pool, std::size_t stride, IoCounters& io) noexcept;
  void release_ping(SpscRing<PingMsg>& pings, IoCounters& io) noexcept;
  // Recorded passes: the median slant range of their pings and the distance between tiles
  // (sim.replay_stride pings); false when the mission has no recorded pass.
  bool recorded_geometry(double& range_m, double& spacing_m) const;
  double swath_m() const noexcept { return survey_->swath_m; }
  double node_spacing_m(int scanline_stride) const noexcept { return survey_->node_spacing_m(scanline_stride); }

 private:
  enum class Phase : std::uint8_t { kCommand, kAwaitState, kFly, kEndPass, kAwaitIdle, kDone };
  struct Recording {  // a recorded file's pings and track (loaded at init)
    tools::FileData data;
    tools::NavTrack track;
  };
  struct Sample {  // one ping instant, simulated or recorded
    std::int64_t t_ns = 0;
    Pose2 nav{};
    std::uint32_t ping_number = 0;
    std::uint64_t device_stamp_ns = 0;
    float altitude_m = -1.0f;
    bool has_truth = false;
    pipeline::PingTruth truth;
    const tools::PingRec* recorded = nullptr;
  };
  static constexpr std::int64_t kPassLeadNs = 200000000;  // a pass's first ping after its mode command
  // Sample times before this (1973) are relative to their recording's start (a KITTI copy's 10 Hz
  // index), later ones are absolute (ns since the epoch) and shared by a pass's sources.
  static constexpr std::int64_t kEpochFloorNs = 100000000000000000LL;
  bool next_simulated(Sample& out) noexcept;
  // Closed loop (see above): the state lives in closed_loop.cpp's ClosedLoopPass.
  Status start_closed_loop_pass(std::uint64_t pass_seed);
  bool next_closed_loop(Sample& out) noexcept;
  void finish_closed_loop() noexcept;
  void log_teach_pose(const Pose2& nav) noexcept;  // a simulated teach pass's ping: the autopilot's log
  struct ClosedLoopPass;
  std::unique_ptr<ClosedLoopPass> cl_;
  std::FILE* log_ = nullptr;
  bool next_recorded(Sample& out) noexcept;
  StepResult emit(const Sample& s, SpscRing<std::uint32_t>& free_slots, float* pool, std::size_t stride, IoCounters& io) noexcept;
  void drain_bus() noexcept;
  void send_mode(drivers::qnavcan::Mode m, bool reverse) noexcept;
  void send_attitude(double heading_rad, double roll_rad = 0.0, double pitch_rad = 0.0) noexcept;
  StepResult fly_rover(IoCounters& io) noexcept;
  // A map pass: the next frame of its folder (sim.pass.images) into the frame pool, one every
  // kMapFramePeriodNs of mission time; unreadable or wrong-size files counted (camera_rejected).
  StepResult fly_downward(IoCounters& io) noexcept;
  Status load_map_frames(const SimPass& p);
  StepResult fly_replay(SpscRing<std::uint32_t>& free_slots, SpscRing<PingMsg>& pings, float* pool, std::size_t stride,
                        IoCounters& io) noexcept;
  StepResult replay_pair(std::int64_t t, IoCounters& io) noexcept;
  bool take_frame_slot(std::uint32_t& slot, IoCounters& io) noexcept;
  bool peek_recorded(std::int64_t& stamp_ns) noexcept;
  Status load_sensors(const SimPass& p, std::size_t index);
  void align_sensors() noexcept;
  std::int64_t replay_time(std::int64_t t) const noexcept { return t + (t >= kEpochFloorNs ? abs_offset_ns_ : rel_offset_ns_); }
  void send_dvl(double fwd_mps, double stbd_mps, std::int64_t t_ns) noexcept;
  void idle_tick() noexcept;
  Status start_pass();

  const DaemonConfig& cfg_;
  SimClock& clock_;
  SimPacer pacer_;
  hal::CanBus* bus_ = nullptr;
  hal::SerialPort* dvl_ = nullptr;
  BusObserver observer_ = nullptr;
  void* observer_ctx_ = nullptr;
  std::unique_ptr<pipeline::SimSurvey> survey_;
  std::unique_ptr<sidescan::SideScanSimulator> sonar_;
  sidescan::Trajectory traj_;
  sidescan::TrajectoryConfig pass_cfg_;
  Phase phase_ = Phase::kCommand;
  std::uint32_t pass_ = 0;
  std::uint8_t mode_counter_ = 0, att_counter_ = 0;
  drivers::qnavcan::Mode reported_state_ = drivers::qnavcan::Mode::kIdle;
  std::uint8_t reported_reject_ = 0;
  bool status_seen_since_cmd_ = false;
  std::int64_t phase_start_ns_ = 0;
  std::int64_t pass_start_ns_ = 0;
  std::int64_t next_idle_att_ns_ = 0;
  bool worker_caught_up_ = true;
  // Pacing (sim.speed): a pass's next sample, drawn and held until its deadline (pace()).
  bool pace(std::int64_t t_ns, bool follow) noexcept;
  bool has_held_ = false;
  Sample held_{};
  bool has_held_rover_ = false;
  RoverSample held_rover_{};
  bool have_prev_ = false;
  Pose2 prev_nav_{};
  // mavlink.enabled: the AHRS also streams between a pass's pings on the grid of mavlink.odometry_hz
  // (its period, ns; 0 = one AHRS sample per ping only). In a fast mission the nav worker sees no
  // finer time than its inputs', so ODOMETRY could come no faster than the pings (5 Hz) without it.
  std::int64_t ahrs_tick_ns_ = 0;
  bool ahrs_tick() noexcept;  // true when it sent one (the step produced)
  double last_heading_ = 0.0;
  std::int64_t last_tov_us_ = 0;
  std::int64_t last_att_ns_ = -1;
  std::int64_t spare_slot_ = -1;
  std::vector<std::unique_ptr<Recording>> recordings_;  // one per [[sim.pass]]; null for a simulated pass
  const Recording* recording_ = nullptr;                 // the pass being flown
  std::size_t rec_next_ = 0, rec_end_ = 0;
  std::uint64_t rec_prev_stamp_ = 0;
  bool rec_started_ = false;
  std::int64_t last_sample_ns_ = 0;
  sidescan::TrajectorySample traj_sample_{};
  PingMsg pending_{};
  bool has_pending_ = false;  // a slot taken from free_slots but not used (render failed)
  bool stalled(const char* sensor, std::int64_t t_ns) const noexcept;
  bool faulty(const char* kind, std::int64_t t_ns) const noexcept;
  void inject_bus_faults(std::int64_t t_ns) noexcept;
  hal::SimCanNetwork* net_ = nullptr;
  hal::FaultFileStore* store_ = nullptr;
  hal::SimGpioLine* leak_line_ = nullptr;
  bool wet_ = false;
  IoCounters* io_ = nullptr;       // for faults_injected (set by step())
  bool bus_off_ = false;           // can_bus_off: the bus is off; a restart frame follows the window
  std::uint32_t noise_seed_ = 12345;
  void record(const hal::CanFrame& f, std::int64_t t_ns) noexcept;
  std::FILE* candump_ = nullptr;
  FramePool frames_;
  std::unique_ptr<SimRover> rover_;  // created at init when the mission has a simulated vo pass
  std::vector<std::unique_ptr<RecordedSensors>> sensors_;  // one per [[sim.pass]]; null without recorded sensors
  const RecordedSensors* rs_ = nullptr;                   // the pass being flown
  std::size_t can_i_ = 0, dvl_i_ = 0, pair_i_ = 0;
  std::int64_t abs_offset_ns_ = 0, rel_offset_ns_ = 0;   // recorded time -> mission time
  bool replay_attitude_ = false, replay_dvl_ = false;     // the pass's AHRS / DVL come from logs
  bool no_ahrs_ = false;                                   // the simulated AHRS never sends (see init)
  bool no_sim_dvl_ = false;                                // the simulated DVL never sends (see init)
  FrameMsg pending_pair_{};
  bool has_pending_pair_ = false;
  static constexpr std::int64_t kMapFramePeriodNs = 200000000;  // downward frames at 5 Hz (the sparus snippet's rate)
  std::vector<std::vector<std::string>> map_files_;        // per pass: its downward frames (map passes), else empty
  std::vector<std::size_t> map_synthetic_;                 // per pass: frames of the synthetic seabed loop (0 = none)
  std::unique_ptr<sim::downward::Seabed> seabed_;          // the synthetic seabed (built once at init)
  static constexpr int kSeabedFramesPerLap = 90;           // the loop `qnav map eval` flies
  std::size_t map_next_ = 0;
  std::int64_t map_t_ns_ = 0;
  std::int64_t spare_frame_ = -1;  // a frame slot taken from the free queue but not sent
};

}  // namespace qnav::daemon
