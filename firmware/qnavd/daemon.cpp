#include "firmware/qnavd/daemon.hpp"

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <optional>

#include "drivers/camera/leak_monitor.hpp"
#include "drivers/dvl/dvl_driver.hpp"
#include "firmware/qnavd/deployment.hpp"
#include "firmware/qnavd/linux_downward.hpp"
#include "firmware/qnavd/linux_stereo.hpp"
#include "firmware/qnavd/software_fault.hpp"
#include "drivers/sonar_stream/jsf_stream_driver.hpp"
#ifdef QNAV_HAVE_GPIOD
#include "hal/linux/gpiod_line.hpp"
#endif
#include "hal/linux/log_ring.hpp"
#include "hal/linux/monotonic_clock.hpp"
#include "hal/linux/posix_file_store.hpp"
#include "hal/linux/process.hpp"
#include "hal/linux/socketcan_bus.hpp"
#include "hal/linux/tcp_client_port.hpp"
#include "hal/linux/termios_serial.hpp"
#include "hal/sim/clocked_can_link.hpp"
#include "hal/sim/sim_can.hpp"
#include "hal/sim/sim_gpio.hpp"
#include "hal/sim/sim_serial.hpp"

namespace qnav::daemon {

// What the io thread drives: one poll of every device, pushing into the nav worker's queues.
class IoBackend {
 public:
  virtual ~IoBackend() = default;
  // Returns true when something was read or produced; false when the caller may wait.
  virtual bool poll_devices(Daemon& d, IoCounters& io) noexcept = 0;
  // The nav worker and its output queue, once both exist (the sim backend's lockstep between passes).
  virtual void set_worker(const NavWorker*, const SpscRing<hal::CanFrame>*) noexcept {}
  virtual void send(const hal::CanFrame& f, IoCounters& io) noexcept = 0;
  virtual void wait(int timeout_ms) noexcept = 0;
  virtual bool done() const noexcept { return false; }
};

struct QueueRefs {
  SpscRing<PingMsg>* pings;
  SpscRing<std::uint32_t>* free_slots;
  SpscRing<hal::CanRxFrame>* can_rx;
  SpscRing<drivers::dvl::DvlVelocity>* dvl;
  float* pool;
  std::size_t stride;
  FramePool frames;  // stereo pairs and downward frames (queues null when neither vo.enabled nor map_runs)
};

namespace {

using std::chrono::microseconds;

// failed (optional): set when the bus reported an error this call (the device went away).
// dropped_seen: the bus's running count of frames dropped before qnavd read them (the kernel's socket
// queue, SO_RXQ_OVFL; the sim bus's queue) at the last call; 0 again when the bus is reopened.
bool drain_can(hal::CanBus& bus, SpscRing<hal::CanRxFrame>& q, IoCounters& io, std::uint32_t& dropped_seen, bool* failed = nullptr) noexcept {
  bool did = false;
  hal::CanRxFrame rx;
  for (int i = 0; i < 64; ++i) {
    const Status s = bus.receive(rx, 0);
    if (!s) {
      if (s.code() != StatusCode::kTimeout) {
        io.device_errors.fetch_add(1, std::memory_order_relaxed);
        io.can_device_down.store(true);
        if (failed) *failed = true;
      }
      break;
    }
    io.can_device_down.store(false);
    io.can_rx_in.fetch_add(1, std::memory_order_relaxed);
    if (!q.try_push(rx)) io.can_rx_overflow.fetch_add(1, std::memory_order_relaxed);
    did = true;
  }
  const std::uint32_t dropped = bus.stats().rx_dropped;
  if (dropped < dropped_seen) dropped_seen = 0;  // a new socket counts from 0
  if (dropped != dropped_seen) io.can_rx_dropped.fetch_add(dropped - dropped_seen, std::memory_order_relaxed);
  dropped_seen = dropped;
  return did;
}

bool drain_dvl(drivers::dvl::DvlSerialDriver& dvl, SpscRing<drivers::dvl::DvlVelocity>& q, IoCounters& io, std::uint32_t& last_rejects) noexcept {
  bool did = false;
  Result<int> r = dvl.poll(0);
  if (!r) {
    io.device_errors.fetch_add(1, std::memory_order_relaxed);
    io.dvl_device_down.store(true);
    return false;
  }
  io.dvl_device_down.store(false);
  drivers::dvl::DvlVelocity v;
  while (dvl.pop(v)) {
    io.dvl_in.fetch_add(1, std::memory_order_relaxed);
    if (!q.try_push(v)) io.dvl_overflow.fetch_add(1, std::memory_order_relaxed);
    did = true;
  }
  std::uint32_t rej = 0;
  for (std::size_t i = 0; i < static_cast<std::size_t>(drivers::dvl::DvlCounter::kCount); ++i)
    if (static_cast<drivers::dvl::DvlCounter>(i) != drivers::dvl::DvlCounter::kNoLock) rej += dvl.counter(static_cast<drivers::dvl::DvlCounter>(i));
  if (rej != last_rejects) {
    io.dvl_rejected.fetch_add(rej - last_rejects, std::memory_order_relaxed);
    last_rejects = rej;
  }
  return did;
}

// The leak detector's line (either backend): a latched LeakMonitor. Returns true on a new leak.
bool poll_leak(drivers::camera::LeakMonitor& leak, IoCounters& io) noexcept {
  const Result<bool> r = leak.poll(0);
  if (!r) {
    io.device_errors.fetch_add(1, std::memory_order_relaxed);
    io.leak_device_down.store(true);
    return false;
  }
  io.leak_device_down.store(false);
  io.leak_events.store(leak.leak_events(), std::memory_order_relaxed);
  if (leak.fault()) io.leak.store(true);
  return r.value();
}

// ---- sim: the simulated vehicle on in-process buses (or a SocketCAN interface), mission time ----
class SimBackend final : public IoBackend {
 public:
  SimBackend(const DaemonConfig& c, SimClock& clock, hal::Clock& wall, QueueRefs q)
      : cfg_(c), clock_(clock), net_(clock), pipe_(clock), vehicle_(c, clock, wall), dvl_(pipe_.b(), drivers::dvl::DvlProtocol::kWaterLinked), q_(q),
        leak_line_(clock, hal::GpioEdge::kBoth), leak_(leak_line_, true), daemon_node_(daemon_sock_, clock, wall),
        vehicle_node_(vehicle_sock_, clock, wall) {}
  Status init(BusObserver obs, void* ctx, hal::FaultFileStore* store, const FramePool& frames) {
    hal::CanBus* vehicle_bus = &vehicle_bus_;
    if (cfg_.sim_can_interface.empty()) {
      QNAV_RETURN_IF_ERROR(daemon_bus_.attach(net_));
      QNAV_RETURN_IF_ERROR(vehicle_bus_.attach(net_));
      daemon_bus_.set_error_frames(true);  // as the SocketCAN backend subscribes to them
      daemon_can_ = &daemon_bus_;
      vehicle_.set_fault_targets(&net_, store);
    } else {
      // sim.can_interface: both ends on the interface (unfiltered sockets, as the in-process bus),
      // stamped with mission time by the link; the lockstep waits for the kernel's round trip.
      QNAV_RETURN_IF_ERROR(open_interface());
      daemon_node_.link(vehicle_node_);
      daemon_can_ = &daemon_node_;
      vehicle_bus = &vehicle_node_;
      vehicle_.set_fault_targets(nullptr, store);  // no error frames from user space on a real interface
    }
    vehicle_.set_bus_observer(obs, ctx);
    vehicle_.set_frame_pool(frames);
    vehicle_.set_leak_line(&leak_line_);
    QNAV_RETURN_IF_ERROR(leak_.start());
    return vehicle_.init(*vehicle_bus, pipe_.a());
  }
  // The nav worker and its output queue, for the lockstep between passes (SimVehicle::set_worker_caught_up).
  void set_worker(const NavWorker* nav, const SpscRing<hal::CanFrame>* can_tx) noexcept override { nav_ = nav, can_tx_ = can_tx; }
  bool poll_devices(Daemon&, IoCounters& io) noexcept override {
    // Replay paces itself to the nav worker: the vehicle moves on only while the worker keeps up
    // (a recorded dive loses nothing to the speed of the replay).
    bool did = false;
    const std::uint64_t queued = io.can_rx_in.load(std::memory_order_relaxed) + io.dvl_in.load(std::memory_order_relaxed);
    const std::int64_t t_before = clock_.now_ns();
    // On an interface the vehicle moves on only once its frames of the last instant have reached the
    // daemon's socket (in process they arrive as they are sent).
    if (q_.can_rx->size() < kMaxBacklog && q_.dvl->size() < kMaxBacklog && in_flight_to_daemon() == 0) {
      // Caught up: every input queued so far taken, two whole worker steps since the last of them was
      // queued or the clock last moved (one began after it: the worker saw that instant), and the
      // frames those steps published sent to the vehicle (and on an interface, arrived there).
      vehicle_.set_worker_caught_up(nav_ == nullptr || (q_.can_rx->size() == 0 && q_.dvl->size() == 0 && can_tx_->size() == 0 &&
                                                        nav_->progress() >= progress_gate_ && in_flight_to_vehicle() == 0));
      const SimVehicle::StepResult r = vehicle_.step(*q_.free_slots, *q_.pings, q_.pool, q_.stride, io);
      done_ = r == SimVehicle::StepResult::kDone;
      did = r == SimVehicle::StepResult::kProduced;
    }
    const bool moved = clock_.now_ns() != t_before;  // mission time moved: the nav thread has a new instant to see
    did |= moved;
    did |= drain_can(*daemon_can_, *q_.can_rx, io, can_dropped_seen_);
    did |= drain_dvl(dvl_, *q_.dvl, io, dvl_rejects_);
    if (nav_ != nullptr && (moved || io.can_rx_in.load(std::memory_order_relaxed) + io.dvl_in.load(std::memory_order_relaxed) != queued))
      progress_gate_ = nav_->progress() + 2;
    did |= poll_leak(leak_, io);
    if (in_flight_to_daemon() == 0) {  // after the navigation of its instant (on an interface: once it arrived)
      vehicle_.release_ping(*q_.pings, io);
      vehicle_.release_pair(io);
    }
    log_pace(false);
    return did;
  }
  void set_log(FILE* log) noexcept { log_ = log; }
  void send(const hal::CanFrame& f, IoCounters& io) noexcept override {
    if (!daemon_can_->send(f)) io.can_tx_errors.fetch_add(1, std::memory_order_relaxed);
  }
  // Waiting for the lockstep: 50 us. Waiting for a paced step's deadline (sim.speed > 0): a sleep to
  // that absolute deadline, in slices of SimPacer::kPollSliceNs so the daemon's frames still reach the
  // vehicle within a slice.
  void wait(int) noexcept override {
    if (!vehicle_.pacer().sleep(SimPacer::kPollSliceNs)) std::this_thread::sleep_for(microseconds(50));
  }
  bool done() const noexcept override { return done_; }
  const SimVehicle& vehicle() const noexcept { return vehicle_; }

