// Clock: the daemon's monotonic time source (ns since an arbitrary epoch, never goes backwards).
// Backends: hal/linux MonotonicClock (CLOCK_MONOTONIC), hal/sim ManualClock (tests and replay).
// now_ns() is O(1) and never allocates.
// sleep_until_ns(t): blocks until now_ns() >= t, an ABSOLUTE deadline, so a loop that sleeps to
// deadlines computed from one start does not drift (a relative sleep adds each wake-up's lateness).
// MonotonicClock sleeps in the kernel (clock_nanosleep TIMER_ABSTIME); ManualClock jumps to t; a
// clock another thread sets (the sim backend's mission clock) cannot wait and returns false.
#pragma once

#include <cstdint>

namespace qnav::hal {

class Clock {
 public:
  virtual ~Clock() = default;
  virtual std::int64_t now_ns() const noexcept = 0;
  virtual bool sleep_until_ns(std::int64_t /*t_ns*/) noexcept { return false; }
};

}  // namespace qnav::hal
