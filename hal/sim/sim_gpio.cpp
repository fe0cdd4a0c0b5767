#include "hal/sim/sim_gpio.hpp"

namespace qnav::hal {

Status SimGpioLine::set(bool value) noexcept {
  level_ = value;
  ++set_calls_;
  last_set_ns_ = clock_.now_ns();
  return Status::ok();
}

Result<GpioEvent> SimGpioLine::wait_event(int /*timeout_ms*/) noexcept {
  GpioEvent e;
  if (!events_.pop(e).is_ok()) return Status(StatusCode::kTimeout, "no GPIO event");
  e.stamp.arrival_ns = clock_.now_ns();
  return e;
}

void SimGpioLine::inject_level(bool level, std::int64_t t_ns) noexcept {
  if (level == level_) return;
  level_ = level;
  const bool want = edges_ == GpioEdge::kBoth || (edges_ == GpioEdge::kRising) == level;
  if (!want) return;
  GpioEvent e;
  e.rising = level;
  e.stamp.sample_ns = t_ns;
  if (!events_.push(e).is_ok()) ++dropped_;
}

}  // namespace qnav::hal
