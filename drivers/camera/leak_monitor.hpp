// LeakMonitor: a leak detector on a GPIO input line (active level configurable). The first edge to
// the active level -- or the active level already present at start() -- latches a health fault
// (fault() stays true until acknowledge() with the line inactive) and is counted. Events from the
// line are drained at most kMaxEventsPerPoll per poll(). No heap.
#pragma once

#include <cstdint>

#include "hal/core/gpio.hpp"
#include "nav/core/status.hpp"

namespace qnav::drivers::camera {

class LeakMonitor {
 public:
  static constexpr int kMaxEventsPerPoll = 8;
  LeakMonitor(hal::GpioInput& line, bool active_high) noexcept : line_(line), active_high_(active_high) {}

  Status start() noexcept;
  // Waits at most timeout_ms for the first event; returns true when a (new) leak was detected.
  Result<bool> poll(int timeout_ms) noexcept;
  bool fault() const noexcept { return fault_; }
  std::int64_t first_leak_ns() const noexcept { return first_leak_ns_; }
  std::uint32_t leak_events() const noexcept { return events_; }
  // Clears the latch only when the line reads inactive now.
  Status acknowledge() noexcept;

 private:
  void latch(std::int64_t t_ns) noexcept;
  hal::GpioInput& line_;
  bool active_high_;
  bool fault_ = false;
  std::int64_t first_leak_ns_ = 0;
  std::uint32_t events_ = 0;
};

}  // namespace qnav::drivers::camera
