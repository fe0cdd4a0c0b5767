#include "firmware/qnavd/linux_stereo.hpp"

#include <cstdio>
#include <cstring>

namespace qnav::daemon {

void LinuxStereoSource::close_devices() noexcept {
  left_.close();
  right_.close();
#ifdef QNAV_HAVE_GPIOD
  trigger_.close();
#endif
  open_ = false;
}

// Opens both cameras (GREY, or YUYV), the trigger line and the pairing; on failure everything is
// closed again and `device` names what failed.
Status LinuxStereoSource::open_devices(const char*& device) noexcept {
  hal::CameraConfig cc;
  cc.width = cfg_.vo.max_width;
  cc.height = cfg_.vo.max_height;
  cc.format = hal::PixelFormat::kGrey;
  cc.device = device = cfg_.vo_left_device.c_str();
  QNAV_RETURN_IF_ERROR(open_grey_camera(left_, cc));  // the right camera tries the left one's format first
  cc.device = device = cfg_.vo_right_device.c_str();
  Status s = open_grey_camera(right_, cc);
  if (!s) {
    left_.close();
    return s;
  }
  has_trigger_ = false;
  hal::GpioOutput* trigger = nullptr;
  if (!cfg_.vo_trigger_chip.empty()) {
    device = cfg_.vo_trigger_chip.c_str();
#ifdef QNAV_HAVE_GPIOD
    hal::GpioLineConfig gc;
    gc.chip = cfg_.vo_trigger_chip.c_str();
    gc.offset = static_cast<unsigned>(cfg_.vo_trigger_line);
    gc.consumer = "qnavd-trigger";
    s = trigger_.open(gc, false);
    if (!s) {
      close_devices();
      return s;
    }
    trigger = &trigger_;
    has_trigger_ = true;
#else
    close_devices();
    return Status(StatusCode::kUnsupported, "this build has no libgpiod: the trigger line cannot be driven");
#endif
  }
  drivers::camera::StereoConfig sc;
  sc.capture_timeout_ms = has_trigger_ ? kCaptureTimeoutMs : 0;
  sc.pair_tolerance_ns = static_cast<std::int64_t>(cfg_.vo_pair_tolerance_ms * 1e6);
  s = stereo_.open(left_, right_, sc, trigger);
  if (!s) {
    std::snprintf(both_, sizeof both_, "%s + %s", cfg_.vo_left_device.c_str(), cfg_.vo_right_device.c_str());
    device = both_;
    close_devices();
    return s;
  }
  open_ = true;
  rejects_ = 0;  // the reopened pair counts from zero (the totals already passed on stay in IoCounters)
  return Status::ok();
}

bool LinuxStereoSource::poll(std::int64_t now_ns, IoCounters& io) noexcept {
  if (!open_) {
    if (!outage_.reopen_due(now_ns)) return false;
    const char* device = "";
    const Status s = open_devices(device);
    if (!s) {
      outage_.failed(now_ns, device, s.message(), io, io.camera_device_down);  // reported once until the devices come back
      return false;
    }
    outage_.opened(io.camera_device_down);
  }
  if (has_trigger_) {
    if (now_ns < next_trigger_ns_) return false;
    next_trigger_ns_ = now_ns + static_cast<std::int64_t>(1e9 / cfg_.vo_rate_hz);
  }
  drivers::camera::StereoFrame f;
  Result<bool> r = stereo_.step(f);
  const std::uint32_t rej = stereo_.counters().get(drivers::camera::CamCounter::kCorrupt) +
                            stereo_.counters().get(drivers::camera::CamCounter::kCaptureError) +
                            stereo_.pairer().counters().total() +
                            (has_trigger_ ? stereo_.counters().get(drivers::camera::CamCounter::kTimeout) : 0u);
  if (rej != rejects_) {
    io.camera_rejected.fetch_add(rej - rejects_, std::memory_order_relaxed);
    rejects_ = rej;
  }
  if (!r) {
    // The device failed (unplugged, stream stopped): closed here, reopened within a second.
    outage_.failed(now_ns, cfg_.vo_left_device.c_str(), r.status().message(), io, io.camera_device_down);
    close_devices();
    return false;
  }
  if (!*r) return false;
  io.frames_in.fetch_add(1, std::memory_order_relaxed);
  std::uint32_t slot = 0;
  if (f.left.width() != pool_.width || f.left.height() != pool_.height || !pool_.free->try_pop(slot)) {
    io.frame_overflow.fetch_add(1, std::memory_order_relaxed);  // the nav worker is behind: dropped, never waited for
    return true;
  }
  const std::size_t n = static_cast<std::size_t>(pool_.width) * static_cast<std::size_t>(pool_.height);
  // The pool's own slot size (frame_slot_bytes: the larger of a stereo pair and a downward frame),
  // the stride the nav worker reads with; a pair fills the first 2 n bytes of its slot.
  std::uint8_t* dst = pool_.slot(slot);
  for (int y = 0; y < pool_.height; ++y) {
    std::memcpy(dst + static_cast<std::size_t>(y) * static_cast<std::size_t>(pool_.width), f.left.row(y), static_cast<std::size_t>(pool_.width));
    std::memcpy(dst + n + static_cast<std::size_t>(y) * static_cast<std::size_t>(pool_.width), f.right.row(y), static_cast<std::size_t>(pool_.width));
  }
  FrameMsg m;
  m.slot = slot;
  m.sequence = sequence_++;
  m.width = static_cast<std::uint16_t>(pool_.width);
  m.height = static_cast<std::uint16_t>(pool_.height);
  m.stamp = f.has_exposure ? hal::SampleStamp{f.exposure_ns, f.pair.left.stamp.arrival_ns} : f.pair.left.stamp;
  if (!pool_.frames->try_push(m)) io.frame_overflow.fetch_add(1, std::memory_order_relaxed);  // cannot happen: one entry per slot
  return true;
}

}  // namespace qnav::daemon