 private:
  // sim.speed > 0: a `sim_pace` line every kPaceLogNs of wall time and one when the mission is done:
  // the pace kept (mission and wall time since the first step), the steps, the late ones.
  static constexpr std::int64_t kPaceLogNs = 10000000000;
  void log_pace(bool force) noexcept {
    const SimPacer& p = vehicle_.pacer();
    if (log_ == nullptr || !p.paced() || !p.started() || pace_logged_at_end_) return;
    const std::int64_t wall_ns = p.wall_elapsed_ns();
    if (!force && !done_ && wall_ns < next_pace_log_ns_) return;
    next_pace_log_ns_ = wall_ns + kPaceLogNs;
    pace_logged_at_end_ = done_;
    std::fprintf(log_,
                 "{\"event\":\"sim_pace\",\"speed\":%g,\"mission_s\":%.3f,\"wall_s\":%.3f,\"steps\":%llu,\"sim_late_steps\":%u,"
                 "\"max_late_ms\":%.2f,\"done\":%s}\n",
                 p.speed(), static_cast<double>(clock_.now_ns() - p.mission_start_ns()) * 1e-9, static_cast<double>(wall_ns) * 1e-9,
                 static_cast<unsigned long long>(p.steps()), p.late_steps(), static_cast<double>(p.max_late_ns()) * 1e-6,
                 done_ ? "true" : "false");
  }
  FILE* log_ = nullptr;
  std::int64_t next_pace_log_ns_ = kPaceLogNs;
  bool pace_logged_at_end_ = false;
  // sim.can_interface: one socket for each end; a missing interface is a start-up error that names it.
  Status open_interface() noexcept {
    hal::SocketCanConfig sc;
    sc.interface = cfg_.sim_can_interface.c_str();
    Status s = daemon_sock_.open(sc);  // error frames as the linux backend subscribes to them
    if (s) {
      sc.error_mask = 0;  // the simulated autopilot, as on the in-process bus, reads no error frames
      s = vehicle_sock_.open(sc);
    }
    if (s) return s;
    std::fprintf(stderr, "qnavd: sim.can_interface \"%s\": %s (a virtual one: modprobe vcan; ip link add %s type vcan; ip link set up %s)\n",
                 sc.interface, s.message(), sc.interface, sc.interface);
    return Status(s.code() == StatusCode::kNotFound ? StatusCode::kNotFound : StatusCode::kIoError,
                  "sim.can_interface: the CAN interface cannot be opened (see the line above)");
  }
  std::size_t in_flight_to_daemon() noexcept { return daemon_can_ == &daemon_node_ ? daemon_node_.in_flight() : 0; }
  std::size_t in_flight_to_vehicle() noexcept { return daemon_can_ == &daemon_node_ ? vehicle_node_.in_flight() : 0; }
  const DaemonConfig& cfg_;
  static constexpr std::size_t kMaxBacklog = 8;
  const SimClock& clock_;
  hal::SimCanNetwork net_;
  hal::SimCanBus daemon_bus_, vehicle_bus_;
  hal::SimSerialPipe pipe_;
  SimVehicle vehicle_;
  drivers::dvl::DvlSerialDriver dvl_;
  QueueRefs q_;
  hal::SimGpioLine leak_line_;  // the simulated leak detector (sim.fault = "leak" wets it)
  drivers::camera::LeakMonitor leak_;
  hal::SocketCanBus daemon_sock_, vehicle_sock_;      // sim.can_interface: the two ends on the interface
  hal::ClockedCanNode daemon_node_, vehicle_node_;    // ... stamped with mission time, counted in flight
  hal::CanBus* daemon_can_ = &daemon_bus_;            // what qnavd's side reads and sends on
  std::uint32_t dvl_rejects_ = 0;
  std::uint32_t can_dropped_seen_ = 0;
  bool done_ = false;
  const NavWorker* nav_ = nullptr;
  const SpscRing<hal::CanFrame>* can_tx_ = nullptr;
  std::uint64_t progress_gate_ = 0;
};

// ---- linux: SocketCAN, termios DVL, JSF over TCP; reopened once a second when they fail ----
class LinuxBackend final : public IoBackend {
 public:
  LinuxBackend(const DaemonConfig& c, const hal::Clock& clock, QueueRefs q, FILE* log)
      : cfg_(c), clock_(clock), q_(q), log_(log), dvl_(dvl_port_, c.dvl_protocol == "pd6" ? drivers::dvl::DvlProtocol::kPd6 : drivers::dvl::DvlProtocol::kWaterLinked) {}
  Status init() {
    drivers::sonar_stream::JsfStreamConfig jc;
    jc.max_samples_per_side = cfg_.max_samples_per_side;
    QNAV_RETURN_IF_ERROR(jsf_.init(jc));
    const char* colon = std::strrchr(cfg_.sonar_address.c_str(), ':');
    if (colon == nullptr) return Status(StatusCode::kInvalidArgument, "sonar.address must be host:port");
    const std::size_t n = static_cast<std::size_t>(colon - cfg_.sonar_address.c_str());
    if (n >= sizeof sonar_host_) return Status(StatusCode::kInvalidArgument, "sonar.address host too long");
    std::memcpy(sonar_host_, cfg_.sonar_address.c_str(), n);
    char* end = nullptr;
    const long port = std::strtol(colon + 1, &end, 10);
    if (end == colon + 1 || *end != '\0' || port < 1 || port > 65535)
      return Status(StatusCode::kInvalidArgument, "sonar.address port must be a number in 1..65535");
    sonar_port_ = static_cast<std::uint16_t>(port);
    if (cfg_.vo_enabled) stereo_ = std::make_unique<LinuxStereoSource>(cfg_, q_.frames, log_);
    if (map_runs(cfg_)) downward_ = std::make_unique<LinuxDownwardSource>(cfg_, q_.frames, log_);  // map.device
    // The leak detector is opened here and, when that fails, retried once a second like the other
    // devices (leak_device_down, FaultSensorTimeout meanwhile).
    // The CAN interface must exist at start: without it the daemon cannot talk to the autopilot.
    return open_can(true);
  }
  bool poll_devices(Daemon&, IoCounters& io) noexcept override {
    const std::int64_t now = clock_.now_ns();
    if (now >= next_retry_ns_) {
      if (!can_.is_open() && open_can(false)) io.can_device_down.store(false);
      if (cfg_.dvl_enabled && !dvl_port_.is_open()) open_dvl();
      if (!sonar_.is_open()) open_sonar();
      if (!cfg_.leak_chip.empty() && !leak_open_) open_leak(io);
      next_retry_ns_ = now + 1000000000;
    }
    bool did = false;
    if (can_.is_open()) {
      bool failed = false;
      did |= drain_can(can_, *q_.can_rx, io, can_dropped_seen_, &failed);
      if (failed) can_.close();  // reopened within a second
    }
    if (dvl_port_.is_open()) {
      did |= drain_dvl(dvl_, *q_.dvl, io, dvl_rejects_);
      if (io.dvl_device_down.load()) dvl_port_.close();  // this poll failed; reopened within a second
    }
    if (sonar_.is_open()) {
      io_ = &io;
      Result<int> r = jsf_.poll(sonar_, 0, &LinuxBackend::on_ping, this);
      if (!r) {
        io.device_errors.fetch_add(1, std::memory_order_relaxed);
        io.sonar_device_down.store(true);
        sonar_.close();
      } else {
        io.sonar_device_down.store(false);
        did |= *r > 0;
      }
      // Rejected: bytes skipped to resynchronise, bad headers, undecodable or unpaired sonar messages.
      // Not rejected: the messages delivered, and other message types or subsystems, which a
      // topside's stream carries as a matter of course (found by the HIL bench's mission scenario:
      // every delivered message was counted here, two per ping, into HEALTH RejectedInputs).
      using sidescan::JsfCounter;
      using sidescan::JsfPingCounter;
      const auto& fc = jsf_.framer_counters();
      const auto& pc = jsf_.ping_counters();
      const std::uint32_t rej = fc.get(JsfCounter::kResyncBytes) + fc.get(JsfCounter::kBadHeader) + fc.get(JsfCounter::kOversize) +
                                pc.get(JsfPingCounter::kBadSonarMessage) + pc.get(JsfPingCounter::kUnpairedChannel);
      if (rej != sonar_rejects_) {
        io.sonar_rejected.fetch_add(rej - sonar_rejects_, std::memory_order_relaxed);
        sonar_rejects_ = rej;
      }
    }
    if (stereo_) did |= stereo_->poll(now, io);
    if (downward_) did |= downward_->poll(now, io);
#ifdef QNAV_HAVE_GPIOD
    if (leak_open_) {
      did |= poll_leak(*leak_, io);
      if (io.leak_device_down.load()) close_leak();  // reopened within a second
    }
#endif
    return did;
  }
  void send(const hal::CanFrame& f, IoCounters& io) noexcept override {
    if (!can_.is_open() || !can_.send(f)) io.can_tx_errors.fetch_add(1, std::memory_order_relaxed);
  }
  void wait(int timeout_ms) noexcept override {
    int leak_fd = -1;
#ifdef QNAV_HAVE_GPIOD
    if (leak_open_) leak_fd = leak_line_.fd();
#endif
    const int fds[7] = {can_.fd(),  dvl_port_.fd(), sonar_.fd(), stereo_ ? stereo_->left_fd() : -1, stereo_ ? stereo_->right_fd() : -1,
                        leak_fd, downward_ ? downward_->fd() : -1};
    hal::wait_readable(fds, 7, timeout_ms);
  }

