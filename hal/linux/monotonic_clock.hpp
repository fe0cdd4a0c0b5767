// MonotonicClock: CLOCK_MONOTONIC in ns. realtime_to_monotonic_ns() converts a kernel timestamp taken
// on CLOCK_REALTIME (SO_TIMESTAMPNS) to the monotonic clock using the current offset between the two
// clocks (error = any step of the realtime clock between the stamp and the call). O(1), no heap.
#pragma once

#include <cstdint>

#include "hal/core/clock.hpp"

namespace qnav::hal {

std::int64_t monotonic_now_ns() noexcept;
std::int64_t realtime_now_ns() noexcept;
std::int64_t realtime_to_monotonic_ns(std::int64_t realtime_ns) noexcept;

class MonotonicClock final : public Clock {
 public:
  std::int64_t now_ns() const noexcept override { return monotonic_now_ns(); }
  // clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME), resumed after a signal. Always true.
  bool sleep_until_ns(std::int64_t t_ns) noexcept override;
};

// RealtimeClock: CLOCK_REALTIME in ns since 1970-01-01 UTC (steps when the system time is set: not for
// intervals; for wall-clock stamps such as MAVLink signing timestamps).
class RealtimeClock final : public Clock {
 public:
  std::int64_t now_ns() const noexcept override { return realtime_now_ns(); }
};

}  // namespace qnav::hal
