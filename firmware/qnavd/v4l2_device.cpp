#include "firmware/qnavd/v4l2_device.hpp"

namespace qnav::daemon {

Status open_grey_camera(hal::V4l2Camera& cam, hal::CameraConfig& cc) noexcept {
  Status s = cam.open(cc);
  if (s) return s;
  cc.format = cc.format == hal::PixelFormat::kGrey ? hal::PixelFormat::kYuyv : hal::PixelFormat::kGrey;
  return cam.open(cc);
}

bool DeviceOutage::reopen_due(std::int64_t now_ns) noexcept {
  if (now_ns < next_open_ns_) return false;
  next_open_ns_ = now_ns + kReopenPeriodNs;
  return true;
}

void DeviceOutage::failed(std::int64_t now_ns, const char* device, const char* what, IoCounters& io, std::atomic<bool>& down) noexcept {
  io.device_errors.fetch_add(1, std::memory_order_relaxed);
  down.store(true);
  if (log_ && !warned_) std::fprintf(log_, "{\"event\":\"device\",\"device\":\"%s\",\"error\":\"%s\"}\n", device, what);
  warned_ = true;
  next_open_ns_ = now_ns + kReopenPeriodNs;
}

void DeviceOutage::opened(std::atomic<bool>& down) noexcept {
  down.store(false);
  warned_ = false;
}

}  // namespace qnav::daemon