 private:
  // The leak detector's line: both edges, the active level from leak.active_low; a level already
  // active when it opens latches the leak at once.
  void open_leak(IoCounters& io) noexcept {
#ifdef QNAV_HAVE_GPIOD
    hal::GpioLineConfig gc;
    gc.chip = cfg_.leak_chip.c_str();
    gc.offset = static_cast<unsigned>(cfg_.leak_line);
    gc.active_low = cfg_.leak_active_low;
    gc.consumer = "qnavd-leak";
    Status s = leak_line_.open(gc, hal::GpioEdge::kBoth);
    if (s) {
      leak_.emplace(leak_line_, true);
      s = leak_->start();
      if (s && leak_->fault()) io.leak.store(true);
    }
    leak_open_ = s.is_ok();
    if (!s) leak_line_.close();
    const char* why = s ? "" : s.message();
#else
    const char* why = "this build has no libgpiod: the leak line cannot be read";
#endif
    io.leak_device_down.store(!leak_open_);
    if (!leak_open_) io.device_errors.fetch_add(1, std::memory_order_relaxed);
    if (!leak_open_ && log_ && !leak_warned_)
      std::fprintf(log_, "{\"event\":\"device\",\"device\":\"%s line %d\",\"error\":\"%s\"}\n", cfg_.leak_chip.c_str(), cfg_.leak_line, why);
    leak_warned_ = !leak_open_;
  }
#ifdef QNAV_HAVE_GPIOD
  void close_leak() noexcept {
    leak_.reset();
    leak_line_.close();
    leak_open_ = false;
  }
#endif
  Status open_can(bool report) noexcept {
    hal::SocketCanConfig sc;
    sc.interface = cfg_.can_interface.c_str();
    // The kernel passes only what qnav reads: its inputs (0x100-0x10F attitude, rates, depth; 0x110
    // mode command) and DroneCAN AHRS Solution messages (29-bit, data type 1000 in bits 8..23).
    hal::CanFilter inputs;
    inputs.id = 0x100;
    inputs.mask = 0x7F0;
    hal::CanFilter mode;
    mode.id = drivers::qnavcan::kIdModeCmd;
    mode.mask = hal::kCanSffMask;
    hal::CanFilter ahrs;
    ahrs.id = 1000u << 8;
    ahrs.mask = 0xFFFFu << 8;
    ahrs.extended = true;
    static_cast<void>(sc.filters.push_back(inputs));
    static_cast<void>(sc.filters.push_back(mode));
    static_cast<void>(sc.filters.push_back(ahrs));
    can_dropped_seen_ = 0;
    const Status s = can_.open(sc);
    if (!s && report && log_) std::fprintf(log_, "{\"event\":\"device\",\"device\":\"%s\",\"error\":\"%s\"}\n", sc.interface, s.message());
    return s;
  }
  void open_dvl() noexcept {
    hal::SerialConfig sc;
    sc.baud = static_cast<std::uint32_t>(cfg_.dvl_baud);
    const Status s = dvl_port_.open(cfg_.dvl_device.c_str(), sc);
    if (!s && log_ && !dvl_warned_) std::fprintf(log_, "{\"event\":\"device\",\"device\":\"%s\",\"error\":\"%s\"}\n", cfg_.dvl_device.c_str(), s.message());
    dvl_warned_ = !s;
  }
  // Never waits: a connection started here is finished at the next retry (a second later), or
  // abandoned and started again when it is still in progress then (a topside that does not answer).
  void open_sonar() noexcept {
    Status s = sonar_.connecting() ? sonar_.poll_connect() : sonar_.begin_connect(sonar_host_, sonar_port_);
    if (s.code() == StatusCode::kNotReady && sonar_.connecting() && connect_started_) {
      s = Status(StatusCode::kTimeout, "TCP connect: no answer within a second");
      sonar_.close();
    }
    connect_started_ = sonar_.connecting();
    if (connect_started_) return;
    if (!s && log_ && !sonar_warned_) std::fprintf(log_, "{\"event\":\"device\",\"device\":\"%s\",\"error\":\"%s\"}\n", cfg_.sonar_address.c_str(), s.message());
    sonar_warned_ = !s;
  }
  static void on_ping(void* ctx, const sonar::SonarPing& ping, const hal::SampleStamp& stamp) {
    auto* self = static_cast<LinuxBackend*>(ctx);
    IoCounters& io = *self->io_;
    std::uint32_t slot = 0;
    const std::size_t half = self->q_.stride / 2;
    io.pings_in.fetch_add(1, std::memory_order_relaxed);
    if (ping.port.size() > half || ping.stbd.size() > half) {
      io.sonar_rejected.fetch_add(1, std::memory_order_relaxed);
      return;
    }
    if (!self->q_.free_slots->try_pop(slot)) {  // the nav worker is behind: drop, count, never block
      io.ping_overflow.fetch_add(1, std::memory_order_relaxed);
      return;
    }
    float* port = self->q_.pool + static_cast<std::size_t>(slot) * self->q_.stride;
    std::memcpy(port, ping.port.data(), ping.port.size() * sizeof(float));
    std::memcpy(port + half, ping.stbd.data(), ping.stbd.size() * sizeof(float));
    PingMsg m;
    m.slot = slot;
    m.ping_number = ping.ping_number;
    m.port_samples = static_cast<std::uint32_t>(ping.port.size());
    m.stbd_samples = static_cast<std::uint32_t>(ping.stbd.size());
    m.slant_range_m = ping.slant_range_m;
    m.altitude_m = ping.altitude_m;
    m.device_stamp_ns = ping.stamp_ns;
    m.stamp = stamp;
    if (!self->q_.pings->try_push(m)) io.ping_overflow.fetch_add(1, std::memory_order_relaxed);  // cannot happen: one slot per entry
  }

