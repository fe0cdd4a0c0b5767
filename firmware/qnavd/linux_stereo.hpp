// LinuxStereoSource: qnavd's stereo pair on the linux backend (vo.camera = "v4l2"): two V4L2 devices
// (vo.left_device, vo.right_device; GREY, or YUYV converted to grey, at vo.width x vo.height) paired
// by sample time through drivers/camera StereoCamera, with an optional hardware trigger line
// (vo.trigger_chip / vo.trigger_line, libgpiod) pulsed at vo.rate_hz. Each pair is copied into a
// free slot of the frame pool and queued for the nav worker, stamped with the left image's sample
// time (the kernel's buffer time on the monotonic clock).
// Faults: a device that cannot be opened or fails (unplugged, driver error) is counted in
// device_errors, flags camera_device_down (the nav worker reports FaultCameraLost in Vo mode), is
// logged once per outage and reopened once a second (DeviceOutage, v4l2_device.hpp); corrupt, unpaired and timed-out frames are counted in camera_rejected; a
// pair with no free slot is dropped and counted (frame_overflow), never waited for.
// Time: with a trigger, one poll per period waits at most 2 x kCaptureTimeoutMs for the pair; without
// one, poll() never waits (capture timeout 0; the io thread's poll() set holds both devices' fds).
// Memory: open() maps the driver buffers and StereoCamera allocates its slots once; poll() allocates
// nothing.
#pragma once

#include <cstdint>
#include <cstdio>

#include "drivers/camera/stereo_camera.hpp"
#include "firmware/qnavd/config.hpp"
#include "firmware/qnavd/messages.hpp"
#include "firmware/qnavd/v4l2_device.hpp"
#include "hal/linux/v4l2_camera.hpp"
#ifdef QNAV_HAVE_GPIOD
#include "hal/linux/gpiod_line.hpp"
#endif

namespace qnav::daemon {

class LinuxStereoSource {
 public:
  static constexpr int kCaptureTimeoutMs = 40;

  LinuxStereoSource(const DaemonConfig& c, const FramePool& pool, FILE* log) noexcept : cfg_(c), pool_(pool), outage_(log) {}
  // One poll: (re)open when due, trigger when due, take a pair if one is ready. True when a pair was queued.
  bool poll(std::int64_t now_ns, IoCounters& io) noexcept;
  // The devices' descriptors for the io thread's wait (-1 when closed).
  int left_fd() const noexcept { return left_.fd(); }
  int right_fd() const noexcept { return right_.fd(); }

 private:
  Status open_devices(const char*& device) noexcept;
  void close_devices() noexcept;

  const DaemonConfig& cfg_;
  FramePool pool_;
  DeviceOutage outage_;  // open failures: counted, logged once, retried once a second (v4l2_device.hpp)
  char both_[160] = {};
  hal::V4l2Camera left_, right_;
#ifdef QNAV_HAVE_GPIOD
  hal::GpiodOutputLine trigger_;
#endif
  bool has_trigger_ = false;
  drivers::camera::StereoCamera stereo_;
  bool open_ = false;
  std::int64_t next_trigger_ns_ = 0;
  std::uint32_t rejects_ = 0, sequence_ = 0;
};

}  // namespace qnav::daemon
