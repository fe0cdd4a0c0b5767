// libgpiod v1.6 GPIO lines (Debian 12's libgpiod-dev; the v2 API is different and not used).
//  - GpiodOutputLine: gpiod_line_request_output_flags (ACTIVE_LOW from the config), set().
//  - GpiodInputLine: edge events (rising/falling/both); wait_event() = gpiod_line_event_wait with
//    the timeout, then gpiod_line_event_read. The event time is the kernel's edge time: CLOCK_MONOTONIC
//    on kernels >= 5.7, CLOCK_REALTIME before; a stamp more than 1 h from the monotonic clock is taken
//    as realtime and converted. fd() lets the daemon put the line in its poll() set.
// Chip names: "gpiochip0" (looked up under /dev) or a path; a gpio-sim chip works the same way.
// Only available when the build found libgpiod (QNAV_HAVE_GPIOD). No heap after open().
#pragma once

#include "hal/core/gpio.hpp"

struct gpiod_chip;
struct gpiod_line;

namespace qnav::hal {

class GpiodOutputLine final : public GpioOutput {
 public:
  GpiodOutputLine() noexcept = default;
  ~GpiodOutputLine() override;
  GpiodOutputLine(const GpiodOutputLine&) = delete;
  GpiodOutputLine& operator=(const GpiodOutputLine&) = delete;
  Status open(const GpioLineConfig& config, bool initial) noexcept;
  void close() noexcept;
  Status set(bool value) noexcept override;

 private:
  gpiod_chip* chip_ = nullptr;
  gpiod_line* line_ = nullptr;
};

class GpiodInputLine final : public GpioInput {
 public:
  GpiodInputLine() noexcept = default;
  ~GpiodInputLine() override;
  GpiodInputLine(const GpiodInputLine&) = delete;
  GpiodInputLine& operator=(const GpiodInputLine&) = delete;
  Status open(const GpioLineConfig& config, GpioEdge edges) noexcept;
  void close() noexcept;
  int fd() const noexcept;
  Result<GpioEvent> wait_event(int timeout_ms) noexcept override;
  Result<bool> get() noexcept override;

 private:
  gpiod_chip* chip_ = nullptr;
  gpiod_line* line_ = nullptr;
};

}  // namespace qnav::hal
