// qnavd's sim backend (io_backend.hpp: SimIoBackend): the simulated vehicle (sim_vehicle: autopilot,
// AHRS, DVL, side-scan, the rover's stereo bench, recorded passes) on in-process CAN and serial
// buses, in mission time. Part of the library qnavd_sim, which the flight binary qnavd does not link
// (it runs qnavd-sim for a configuration with daemon.backend = "sim"); linking it registers the
// backend with the daemon's start-up.
#include <chrono>
#include <cstdio>
#include <memory>
#include <thread>

#include "firmware/qnavd/daemon.hpp"
#include "firmware/qnavd/io_backend.hpp"
#include "firmware/qnavd/nav_worker.hpp"
#include "firmware/qnavd/sim_pacer.hpp"
#include "firmware/qnavd/sim_vehicle.hpp"
#include "hal/linux/posix_file_store.hpp"
#include "hal/linux/socketcan_bus.hpp"
#include "hal/sim/clocked_can_link.hpp"
#include "hal/sim/fault_file_store.hpp"
#include "hal/sim/sim_can.hpp"
#include "hal/sim/sim_gpio.hpp"
#include "hal/sim/sim_serial.hpp"

namespace qnav::daemon {
namespace {

using std::chrono::microseconds;

// ---- sim: the simulated vehicle on in-process buses (or a SocketCAN interface), mission time ----
class SimBackend final : public SimIoBackend {
 public:
  SimBackend(const DaemonConfig& c, hal::Clock& wall)
      : cfg_(c), net_(clock_), pipe_(clock_), vehicle_(c, clock_, wall), dvl_(pipe_.b(), drivers::dvl::DvlProtocol::kWaterLinked), q_{},
        store_(hal::host_file_store()), leak_line_(clock_, hal::GpioEdge::kBoth), leak_(leak_line_, true), daemon_node_(daemon_sock_, clock_, wall),
        vehicle_node_(vehicle_sock_, clock_, wall) {}
  // The queues and pools once the static block holds them (init() only checks the frame geometry).
  void set_queues(const QueueRefs& q) noexcept override {
    q_ = q;
    vehicle_.set_frame_pool(q.frames);
  }
  Status init(BusObserver obs, void* ctx, const FramePool& frames) override {
    hal::FaultFileStore* store = &store_;
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
  void set_log(FILE* log) noexcept override {
    log_ = log;
    vehicle_.set_log(log);
  }
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
  bool recorded_geometry(double& range_m, double& spacing_m) const override { return vehicle_.recorded_geometry(range_m, spacing_m); }
  double node_spacing_m(int scanline_stride) const override { return vehicle_.node_spacing_m(scanline_stride); }
  double swath_m() const override { return vehicle_.swath_m(); }
  const hal::Clock& clock() const noexcept override { return clock_; }
  hal::FileStore& store() noexcept override { return store_; }

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
  SimClock clock_;  // mission time
  hal::SimCanNetwork net_;
  hal::SimCanBus daemon_bus_, vehicle_bus_;
  hal::SimSerialPipe pipe_;
  SimVehicle vehicle_;
  drivers::dvl::DvlSerialDriver dvl_;
  QueueRefs q_;
  hal::FaultFileStore store_;   // the route store behind a switch that can make the disk full (sim.fault = "disk_full")
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

std::unique_ptr<SimIoBackend> make_sim_backend(const DaemonConfig& c, hal::Clock& wall) { return std::make_unique<SimBackend>(c, wall); }

// Registered before main() runs: qnavd_sim is an object library, so this object is always linked.
const bool g_registered = (set_sim_backend_factory(&make_sim_backend), true);

}  // namespace
}  // namespace qnav::daemon
