// SimSensors: the sim vehicle's navigation sensors on the daemon's buses, and the faults injected
// into them (part of SimVehicle, sim_vehicle.hpp; driven by the io thread only).
//   - the AHRS on the CAN bus: QNAV_ATTITUDE_IN with the compass heading (or, sim.ahrs = "dronecan",
//     a DroneCAN ahrs.Solution from node 42), at most one sample per instant of mission time;
//   - the DVL on an in-process serial line: Water Linked "wrz" sentences (real checksums) with the
//     body velocities it is given, parsed by the real driver;
//   - a recorded pass's CAN frames and DVL reports, played as they were logged (sim_replay.hpp);
//   - sim.candump: every frame on the bus in candump -l format (`qnav can decode` reads it);
//   - the fault windows of a pass (sim.stall: a sensor falls silent; sim.fault: damaged or
//     disordered input, CAN error frames and bus-off, a wet leak line, a full disk). Every injected
//     sample is counted in IoCounters::faults_injected.
// Owns: the candump file (opened at init); the bus, the DVL line and the fault targets are the
// caller's. Memory: no heap after init. Time: O(1) per sample (a DroneCAN solution: 16 frames at most).
#pragma once

#include <cstdint>
#include <cstdio>

#include "firmware/pipeline/sim_survey.hpp"
#include "firmware/qnavd/config.hpp"
#include "firmware/qnavd/messages.hpp"
#include "firmware/qnavd/sim_pacer.hpp"
#include "hal/core/can.hpp"
#include "hal/core/serial.hpp"
#include "hal/sim/fault_file_store.hpp"
#include "hal/sim/sim_can.hpp"
#include "hal/sim/sim_gpio.hpp"
#include "nav/core/geometry.hpp"

namespace qnav::tools {
struct PingRec;
}

namespace qnav::daemon {

// What a step of the sim vehicle did (SimVehicle::step and its parts).
enum class SimStep : std::uint8_t { kProduced, kWaiting, kDone };

// A pass's first sample comes this long after its mode command.
constexpr std::int64_t kSimPassLeadNs = 200000000;

// One ping instant of a pass, simulated or recorded: the navigation the sensors report at it, the
// ping's identity and its truth.
struct SimSample {
  std::int64_t t_ns = 0;
  Pose2 nav{};
  std::uint32_t ping_number = 0;
  std::uint64_t device_stamp_ns = 0;
  float altitude_m = -1.0f;
  bool has_truth = false;
  pipeline::PingTruth truth;
  const tools::PingRec* recorded = nullptr;
};

class SimSensors {
 public:
  SimSensors(const DaemonConfig& config, SimClock& clock) noexcept : cfg_(config), clock_(clock) {}
  ~SimSensors();
  SimSensors(const SimSensors&) = delete;
  SimSensors& operator=(const SimSensors&) = delete;
  // bus: the vehicle's node on the daemon's CAN bus; dvl: the DVL's end of the serial line. Opens
  // sim.candump.
  Status init(hal::CanBus& bus, hal::SerialPort& dvl);
  // The simulated AHRS never sends (a stereo sequence replayed without its CAN log: a rig without an
  // attitude sensor).
  void set_no_ahrs() noexcept { no_ahrs_ = true; }
  void set_fault_targets(hal::SimCanNetwork* net, hal::FaultFileStore* store) noexcept { net_ = net, store_ = store; }
  void set_leak_line(hal::SimGpioLine* line) noexcept { leak_line_ = line; }
  void set_counters(IoCounters* io) noexcept { io_ = io; }
  hal::FaultFileStore* store() const noexcept { return store_; }
  hal::CanBus& bus() noexcept { return *bus_; }
  // The pass the fault windows are measured in (its index, its start) and whether it is flying
  // (out of the flight no sim.fault window is open; sim.stall windows are).
  void set_pass(std::uint32_t pass, std::int64_t start_ns) noexcept { pass_ = pass, pass_start_ns_ = start_ns; }
  void set_flying(bool flying) noexcept { flying_ = flying; }
  // The altitude the DVL reports (the simulated pass's).
  void set_dvl_altitude(double altitude_m) noexcept { dvl_altitude_m_ = altitude_m; }

  bool stalled(const char* sensor, std::int64_t t_ns) const noexcept;
  bool faulty(const char* kind, std::int64_t t_ns) const noexcept;
  // Once per instant: error frames on the bus, bus-off and its restart, the leak, the disk filling up.
  void inject_bus_faults(std::int64_t t_ns) noexcept;
  // A frame on the bus, into sim.candump.
  void record(const hal::CanFrame& f, std::int64_t t_ns) noexcept;
  // The AHRS at the clock's time (heading wrapped into [0, 2 pi)).
  void send_attitude(double heading_rad, double roll_rad = 0.0, double pitch_rad = 0.0) noexcept;
  double last_heading() const noexcept { return last_heading_; }
  // The DVL's body velocities at t_ns (its time of validity strictly increases).
  void send_dvl(double fwd_mps, double stbd_mps, std::int64_t t_ns) noexcept;
  // A recorded pass: a logged CAN frame (an error frame goes onto the network) and a DVL report.
  void replay_can(const hal::CanFrame& f, std::int64_t t_ns) noexcept;
  void replay_dvl(const char* text, std::size_t length, std::int64_t t_ns) noexcept;

 private:
  void count_fault() noexcept { io_->faults_injected.fetch_add(1, std::memory_order_relaxed); }

  const DaemonConfig& cfg_;
  SimClock& clock_;
  hal::CanBus* bus_ = nullptr;
  hal::SerialPort* dvl_ = nullptr;
  std::FILE* candump_ = nullptr;
  hal::SimCanNetwork* net_ = nullptr;
  hal::FaultFileStore* store_ = nullptr;
  hal::SimGpioLine* leak_line_ = nullptr;
  IoCounters* io_ = nullptr;  // for faults_injected (set by SimVehicle::step)
  std::uint32_t pass_ = 0;
  std::int64_t pass_start_ns_ = 0;
  bool flying_ = false;
  bool no_ahrs_ = false;
  bool wet_ = false;
  bool bus_off_ = false;  // can_bus_off: the bus is off; a restart frame follows the window
  std::uint8_t att_counter_ = 0;
  double last_heading_ = 0.0;
  std::int64_t last_att_ns_ = -1;
  std::int64_t last_tov_us_ = 0;
  double dvl_altitude_m_ = 0.0;
  std::uint32_t noise_seed_ = 12345;
};

}  // namespace qnav::daemon
