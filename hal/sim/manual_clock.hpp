// ManualClock: a Clock the test or the replay loop sets and advances; sleep_until_ns(t) jumps to t
// (never backwards). O(1), no heap. Single-threaded.
#pragma once

#include <cstdint>

#include "hal/core/clock.hpp"

namespace qnav::hal {

class ManualClock final : public Clock {
 public:
  explicit ManualClock(std::int64_t start_ns = 0) noexcept : now_ns_(start_ns) {}
  std::int64_t now_ns() const noexcept override { return now_ns_; }
  void set_ns(std::int64_t t) noexcept { now_ns_ = t; }
  void advance_ns(std::int64_t dt) noexcept { now_ns_ += dt; }
  bool sleep_until_ns(std::int64_t t_ns) noexcept override {
    if (t_ns > now_ns_) now_ns_ = t_ns;
    return true;
  }

 private:
  std::int64_t now_ns_;
};

}  // namespace qnav::hal
