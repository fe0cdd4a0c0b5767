#include "firmware/qnavd/daemon.hpp"

#include "nav/core/assert.hpp"

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <optional>

#include "drivers/camera/leak_monitor.hpp"
#include "drivers/dvl/dvl_driver.hpp"
#include "firmware/qnavd/deployment.hpp"
#include "firmware/qnavd/io_backend.hpp"
#include "firmware/qnavd/linux_downward.hpp"
#include "firmware/qnavd/linux_stereo.hpp"
#include "firmware/qnavd/mavlink_key.hpp"
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

namespace qnav::daemon {

namespace {

using std::chrono::microseconds;

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
  // The MAVLink links, so that their traffic wakes the io thread too (mavlink.enabled).
  void set_mavlink(const MavlinkIo* m) noexcept { mav_ = m; }
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
    int mav[3] = {-1, -1, -1};
    if (mav_ != nullptr) mav_->fds(mav);
    const int fds[10] = {can_.fd(),  dvl_port_.fd(), sonar_.fd(), stereo_ ? stereo_->left_fd() : -1, stereo_ ? stereo_->right_fd() : -1,
                         leak_fd, downward_ ? downward_->fd() : -1, mav[0], mav[1], mav[2]};
    hal::wait_readable(fds, 10, timeout_ms);
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
  const MavlinkIo* mav_ = nullptr;
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

// A queue's ring over its buffer in the static block (deployment.hpp names it "queue.<name>").
template <typename T>
Status make_ring(StaticMemory& mem, const char* queue, SpscRing<T>& ring, std::size_t depth) {
  Result<Span<T>> r = mem.take_array<T>(queue_buffer_name(queue), depth);
  if (!r) return r.status();
  return ring.init(r.value());
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
  // A broken invariant in nav/, drivers/ or hal/ (QNAV_ASSERT) is a software fault here: counted,
  // FaultSoftware raised, logged; the daemon goes on in the defined state the call site leaves.
  set_assert_handler(&SoftwareFaults::record);
  const Status s = init_pipeline();
  if (!s && static_ && log_ != nullptr && static_->failed_name()[0] != '\0')
    std::fprintf(log_, "{\"event\":\"error\",\"what\":\"deployment table: buffer %s %s\"}\n", static_->failed_name(), s.message());
  flush_logs();
  return s;
}

// Start-up, in the deployment table's terms: the sim backend first resolves a recorded pass's
// geometry (it sets the tile and localiser sizes); then the table is made from the configuration in
// force, its static block allocated (StaticMemory), and every queue, pool, log ring and nav arena
// carved from it by name; complete() proves nothing in the table was left out.
Status Daemon::init_pipeline() {
  wall_ = std::make_unique<hal::MonotonicClock>();
  std::unique_ptr<SimIoBackend> sim;
  FramePool fp;
  const bool frames_on = cfg_.vo_enabled || map_runs(cfg_);
  if (frames_on) {
    fp.width = cfg_.vo.max_width;
    fp.height = cfg_.vo.max_height;
    fp.map_width = cfg_.map_width;
    fp.map_height = cfg_.map_height;
    fp.slot_bytes = frame_slot_bytes(cfg_);
    fp.frames = &frames_;  // the rings' storage is carved below, before any frame moves
    fp.free = &free_frames_;
  }
  stride_ = 2 * cfg_.max_samples_per_side;
  QueueRefs refs{&pings_, &free_slots_, &can_rx_, &dvl_q_, nullptr, stride_, fp};
  if (cfg_.backend == Backend::kSim) {
    // The simulated vehicle is a library of its own (qnavd_sim) that the flight binary does not link.
    const SimBackendFactory make_sim = sim_backend_factory();
    if (make_sim == nullptr)
      return Status(StatusCode::kUnsupported, "daemon.backend = \"sim\" needs the simulator, which this binary does not link: run qnavd-sim");
    sim = make_sim(cfg_, *wall_);
    QNAV_RETURN_IF_ERROR(sim->init(bus_observer_, bus_ctx_, refs.frames));
    sim_clock_ = &sim->clock();
    sim_store_ = &sim->store();
    double range_m = 0.0;
    if (sim->recorded_geometry(range_m, route_spacing_m_)) {
      // Recorded passes: tiles and registration as `qnav route train|repeat --sonar` sets them for
      // the file (pipeline/route_defaults), the route header's spacing and swath from the file.
      cfg_.tiles = pipeline::file_route_tile_config(range_m, 0.0, 0.0, 0.0, cfg_.sim_replay_lines, cfg_.sim_replay_stride);
      cfg_.tiles.corrector.max_samples_per_side = cfg_.max_samples_per_side;
      cfg_.localiser = pipeline::file_localiser_config(route::RouteDirection::kForward, cfg_.max_nodes, 8, route_spacing_m_);
      cfg_.localiser.window_slots = std::max<std::size_t>(cfg_.localiser.window_slots, cfg_.localiser.filter.max_registrations() + 1u);
      route_swath_m_ = 2.0 * range_m;
    } else {
      route_spacing_m_ = cfg_.tiles.tiles.tile_length_m > 0.0 ? cfg_.tiles.tiles.tile_stride_m : sim->node_spacing_m(cfg_.tiles.tiles.scanline_stride);
      route_swath_m_ = sim->swath_m();
    }
  }
  static_ = std::make_unique<StaticMemory>(make_deployment(cfg_));
  StaticMemory& mem = *static_;
  {  // the threads' log rings (drained by the main thread); taken whether or not there is a log
    Result<Span<char>> nav_mem = mem.take_array<char>("log.nav", kNavLogBytes + kLogLineBytes);
    if (!nav_mem) return nav_mem.status();
    Result<Span<char>> io_mem = mem.take_array<char>("log.io", kIoLogBytes + kLogLineBytes);
    if (!io_mem) return io_mem.status();
    if (log_ != nullptr) {
      // The io and nav threads log through rings the main thread drains: a slow or full log pipe
      // (journald) costs lines (counted), never a deadline.
      nav_log_ = std::make_unique<hal::LogRing>();
      io_log_ = std::make_unique<hal::LogRing>();
      QNAV_RETURN_IF_ERROR(nav_log_->open(nav_mem.value(), kLogLineBytes));
      QNAV_RETURN_IF_ERROR(io_log_->open(io_mem.value(), kLogLineBytes));
    }
  }
  Result<Span<float>> pool = mem.take_array<float>("ping_pool", cfg_.ping_queue * stride_);
  if (!pool) return pool.status();
  pool_ = pool.value().data();
  QNAV_RETURN_IF_ERROR(make_ring(mem, "pings", pings_, cfg_.ping_queue));
  QNAV_RETURN_IF_ERROR(make_ring(mem, "free_slots", free_slots_, cfg_.ping_queue));
  QNAV_RETURN_IF_ERROR(make_ring(mem, "can_rx", can_rx_, cfg_.can_rx_queue));
  QNAV_RETURN_IF_ERROR(make_ring(mem, "can_tx", can_tx_, cfg_.can_tx_queue));
  QNAV_RETURN_IF_ERROR(make_ring(mem, "dvl", dvl_q_, kDvlQueueCapacity));
  if (cfg_.mavlink_enabled) {
    if (!cfg_.mavlink_key_file.empty()) {  // the signing key: root-owned, 0600, 32 bytes, or no start (mavlink_key.hpp)
      Result<drivers::mavlink::SigningKey> key = load_mavlink_key(cfg_.mavlink_key_file.c_str(), cfg_.mavlink_key_owner_uid);
      if (!key) return key.status();
      std::memcpy(cfg_.mavlink_key_secret, key.value().secret, sizeof cfg_.mavlink_key_secret);
      cfg_.mavlink_key_loaded = true;
    }
    QNAV_RETURN_IF_ERROR(make_ring(mem, "mav_rx", mav_rx_, mav_rx_depth(cfg_)));
    QNAV_RETURN_IF_ERROR(make_ring(mem, "mav_tx", mav_tx_, mav_tx_depth(cfg_)));
    // Both backends: real UDP (and, on linux, the serial device); the sim's messages carry mission time.
    mav_io_ = std::make_unique<MavlinkIo>(cfg_, sample_clock(), io_log_ ? io_log_->stream() : nullptr);
    QNAV_RETURN_IF_ERROR(mav_io_->open());
  }
  for (std::uint32_t s = 0; s < cfg_.ping_queue; ++s) QNAV_RETURN_IF_ERROR(free_slots_.try_push(s));
  if (frames_on) {
    const std::size_t slots = frame_pool_slots(cfg_);
    Result<Span<std::uint8_t>> frames = mem.take_array<std::uint8_t>("frame_pool", slots * fp.slot_bytes);
    if (!frames) return frames.status();
    fp.pool = frames.value().data();
    QNAV_RETURN_IF_ERROR(make_ring(mem, "frames", frames_, slots));
    QNAV_RETURN_IF_ERROR(make_ring(mem, "free_frames", free_frames_, slots));
    for (std::uint32_t s = 0; s < slots; ++s) QNAV_RETURN_IF_ERROR(free_frames_.try_push(s));
  }
  refs.pool = pool_;
  refs.frames = fp;
  if (sim) {
    sim->set_queues(refs);
    sim->set_log(io_log_ ? io_log_->stream() : nullptr);
    backend_ = std::move(sim);
    // Paced (sim.speed > 0): a quarter of a handshake tick's wall time (10 ms of mission time), 200 us
    // to 2 ms, so the lockstep between passes keeps the pace and an idle worker does not spin at 1x.
    nav_idle_wait_us_ = cfg_.sim_speed > 0.0 ? std::clamp(static_cast<long>(2500.0 / cfg_.sim_speed), 200L, 2000L) : 200;
  } else {
    auto lb = std::make_unique<LinuxBackend>(cfg_, *wall_, refs, io_log_ ? io_log_->stream() : nullptr);
    QNAV_RETURN_IF_ERROR(lb->init());
    lb->set_mavlink(mav_io_.get());
    backend_ = std::move(lb);
  }
  QNAV_RETURN_IF_ERROR(hal::ensure_dir(cfg_.route_dir.c_str()));
  hal::FileStore& store = sim_store_ != nullptr ? *sim_store_ : hal::host_file_store();
  nav_ = std::make_unique<NavWorker>(cfg_, sample_clock(), *wall_, store);
  nav_->set_route_geometry(route_spacing_m_, route_swath_m_);
  NavQueues nq;
  nq.pings = &pings_;
  nq.free_slots = &free_slots_;
  nq.can_rx = &can_rx_;
  nq.can_tx = &can_tx_;
  nq.dvl = &dvl_q_;
  nq.ping_pool = pool_;
  nq.ping_pool_stride = stride_;
  nq.io = &io_;
  if (cfg_.mavlink_enabled) {
    nq.mav_rx = &mav_rx_;
    nq.mav_tx = &mav_tx_;
  }
  if (frames_on) {
    nq.frames = fp.frames;
    nq.free_frames = fp.free;
    nq.frame_pool = fp.pool;
    nq.frame_slot_bytes = fp.slot_bytes;
  }
  nav_->set_frame_observer(frame_observer_, frame_ctx_);
  backend_->set_worker(nav_.get(), &can_tx_);
  QNAV_RETURN_IF_ERROR(nav_->init(nq, tile_observer_, tile_ctx_, nav_log_ ? nav_log_->stream() : nullptr, &mem));
  return mem.complete();
}

void Daemon::io_loop() noexcept {
  if (cfg_.realtime) {
    const Status s = hal::set_thread_realtime(cfg_.io_priority, cfg_.io_cpu);
    if (!s && io_log_) std::fprintf(io_log_->stream(), "{\"event\":\"warning\",\"thread\":\"io\",\"what\":\"realtime not set: %s\"}\n", s.message());
  }
  while (!io_exit_.load(std::memory_order_relaxed)) {
    bool did = backend_->poll_devices(*this, io_);
    if (mav_io_) did |= mav_io_->poll(mav_rx_, io_);
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
    if (mav_io_) {
      MavBytes m;
      while (mav_tx_.try_pop(m)) {
        mav_io_->send(m, io_);
        did = true;
      }
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
    const Deployment& d = static_->table();
    std::fprintf(log_,
                 "{\"event\":\"started\",\"backend\":\"%s\",\"route_dir\":\"%s\",\"static_bytes\":%zu,\"heap_bytes\":%zu,\"ping_queue\":%zu,"
                 "\"can_interface\":\"%s\",\"realtime\":%s}\n",
                 cfg_.backend == Backend::kSim ? "sim" : "linux", cfg_.route_dir.c_str(), d.total_static_bytes(), d.total_heap_bytes(), cfg_.ping_queue,
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
