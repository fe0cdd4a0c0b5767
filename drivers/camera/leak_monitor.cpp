#include "drivers/camera/leak_monitor.hpp"

namespace qnav::drivers::camera {

void LeakMonitor::latch(std::int64_t t_ns) noexcept {
  ++events_;
  if (!fault_) first_leak_ns_ = t_ns;
  fault_ = true;
}

Status LeakMonitor::start() noexcept {
  auto level = line_.get();
  if (!level.is_ok()) return level.status();
  if (level.value() == active_high_) latch(0);
  return Status::ok();
}

Result<bool> LeakMonitor::poll(int timeout_ms) noexcept {
  const bool before = fault_;
  const std::uint32_t events_before = events_;
  for (int i = 0; i < kMaxEventsPerPoll; ++i) {
    auto e = line_.wait_event(i == 0 ? timeout_ms : 0);
    if (!e.is_ok()) {
      if (e.status() == StatusCode::kTimeout) break;
      return e.status();
    }
    if (e.value().rising == active_high_) latch(e.value().stamp.sample_ns);
  }
  return !before && fault_ && events_ > events_before;
}

Status LeakMonitor::acknowledge() noexcept {
  auto level = line_.get();
  if (!level.is_ok()) return level.status();
  if (level.value() == active_high_) return Status(StatusCode::kNotReady, "leak line still active");
  fault_ = false;
  return Status::ok();
}

}  // namespace qnav::drivers::camera
