// What qnavd's V4L2 camera sources share (LinuxStereoSource: the stereo pair of Mode = Vo;
// LinuxDownwardSource: the downward camera of Mode = Map):
//  - open_grey_camera(): a capture device opened for 8-bit grey frames, GREY if the driver offers it,
//    else YUYV (converted to grey per frame by hal::V4l2Camera);
//  - DeviceOutage: a device that cannot be opened or fails while streaming is counted
//    (IoCounters::device_errors) every time, flags its *_device_down, is logged once per outage (a
//    JSON "device" event with the OS's reason) and reopened at most once a second.
// No heap; nothing here blocks.
#pragma once

#include <atomic>
#include <cstdint>
#include <cstdio>

#include "firmware/qnavd/messages.hpp"
#include "hal/linux/v4l2_camera.hpp"

namespace qnav::daemon {

// Opens cam with cc (device, width, height): cc.format first, then the other of GREY / YUYV; cc.format
// is left at the one that opened. The second attempt's error is returned when both fail.
Status open_grey_camera(hal::V4l2Camera& cam, hal::CameraConfig& cc) noexcept;

class DeviceOutage {
 public:
  static constexpr std::int64_t kReopenPeriodNs = 1000000000;  // once a second

  explicit DeviceOutage(FILE* log) noexcept : log_(log) {}
  // True when an open attempt is due now; the next one is then due a second later.
  bool reopen_due(std::int64_t now_ns) noexcept;
  // The device failed (could not be opened, or failed while streaming): counted, `down` set, logged
  // unless this outage was already logged; the next open attempt a second from now.
  void failed(std::int64_t now_ns, const char* device, const char* what, IoCounters& io, std::atomic<bool>& down) noexcept;
  // The device is open (again): `down` cleared; its next failure is logged.
  void opened(std::atomic<bool>& down) noexcept;

 private:
  FILE* log_;
  bool warned_ = false;
  std::int64_t next_open_ns_ = 0;
};

}  // namespace qnav::daemon
