// Clock: the daemon's monotonic time source (ns since an arbitrary epoch, never goes backwards).
// Backends: hal/linux MonotonicClock (CLOCK_MONOTONIC), hal/sim ManualClock (tests and replay).
// now_ns() is O(1) and never allocates.
#pragma once

#include <cstdint>

namespace qnav::hal {

class Clock {
 public:
  virtual ~Clock() = default;
  virtual std::int64_t now_ns() const noexcept = 0;
};

}  // namespace qnav::hal
