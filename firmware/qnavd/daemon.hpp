// Daemon: qnavd's process structure (deployment.hpp): it owns the queues, the ping pool, the I/O
// backend and the NavWorker, starts the io and nav threads, and runs the main thread's duties
// (signals, sd_notify READY / WATCHDOG / STOPPING, bounded shutdown).
// Backends: sim (SimVehicle on an in-process CAN network, or a SocketCAN interface with
// sim.can_interface, and serial line, mission time, paced by sim.speed; its rover's stereo bench in vo
// passes) or linux (SocketCAN on can.interface, the DVL on dvl.device through
// termios, the sonar's JSF stream over TCP from sonar.address, the stereo pair on two V4L2 devices
// with an optional GPIO trigger). A device that fails or disappears is counted (device_errors), flagged
// (its *_device_down bit; the nav worker reports the sensor lost) and reopened once a second.
// Logging: the io and nav threads write their lines into LogRings (hal/linux/log_ring.hpp) that the
// main thread drains to the log without blocking, so a slow journald pipe never stalls them.
// init() allocates everything; after start() no thread allocates (the allocation test proves it).
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdio>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "firmware/qnavd/config.hpp"
#include "firmware/qnavd/nav_worker.hpp"
#include "firmware/qnavd/io_backend.hpp"
#include "firmware/qnavd/mavlink_io.hpp"
#include "firmware/qnavd/static_memory.hpp"
#include "hal/linux/log_ring.hpp"

namespace qnav::daemon {

class IoBackend;

class Daemon {
 public:
  explicit Daemon(const DaemonConfig& config);
  ~Daemon();
  Daemon(const Daemon&) = delete;
  Daemon& operator=(const Daemon&) = delete;

  // Sizes and allocates every buffer, opens the devices. log: where log lines go (stdout in qnavd).
  Status init(FILE* log);
  void set_tile_observer(TileObserver f, void* ctx) noexcept { tile_observer_ = f, tile_ctx_ = ctx; }
  void set_bus_observer(BusObserver f, void* ctx) noexcept { bus_observer_ = f, bus_ctx_ = ctx; }
  void set_frame_observer(FrameObserver f, void* ctx) noexcept { frame_observer_ = f, frame_ctx_ = ctx; }
  // Starts the io and nav threads (realtime when configured and permitted; a warning otherwise).
  Status start();
  // The main thread: until a stop signal, stop(), or (sim) the end of the mission. Returns the exit code.
  int run();
  void stop() noexcept { stop_.store(true); }
  bool mission_done() const noexcept { return mission_done_.load(); }
  const NavWorker& nav() const noexcept { return *nav_; }
  const IoCounters& io_counters() const noexcept { return io_; }
  const hal::Clock& sample_clock() const noexcept;
  // The configuration in force (after recorded passes set their geometry).
  const DaemonConfig& config() const noexcept { return cfg_; }
  // The static block and the table it was built from (after init()).
  const StaticMemory& static_memory() const noexcept { return *static_; }
  // The MAVLink links (mavlink.enabled), else nullptr.
  const MavlinkIo* mavlink_io() const noexcept { return mav_io_.get(); }

 private:
  void io_loop() noexcept;
  void nav_loop() noexcept;
  Status init_pipeline();
  void flush_logs(bool final = false) noexcept;

  DaemonConfig cfg_;  // a copy: recorded passes set the tile and localiser geometry from their files
  FILE* log_ = nullptr;
  std::unique_ptr<hal::LogRing> nav_log_, io_log_;  // the threads' log lines, drained by the main thread
  std::uint64_t log_dropped_reported_ = 0;
  std::unique_ptr<hal::Clock> wall_;
  const hal::Clock* sim_clock_ = nullptr;     // sim backend: mission time (the backend owns it)
  hal::FileStore* sim_store_ = nullptr;       // sim backend: the route store it provides
  // Every queue, pool, log ring and nav arena below lives in this block, carved by the deployment
  // table's names (static_memory.hpp).
  std::unique_ptr<StaticMemory> static_;
  float* pool_ = nullptr;                    // the ping pool
  SpscRing<FrameMsg> frames_;
  SpscRing<std::uint32_t> free_frames_;
  SpscRing<PingMsg> pings_;
  SpscRing<std::uint32_t> free_slots_;
  SpscRing<hal::CanRxFrame> can_rx_;
  SpscRing<hal::CanFrame> can_tx_;
  SpscRing<drivers::dvl::DvlVelocity> dvl_q_;
  SpscRing<MavBytes> mav_rx_, mav_tx_;       // mavlink.enabled
  std::unique_ptr<MavlinkIo> mav_io_;        // the io thread's MAVLink links (either backend)
  std::size_t stride_ = 0;
  IoCounters io_;
  std::unique_ptr<IoBackend> backend_;
  std::unique_ptr<NavWorker> nav_;
  TileObserver tile_observer_ = nullptr;
  void* tile_ctx_ = nullptr;
  BusObserver bus_observer_ = nullptr;
  void* bus_ctx_ = nullptr;
  FrameObserver frame_observer_ = nullptr;
  void* frame_ctx_ = nullptr;
  std::thread io_thread_, nav_thread_;
  std::atomic<bool> stop_{false}, io_exit_{false}, nav_exited_{false}, mission_done_{false};
  // The nav thread's doorbell: the io thread rings it when it queued something (or moved the sim
  // clock); with nothing to do the nav thread waits for it, at most nav_idle_wait_us_: 2 ms on the
  // linux backend (time-driven work, outputs at >= 100 ms periods and staleness checks, needs no
  // finer step; it used to poll 5,000 times a second), 200 us on the sim backend, whose idle clock
  // waits for the worker's steps (SimVehicle::set_worker_caught_up); paced (sim.speed > 0) a quarter of
  // a handshake tick's wall time, 200 us to 2 ms, so a real-time mission does not spin.
  std::mutex bell_mu_;
  std::condition_variable bell_cv_;
  bool bell_ = false;
  long nav_idle_wait_us_ = 2000;
  std::int64_t started_wall_ns_ = 0;
  double route_spacing_m_ = 60.0;  // header of a route taught here: node spacing and swath (set by the backend)
  double route_swath_m_ = 100.0;
};

}  // namespace qnav::daemon