  const DaemonConfig& cfg_;
  const hal::Clock& clock_;
  QueueRefs q_;
  FILE* log_;
  hal::SocketCanBus can_;
  hal::TermiosSerialPort dvl_port_;
  drivers::dvl::DvlSerialDriver dvl_;
  hal::TcpClientPort sonar_;
  drivers::sonar_stream::JsfStreamDriver jsf_;
  char sonar_host_[64] = {};
  std::uint16_t sonar_port_ = 0;
  IoCounters* io_ = nullptr;
  std::int64_t next_retry_ns_ = 0;
  std::uint32_t dvl_rejects_ = 0, sonar_rejects_ = 0;
  std::uint32_t can_dropped_seen_ = 0;
  bool dvl_warned_ = false, sonar_warned_ = false;
  bool connect_started_ = false;  // the sonar's connect was in progress at the last retry
  std::unique_ptr<LinuxStereoSource> stereo_;  // vo.enabled: the V4L2 pair
  std::unique_ptr<LinuxDownwardSource> downward_;  // map.enabled with map.device: the downward V4L2 camera
#ifdef QNAV_HAVE_GPIOD
  hal::GpiodInputLine leak_line_;
  std::optional<drivers::camera::LeakMonitor> leak_;
#endif
  bool leak_open_ = false, leak_warned_ = false;
};

template <typename T>
Status make_ring(std::vector<T>& store, SpscRing<T>& ring, std::size_t depth) {
  store.assign(depth, T{});
  return ring.init(Span<T>(store.data(), store.size()));
}

}  // namespace

Daemon::Daemon(const DaemonConfig& config) : cfg_(config) {}

Daemon::~Daemon() {
  stop();
  io_exit_.store(true);  // a started daemon destroyed without run() must not hang in join
  if (io_thread_.joinable()) io_thread_.join();
  if (nav_thread_.joinable()) nav_thread_.join();
  if (nav_) nav_->shutdown();  // a daemon destroyed without run(): the route closed, its lines logged
  flush_logs(true);
}

// Main thread: the rings' lines to the log's descriptor, without blocking (what the descriptor does
// not take now stays for the next call; `final` waits for it, bounded by daemon.shutdown_timeout_s).
// A change in the dropped-line count is reported.
void Daemon::flush_logs(bool final) noexcept {
  if (log_ == nullptr || !nav_log_) return;
  std::fflush(log_);
  const int fd = fileno(log_);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(static_cast<long>(cfg_.shutdown_timeout_s * 1000));
  for (;;) {
    if (final) {
      // The threads have stopped: a line they left unfinished goes out too. (While they run, their
      // streams are line-buffered and hand over every finished line themselves; flushing here would
      // make a realtime thread wait for this one on the stream's lock.)
      std::fflush(nav_log_->stream());
      std::fflush(io_log_->stream());
    }
    io_log_->drain(fd);
    nav_log_->drain(fd);
    if (!final || (nav_log_->pending() == 0 && io_log_->pending() == 0) || std::chrono::steady_clock::now() > deadline) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  const std::uint64_t dropped = nav_log_->dropped_lines() + io_log_->dropped_lines();
  if (dropped != log_dropped_reported_) {
    std::fprintf(log_, "{\"event\":\"log_dropped\",\"lines\":%llu}\n", static_cast<unsigned long long>(dropped));
    std::fflush(log_);
    log_dropped_reported_ = dropped;
  }
}

const hal::Clock& Daemon::sample_clock() const noexcept {
  if (sim_clock_) return *sim_clock_;
  return *wall_;
}

Status Daemon::init(FILE* log) {
  log_ = log;
  if (log_ != nullptr) {
    // The io and nav threads log through rings the main thread drains: a slow or full log pipe
    // (journald) costs lines (counted), never a deadline.
    nav_log_ = std::make_unique<hal::LogRing>();
    io_log_ = std::make_unique<hal::LogRing>();
    QNAV_RETURN_IF_ERROR(nav_log_->open(kNavLogBytes));
    QNAV_RETURN_IF_ERROR(io_log_->open(kIoLogBytes));
  }
  const Status s = init_pipeline();
  flush_logs();
  return s;
}

Status Daemon::init_pipeline() {
  wall_ = std::make_unique<hal::MonotonicClock>();
  if (cfg_.backend == Backend::kSim) sim_clock_ = std::make_unique<SimClock>();
  stride_ = 2 * cfg_.max_samples_per_side;
  pool_.assign(cfg_.ping_queue * stride_, 0.0f);
  QNAV_RETURN_IF_ERROR(make_ring(ping_store_, pings_, cfg_.ping_queue));
  QNAV_RETURN_IF_ERROR(make_ring(free_store_, free_slots_, cfg_.ping_queue));
  QNAV_RETURN_IF_ERROR(make_ring(can_rx_store_, can_rx_, cfg_.can_rx_queue));
  QNAV_RETURN_IF_ERROR(make_ring(can_tx_store_, can_tx_, cfg_.can_tx_queue));
  QNAV_RETURN_IF_ERROR(make_ring(dvl_store_, dvl_q_, kDvlQueueCapacity));
  for (std::uint32_t s = 0; s < cfg_.ping_queue; ++s) QNAV_RETURN_IF_ERROR(free_slots_.try_push(s));
  FramePool fp;
  if (cfg_.vo_enabled || map_runs(cfg_)) {
    const std::size_t slots = frame_pool_slots(cfg_);
    fp.width = cfg_.vo.max_width;
    fp.height = cfg_.vo.max_height;
    fp.map_width = cfg_.map_width;
    fp.map_height = cfg_.map_height;
    fp.slot_bytes = frame_slot_bytes(cfg_);
    frame_pool_.assign(slots * fp.slot_bytes, 0);
    QNAV_RETURN_IF_ERROR(make_ring(frame_store_, frames_, slots));
    QNAV_RETURN_IF_ERROR(make_ring(free_frame_store_, free_frames_, slots));
    for (std::uint32_t s = 0; s < slots; ++s) QNAV_RETURN_IF_ERROR(free_frames_.try_push(s));
    fp.frames = &frames_;
    fp.free = &free_frames_;
    fp.pool = frame_pool_.data();
  }
  const QueueRefs refs{&pings_, &free_slots_, &can_rx_, &dvl_q_, pool_.data(), stride_, fp};
  if (cfg_.backend == Backend::kSim) {
    auto sim = std::make_unique<SimBackend>(cfg_, *sim_clock_, *wall_, refs);
    // The route store behind a switch that can make the disk full (sim.fault = "disk_full").
    fault_store_ = std::make_unique<hal::FaultFileStore>(hal::host_file_store());
    QNAV_RETURN_IF_ERROR(sim->init(bus_observer_, bus_ctx_, fault_store_.get(), refs.frames));
    sim->set_log(io_log_ ? io_log_->stream() : nullptr);
    double range_m = 0.0;
    if (sim->vehicle().recorded_geometry(range_m, route_spacing_m_)) {
      // Recorded passes: tiles and registration as `qnav route train|repeat --sonar` sets them for
      // the file (pipeline/route_defaults), the route header's spacing and swath from the file.
      cfg_.tiles = pipeline::file_route_tile_config(range_m, cfg_.sim_replay_lines, cfg_.sim_replay_stride);
      cfg_.tiles.corrector.max_samples_per_side = cfg_.max_samples_per_side;
      cfg_.localiser = pipeline::file_localiser_config(route::RouteDirection::kForward, cfg_.max_nodes, 8, route_spacing_m_);
      cfg_.localiser.window_slots = std::max<std::size_t>(cfg_.localiser.window_slots, cfg_.localiser.filter.max_registrations() + 1u);
      route_swath_m_ = 2.0 * range_m;
    } else {
      route_spacing_m_ = sim->vehicle().node_spacing_m(cfg_.tiles.tiles.scanline_stride);
      route_swath_m_ = sim->vehicle().swath_m();
    }
    backend_ = std::move(sim);
    // Paced (sim.speed > 0): a quarter of a handshake tick's wall time (10 ms of mission time), 200 us
    // to 2 ms, so the lockstep between passes keeps the pace and an idle worker does not spin at 1x.
    nav_idle_wait_us_ = cfg_.sim_speed > 0.0 ? std::clamp(static_cast<long>(2500.0 / cfg_.sim_speed), 200L, 2000L) : 200;
  } else {
    auto lb = std::make_unique<LinuxBackend>(cfg_, *wall_, refs, io_log_ ? io_log_->stream() : nullptr);
    QNAV_RETURN_IF_ERROR(lb->init());
    backend_ = std::move(lb);
  }
  QNAV_RETURN_IF_ERROR(hal::ensure_dir(cfg_.route_dir.c_str()));
  hal::FileStore& store = fault_store_ ? static_cast<hal::FileStore&>(*fault_store_) : hal::host_file_store();
  nav_ = std::make_unique<NavWorker>(cfg_, sample_clock(), *wall_, store);
  nav_->set_route_geometry(route_spacing_m_, route_swath_m_);
  NavQueues nq;
  nq.pings = &pings_;
  nq.free_slots = &free_slots_;
  nq.can_rx = &can_rx_;
  nq.can_tx = &can_tx_;
  nq.dvl = &dvl_q_;
  nq.ping_pool = pool_.data();
  nq.ping_pool_stride = stride_;
  nq.io = &io_;
  nq.frames = fp.frames;
  nq.free_frames = fp.free;
  nq.frame_pool = fp.pool;
  nq.frame_slot_bytes = fp.slot_bytes;
  nav_->set_frame_observer(frame_observer_, frame_ctx_);
  backend_->set_worker(nav_.get(), &can_tx_);
  return nav_->init(nq, tile_observer_, tile_ctx_, nav_log_ ? nav_log_->stream() : nullptr);
}

void Daemon::io_loop() noexcept {
  if (cfg_.realtime) {
    const Status s = hal::set_thread_realtime(cfg_.io_priority, cfg_.io_cpu);
    if (!s && io_log_) std::fprintf(io_log_->stream(), "{\"event\":\"warning\",\"thread\":\"io\",\"what\":\"realtime not set: %s\"}\n", s.message());
  }
  while (!io_exit_.load(std::memory_order_relaxed)) {
    bool did = backend_->poll_devices(*this, io_);
    if (did) {
      {
        const std::lock_guard<std::mutex> lock(bell_mu_);
        bell_ = true;
      }
      bell_cv_.notify_one();
    }
    hal::CanFrame f;
    while (can_tx_.try_pop(f)) {
      backend_->send(f, io_);
      did = true;
    }
    if (backend_->done()) mission_done_.store(true);
    if (!did) backend_->wait(5);
  }
}

void Daemon::nav_loop() noexcept {
  if (cfg_.realtime) {
    const Status s = hal::set_thread_realtime(cfg_.nav_priority, cfg_.nav_cpu);
    if (!s && nav_log_) std::fprintf(nav_log_->stream(), "{\"event\":\"warning\",\"thread\":\"nav\",\"what\":\"realtime not set: %s\"}\n", s.message());
  }
  while (!stop_.load(std::memory_order_relaxed)) {
    if (nav_->run_once()) continue;
    std::unique_lock<std::mutex> lock(bell_mu_);
    bell_cv_.wait_for(lock, microseconds(nav_idle_wait_us_), [this] { return bell_ || stop_.load(std::memory_order_relaxed); });
    bell_ = false;
  }
  nav_->shutdown();  // the node in progress finished or discarded, the route closed and fsynced
  nav_exited_.store(true);
}

Status Daemon::start() {
  if (!nav_) return Status(StatusCode::kNotReady, "daemon: start() before init()");
  if (cfg_.realtime) {
    const Status s = hal::lock_memory();
    if (!s && log_) std::fprintf(log_, "{\"event\":\"warning\",\"what\":\"memory not locked: %s\"}\n", s.message());
  }
  started_wall_ns_ = wall_->now_ns();
  if (log_ && cfg_.log != LogFormat::kOff) {
    const Deployment d = make_deployment(cfg_);
    std::fprintf(log_,
                 "{\"event\":\"started\",\"backend\":\"%s\",\"route_dir\":\"%s\",\"static_bytes\":%zu,\"ping_queue\":%zu,"
                 "\"can_interface\":\"%s\",\"realtime\":%s}\n",
                 cfg_.backend == Backend::kSim ? "sim" : "linux", cfg_.route_dir.c_str(), d.total_static_bytes(), cfg_.ping_queue,
                 cfg_.can_interface.c_str(), cfg_.realtime ? "true" : "false");
    std::fflush(log_);
  }
  io_thread_ = std::thread([this] { io_loop(); });
  nav_thread_ = std::thread([this] { nav_loop(); });
  return Status::ok();
}

int Daemon::run() {
  hal::ServiceNotifier notifier;
  notifier.notify("READY=1\nSTATUS=navigating").ignore();
  const std::uint64_t wd_us = notifier.watchdog_usec();
  std::uint64_t last_progress = nav_->progress();
  auto next_pet = std::chrono::steady_clock::now();
  while (!stop_.load() && !hal::StopSignals::requested() && !(cfg_.backend == Backend::kSim && cfg_.sim_exit_at_end && mission_done_.load())) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    flush_logs();
    if (wd_us > 0 && std::chrono::steady_clock::now() >= next_pet) {
      // Pet the watchdog only when the nav worker made progress since the last pet.
      const std::uint64_t p = nav_->progress();
      if (p != last_progress) notifier.notify("WATCHDOG=1").ignore();
      last_progress = p;
      next_pet = std::chrono::steady_clock::now() + microseconds(wd_us / 2);
    }
  }
  notifier.notify("STOPPING=1").ignore();
  stop_.store(true);
  // Bounded shutdown: the nav worker finishes its step and closes the route; the io thread keeps
  // draining (the last outputs) until then.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(static_cast<long>(cfg_.shutdown_timeout_s * 1000));
  while (!nav_exited_.load() && std::chrono::steady_clock::now() < deadline) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  io_exit_.store(true);
  if (io_thread_.joinable()) io_thread_.join();
  if (!nav_exited_.load()) {
    // The nav thread is stuck (storage hung in the final commit?). Everything taught up to the node in
    // progress is fdatasync'ed under .new; leave now, without running destructors under its feet.
    if (log_) {
      std::fprintf(log_, "{\"event\":\"error\",\"what\":\"nav worker did not stop within %.1f s; exiting\"}\n", cfg_.shutdown_timeout_s);
      std::fflush(log_);
    }
    flush_logs();
    hal::exit_now(1);
  }
  if (nav_thread_.joinable()) nav_thread_.join();
  flush_logs(true);
  const int sig = hal::StopSignals::signal_number();
  if (log_) {
    const hal::ProcessUsage u = hal::process_usage();
    const double wall_s = static_cast<double>(wall_->now_ns() - started_wall_ns_) * 1e-9;
    std::fprintf(log_,
                 "{\"event\":\"stopped\",\"signal\":%d,\"mission_done\":%s,\"wall_s\":%.2f,\"cpu_s\":%.2f,\"cpu_load_pct\":%.1f,"
                 "\"max_rss_kb\":%ld,\"tiles\":%u,\"deadline_misses\":%u,\"software_faults\":%u,\"writer_errors\":%u,\"route_committed\":%s}\n",
                 sig, mission_done_.load() ? "true" : "false", wall_s, u.cpu_s, wall_s > 0 ? 100.0 * u.cpu_s / wall_s : 0.0, u.max_rss_kb,
                 nav_->tiles(), nav_->deadline_misses(), SoftwareFaults::count(), nav_->writer_errors(),
                 nav_->commit_failed() ? "false" : "true");
    std::fflush(log_);
  }
  return nav_->commit_failed() ? 1 : 0;  // a route that could not be committed is not a clean stop
}

}  // namespace qnav::daemon
