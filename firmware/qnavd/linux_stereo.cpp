#include "firmware/qnavd/linux_stereo.hpp"

#include <cstdio>
#include <cstring>

namespace qnav::daemon {

void LinuxStereoSource::report(const char* device, const char* what) noexcept {
  if (log_ && !warned_) std::fprintf(log_, "{\"event\":\"device\",\"device\":\"%s\",\"error\":\"%s\"}\n", device, what);
}

void LinuxStereoSource::close_devices() noexcept {
  left_.close();
  right_.close();
#ifdef QNAV_HAVE_GPIOD
  trigger_.close();
#endif
  open_ = false;
}

bool LinuxStereoSource::open_devices(IoCounters& io) noexcept {
  hal::CameraConfig cc;
  cc.width = cfg_.vo.max_width;
  cc.height = cfg_.vo.max_height;
  cc.format = hal::PixelFormat::kGrey;
  cc.device = cfg_.vo_left_device.c_str();
  Status s = left_.open(cc);
  if (!s) {
    cc.format = hal::PixelFormat::kYuyv;  // many cameras offer YUYV only; converted to grey per frame
    s = left_.open(cc);
  }
  if (!s) {
    report(cc.device, s.message());
    io.device_errors.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  cc.device = cfg_.vo_right_device.c_str();
  s = right_.open(cc);
  if (!s) {
    cc.format = cc.format == hal::PixelFormat::kGrey ? hal::PixelFormat::kYuyv : hal::PixelFormat::kGrey;
    s = right_.open(cc);
  }
  if (!s) {
    report(cc.device, s.message());
    io.device_errors.fetch_add(1, std::memory_order_relaxed);
    left_.close();
    return false;
  }
  has_trigger_ = false;
  hal::GpioOutput* trigger = nullptr;
  if (!cfg_.vo_trigger_chip.empty()) {
#ifdef QNAV_HAVE_GPIOD
    hal::GpioLineConfig gc;
    gc.chip = cfg_.vo_trigger_chip.c_str();
    gc.offset = static_cast<unsigned>(cfg_.vo_trigger_line);
    gc.consumer = "qnavd-trigger";
    s = trigger_.open(gc, false);
    if (!s) {
      report(cfg_.vo_trigger_chip.c_str(), s.message());
      io.device_errors.fetch_add(1, std::memory_order_relaxed);
      close_devices();
      return false;
    }
    trigger = &trigger_;
    has_trigger_ = true;
#else
    report(cfg_.vo_trigger_chip.c_str(), "this build has no libgpiod: the trigger line cannot be driven");
    io.device_errors.fetch_add(1, std::memory_order_relaxed);
    close_devices();
    return false;
#endif
  }
  drivers::camera::StereoConfig sc;
  sc.capture_timeout_ms = has_trigger_ ? kCaptureTimeoutMs : 0;
  sc.pair_tolerance_ns = static_cast<std::int64_t>(cfg_.vo_pair_tolerance_ms * 1e6);
  s = stereo_.open(left_, right_, sc, trigger);
  if (!s) {
    char both[160];
    std::snprintf(both, sizeof both, "%s + %s", cfg_.vo_left_device.c_str(), cfg_.vo_right_device.c_str());
    report(both, s.message());
    io.device_errors.fetch_add(1, std::memory_order_relaxed);
    close_devices();
    return false;
  }
  open_ = true;
  warned_ = false;
  rejects_ = 0;  // the reopened pair counts from zero (the totals already passed on stay in IoCounters)
  return true;
}

bool LinuxStereoSource::poll(std::int64_t now_ns, IoCounters& io) noexcept {
  if (!open_) {
    if (now_ns < next_open_ns_) return false;
    next_open_ns_ = now_ns + 1000000000;
    if (!open_devices(io)) {
      io.camera_device_down.store(true);
      warned_ = true;  // reported once until the devices come back
      return false;
    }
    io.camera_device_down.store(false);
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
    io.device_errors.fetch_add(1, std::memory_order_relaxed);
    io.camera_device_down.store(true);
    report(cfg_.vo_left_device.c_str(), r.status().message());
    close_devices();
    next_open_ns_ = now_ns + 1000000000;
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
  std::uint8_t* dst = pool_.pool + static_cast<std::size_t>(slot) * 2 * n;
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
