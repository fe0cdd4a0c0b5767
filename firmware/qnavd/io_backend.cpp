#include "firmware/qnavd/io_backend.hpp"

namespace qnav::daemon {

namespace {
SimBackendFactory g_sim_factory = nullptr;
}  // namespace

void set_sim_backend_factory(SimBackendFactory f) noexcept { g_sim_factory = f; }
SimBackendFactory sim_backend_factory() noexcept { return g_sim_factory; }

bool drain_can(hal::CanBus& bus, SpscRing<hal::CanRxFrame>& q, IoCounters& io, std::uint32_t& dropped_seen, bool* failed) noexcept {
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

}  // namespace qnav::daemon
