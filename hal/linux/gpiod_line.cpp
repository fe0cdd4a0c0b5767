#include "hal/linux/gpiod_line.hpp"

#include <gpiod.h>

#include <cerrno>

#include "hal/linux/device_error.hpp"
#include "hal/linux/monotonic_clock.hpp"

namespace qnav::hal {

namespace {
gpiod_chip* open_chip(const char* name) noexcept {
  if (name == nullptr) return nullptr;
  return name[0] == '/' ? gpiod_chip_open(name) : gpiod_chip_open_by_name(name);
}
Status chip_error(const char* chip) noexcept {
  const int e = errno;
  return device_error(e == 0 || e == ENOENT || e == ENODEV || e == ENXIO ? StatusCode::kNotFound : StatusCode::kIoError,
                      "cannot open GPIO chip", chip, e, gpiochip_open_hint(e));
}
Status request_error(const char* what, const char* chip) noexcept {
  const int e = errno;
  return device_error(StatusCode::kIoError, what, chip, e,
                      e == EBUSY ? "the line is held by another consumer: `gpioinfo CHIP` names it" : gpiochip_open_hint(e));
}
int flags_of(const GpioLineConfig& c) noexcept { return c.active_low ? GPIOD_LINE_REQUEST_FLAG_ACTIVE_LOW : 0; }
// The chip and line c names, both open and not yet requested (on failure both null, the error named).
Status open_line(const GpioLineConfig& c, gpiod_chip*& chip, gpiod_line*& line) noexcept {
  errno = 0;
  chip = open_chip(c.chip);
  if (chip == nullptr) return chip_error(c.chip);
  line = gpiod_chip_get_line(chip, c.offset);
  if (line == nullptr) {
    gpiod_chip_close(chip);
    chip = nullptr;
    return Status(StatusCode::kNotFound, "GPIO line offset not on this chip");
  }
  return Status::ok();
}
// Releases the line (if requested) and closes the chip; both null after.
void release_line(gpiod_chip*& chip, gpiod_line*& line) noexcept {
  if (line != nullptr) gpiod_line_release(line);
  if (chip != nullptr) gpiod_chip_close(chip);
  line = nullptr;
  chip = nullptr;
}
}  // namespace

GpiodOutputLine::~GpiodOutputLine() { close(); }
void GpiodOutputLine::close() noexcept { release_line(chip_, line_); }
Status GpiodOutputLine::open(const GpioLineConfig& c, bool initial) noexcept {
  close();
  if (const Status st = open_line(c, chip_, line_); !st) return st;
  if (gpiod_line_request_output_flags(line_, c.consumer, flags_of(c), initial ? 1 : 0) < 0) {
    const Status st = request_error("GPIO output request failed on", c.chip);
    line_ = nullptr;
    close();
    return st;
  }
  return Status::ok();
}
Status GpiodOutputLine::set(bool value) noexcept {
  if (line_ == nullptr) return Status(StatusCode::kNotReady, "GPIO line not open");
  if (gpiod_line_set_value(line_, value ? 1 : 0) < 0) return Status(StatusCode::kIoError, "GPIO set failed");
  return Status::ok();
}

GpiodInputLine::~GpiodInputLine() { close(); }
void GpiodInputLine::close() noexcept { release_line(chip_, line_); }
int GpiodInputLine::fd() const noexcept { return line_ != nullptr ? gpiod_line_event_get_fd(line_) : -1; }
Status GpiodInputLine::open(const GpioLineConfig& c, GpioEdge edges) noexcept {
  close();
  if (const Status st = open_line(c, chip_, line_); !st) return st;
  int r;
  switch (edges) {
    case GpioEdge::kRising: r = gpiod_line_request_rising_edge_events_flags(line_, c.consumer, flags_of(c)); break;
    case GpioEdge::kFalling: r = gpiod_line_request_falling_edge_events_flags(line_, c.consumer, flags_of(c)); break;
    default: r = gpiod_line_request_both_edges_events_flags(line_, c.consumer, flags_of(c)); break;
  }
  if (r < 0) {
    const Status st = request_error("GPIO event request failed on", c.chip);
    line_ = nullptr;
    close();
    return st;
  }
  return Status::ok();
}
Result<GpioEvent> GpiodInputLine::wait_event(int timeout_ms) noexcept {
  if (line_ == nullptr) return Status(StatusCode::kNotReady, "GPIO line not open");
  const int ms = timeout_ms < 0 ? 0 : timeout_ms;
  timespec to{ms / 1000, static_cast<long>(ms % 1000) * 1000000L};
  const int w = gpiod_line_event_wait(line_, &to);
  if (w == 0) return Status(StatusCode::kTimeout, "no GPIO event");
  if (w < 0) return Status(StatusCode::kIoError, "GPIO event wait failed");
  gpiod_line_event ev{};
  if (gpiod_line_event_read(line_, &ev) < 0) return Status(StatusCode::kIoError, "GPIO event read failed");
  GpioEvent e;
  e.stamp.arrival_ns = monotonic_now_ns();
  e.rising = ev.event_type == GPIOD_LINE_EVENT_RISING_EDGE;
  const std::int64_t t = static_cast<std::int64_t>(ev.ts.tv_sec) * 1000000000LL + ev.ts.tv_nsec;
  constexpr std::int64_t kHour = 3600LL * 1000000000LL;
  const std::int64_t d = t - e.stamp.arrival_ns;
  e.stamp.sample_ns = (d > kHour || d < -kHour) ? realtime_to_monotonic_ns(t) : t;
  return e;
}
Result<bool> GpiodInputLine::get() noexcept {
  if (line_ == nullptr) return Status(StatusCode::kNotReady, "GPIO line not open");
  const int v = gpiod_line_get_value(line_);
  if (v < 0) return Status(StatusCode::kIoError, "GPIO get failed");
  return v != 0;
}

}  // namespace qnav::hal
