// LinuxDownwardSource: qnavd's downward camera on the linux backend (Mode = Map; map.enabled with
// map.device): one V4L2 capture device (GREY, or YUYV converted to grey, at map.width x map.height)
// read straight into a free slot of the frame pool (the pool the sim backend's map passes fill) and
// queued for the nav worker as a downward FrameMsg, stamped with the kernel's buffer time on the
// monotonic clock. Intrinsics and altitude are the [map] keys (map.focal_px, cu_px, cv_px,
// altitude_m), applied by the nav worker's mapper.
// Faults: a device that cannot be opened or fails while streaming (unplugged, driver error) is counted
// in device_errors, flags downward_device_down (the nav worker reports FaultCameraLost in Mode = Map),
// is logged once per outage and reopened once a second (DeviceOutage, v4l2_device.hpp, as
// LinuxStereoSource); a frame the driver flags as corrupt or that cannot be converted is counted in
// camera_rejected; a frame with no free slot is read into a spare buffer and dropped (frame_overflow),
// never waited for.
// Time: poll() never waits (capture timeout 0; the io thread's poll() set holds the device's fd).
// Memory: the constructor allocates the spare frame (map.width x map.height bytes), open() maps the
// driver's buffers; poll() allocates nothing.
#pragma once

#include <cstdint>
#include <cstdio>
#include <vector>

#include "firmware/qnavd/config.hpp"
#include "firmware/qnavd/messages.hpp"
#include "firmware/qnavd/v4l2_device.hpp"
#include "hal/linux/v4l2_camera.hpp"

namespace qnav::daemon {

class LinuxDownwardSource {
 public:
  LinuxDownwardSource(const DaemonConfig& c, const FramePool& pool, FILE* log);
  // One poll: (re)open when due, take a frame if one is ready. True when a frame was read.
  bool poll(std::int64_t now_ns, IoCounters& io) noexcept;
  // The device's descriptor for the io thread's wait (-1 when closed).
  int fd() const noexcept { return cam_.fd(); }
  bool is_open() const noexcept { return open_; }
  hal::PixelFormat format() const noexcept { return format_; }  // what the device was opened with

 private:
  const DaemonConfig& cfg_;
  FramePool pool_;
  DeviceOutage outage_;
  hal::V4l2Camera cam_;
  std::vector<std::uint8_t> spare_;  // a frame with no free slot is read here and dropped
  hal::PixelFormat format_ = hal::PixelFormat::kGrey;
  bool open_ = false, have_slot_ = false;
  std::uint32_t slot_ = 0;           // the free slot held for the next frame (when have_slot_)
  std::uint32_t sequence_ = 0;
};

}  // namespace qnav::daemon
