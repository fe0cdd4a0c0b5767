// SimGpioLine: one simulated GPIO line usable as output (records every set() with its time) and
// as edge-event input (the test injects levels; edges matching the configured GpioEdge queue events,
// up to kEventDepth; overflow counts `events_dropped`). wait_event() never blocks. No heap.
#pragma once

#include <cstddef>
#include <cstdint>

#include "hal/core/clock.hpp"
#include "hal/core/gpio.hpp"
#include "nav/core/ring_buffer.hpp"

namespace qnav::hal {

class SimGpioLine final : public GpioOutput, public GpioInput {
 public:
  static constexpr std::size_t kEventDepth = 64;
  SimGpioLine(const Clock& clock, GpioEdge edges, bool initial = false) noexcept
      : clock_(clock), edges_(edges), level_(initial) {}

  Status set(bool value) noexcept override;
  Result<GpioEvent> wait_event(int timeout_ms) noexcept override;
  Result<bool> get() noexcept override { return level_; }

  // Test side: drive the input level at time t_ns (an edge when it changes).
  void inject_level(bool level, std::int64_t t_ns) noexcept;
  std::uint32_t set_calls() const noexcept { return set_calls_; }
  std::int64_t last_set_ns() const noexcept { return last_set_ns_; }
  std::uint32_t events_dropped() const noexcept { return dropped_; }

 private:
  const Clock& clock_;
  GpioEdge edges_;
  bool level_;
  RingBuffer<GpioEvent, kEventDepth> events_;
  std::uint32_t set_calls_ = 0;
  std::int64_t last_set_ns_ = 0;
  std::uint32_t dropped_ = 0;
};

}  // namespace qnav::hal
