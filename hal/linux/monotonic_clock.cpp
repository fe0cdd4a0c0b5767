#include "hal/linux/monotonic_clock.hpp"

#include <errno.h>
#include <time.h>

namespace qnav::hal {

namespace {
std::int64_t read_ns(clockid_t id) noexcept {
  timespec ts{};
  clock_gettime(id, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000000000LL + ts.tv_nsec;
}
}  // namespace

std::int64_t monotonic_now_ns() noexcept { return read_ns(CLOCK_MONOTONIC); }
std::int64_t realtime_now_ns() noexcept { return read_ns(CLOCK_REALTIME); }
std::int64_t realtime_to_monotonic_ns(std::int64_t realtime_ns) noexcept {
  const std::int64_t mono = monotonic_now_ns();
  const std::int64_t real = realtime_now_ns();
  return realtime_ns - (real - mono);
}

bool MonotonicClock::sleep_until_ns(std::int64_t t_ns) noexcept {
  if (t_ns <= 0) return true;
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(t_ns / 1000000000LL);
  ts.tv_nsec = static_cast<long>(t_ns % 1000000000LL);
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
  return true;
}

}  // namespace qnav::hal
