// The io thread's backends as qnavd's start-up sees them (daemon.cpp): IoBackend, what every backend
// is (one poll of every device into the nav worker's queues), and SimIoBackend, what the simulated
// vehicle adds. The linux backend lives in daemon.cpp; the sim backend in sim_backend.cpp, in the
// library qnavd_sim that the flight binary does not link: a program that links it (qnavd-sim, the
// tests) registers it at static initialisation, and a Daemon with backend = "sim" fails to start
// with a named error where it is absent.
// Also the polling steps both backends share (drain a CAN bus, a DVL driver, a leak line).
#pragma once

#include <cstdint>
#include <cstdio>
#include <memory>

#include "drivers/camera/leak_monitor.hpp"
#include "drivers/dvl/dvl_driver.hpp"
#include "drivers/dvl/dvl_types.hpp"
#include "firmware/qnavd/config.hpp"
#include "firmware/qnavd/messages.hpp"
#include "hal/core/can.hpp"
#include "hal/core/clock.hpp"
#include "hal/core/file_store.hpp"
#include "nav/core/spsc_ring.hpp"

namespace qnav::daemon {

class Daemon;
class NavWorker;

// Every CAN frame on the simulated bus as the vehicle's side saw it (tests, candump recording).
using BusObserver = void (*)(void* ctx, const hal::CanRxFrame& f);

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


// The simulated vehicle behind the io thread (sim_backend.cpp). Start-up order: init() (the frame
// geometry is checked against the passes; recorded passes are read), then the geometry queries,
// then set_queues() once the static block holds the queues and pools.
class SimIoBackend : public IoBackend {
 public:
  virtual Status init(BusObserver obs, void* ctx, const FramePool& frames) = 0;
  virtual void set_queues(const QueueRefs& q) noexcept = 0;
  // Recorded passes: the median slant range and the node spacing of their tracks (false: none).
  virtual bool recorded_geometry(double& range_m, double& spacing_m) const = 0;
  // The simulated survey: node spacing for a tile stride, and the sonar's swath.
  virtual double node_spacing_m(int scanline_stride) const = 0;
  virtual double swath_m() const = 0;
  // Mission time (the nav worker's sample clock).
  virtual const hal::Clock& clock() const noexcept = 0;
  // The route store: the host's file system behind a switch that can make the disk full (sim.fault).
  virtual hal::FileStore& store() noexcept = 0;
  // Where its `sim_pace` lines go (the io thread's log ring; nullptr: none).
  virtual void set_log(FILE* log) noexcept = 0;
};

using SimBackendFactory = std::unique_ptr<SimIoBackend> (*)(const DaemonConfig& c, hal::Clock& wall);
// Set by the sim library at static initialisation; nullptr in the flight binary.
void set_sim_backend_factory(SimBackendFactory f) noexcept;
SimBackendFactory sim_backend_factory() noexcept;

// failed (optional): set when the bus reported an error this call (the device went away).
// dropped_seen: the bus's running count of frames dropped before qnavd read them (the kernel's socket
// queue, SO_RXQ_OVFL; the sim bus's queue) at the last call; 0 again when the bus is reopened.
bool drain_can(hal::CanBus& bus, SpscRing<hal::CanRxFrame>& q, IoCounters& io, std::uint32_t& dropped_seen, bool* failed = nullptr) noexcept;
bool drain_dvl(drivers::dvl::DvlSerialDriver& dvl, SpscRing<drivers::dvl::DvlVelocity>& q, IoCounters& io, std::uint32_t& last_rejects) noexcept;
// The leak detector's line (either backend): a latched LeakMonitor. Returns true on a new leak.
bool poll_leak(drivers::camera::LeakMonitor& leak, IoCounters& io) noexcept;

}  // namespace qnav::daemon
