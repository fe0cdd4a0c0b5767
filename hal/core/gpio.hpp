// GPIO interfaces: output lines (camera trigger) and edge-event input lines (strobe, leak detector).
//  - GpioOutput::set(): drives the line (logical value; active-low is handled by the backend).
//  - GpioInput::wait_event(): waits at most timeout_ms for one edge; kTimeout when none. The event
//    time is the kernel's edge time converted to the monotonic clock (sample_ns), arrival_ns is
//    when the daemon read it. get(): current logical level.
// Implementations: hal/linux GpiodOutputLine / GpiodInputLine (libgpiod v1.6), hal/sim SimGpioLine.
// No call allocates after open.
#pragma once

#include <cstdint>

#include "hal/core/stamp.hpp"
#include "nav/core/status.hpp"

namespace qnav::hal {

enum class GpioEdge : std::uint8_t { kRising, kFalling, kBoth };

struct GpioLineConfig {
  const char* chip = "gpiochip0";  // name under /dev, or a path
  unsigned offset = 0;
  bool active_low = false;
  const char* consumer = "qnav";
};

struct GpioEvent {
  bool rising = false;
  SampleStamp stamp;
};

class GpioOutput {
 public:
  virtual ~GpioOutput() = default;
  virtual Status set(bool value) noexcept = 0;
};

class GpioInput {
 public:
  virtual ~GpioInput() = default;
  virtual Result<GpioEvent> wait_event(int timeout_ms) noexcept = 0;
  virtual Result<bool> get() noexcept = 0;
};

}  // namespace qnav::hal
