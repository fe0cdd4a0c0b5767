#include "firmware/qnavd/linux_downward.hpp"

namespace qnav::daemon {

LinuxDownwardSource::LinuxDownwardSource(const DaemonConfig& c, const FramePool& pool, FILE* log)
    : cfg_(c), pool_(pool), outage_(log), spare_(static_cast<std::size_t>(c.map_width) * static_cast<std::size_t>(c.map_height), 0) {}

bool LinuxDownwardSource::poll(std::int64_t now_ns, IoCounters& io) noexcept {
  if (!open_) {
    if (!outage_.reopen_due(now_ns)) return false;
    hal::CameraConfig cc;
    cc.device = cfg_.map_device.c_str();
    cc.width = cfg_.map_width;
    cc.height = cfg_.map_height;
    cc.format = hal::PixelFormat::kGrey;
    const Status s = open_grey_camera(cam_, cc);
    if (!s) {
      outage_.failed(now_ns, cc.device, s.message(), io, io.downward_device_down);  // logged once until it comes back
      return false;
    }
    format_ = cc.format;
    open_ = true;
    outage_.opened(io.downward_device_down);
  }
  // A free slot is held until a frame fills it (the io thread only takes from the free queue).
  if (!have_slot_) have_slot_ = pool_.free->try_pop(slot_).is_ok();
  std::uint8_t* dst = have_slot_ ? pool_.slot(slot_) : spare_.data();
  const Result<ImageViewU8> view = ImageViewU8::make(dst, cfg_.map_width, cfg_.map_height);
  if (!view) return false;  // cannot happen: map.width x map.height were validated
  const Result<hal::CameraFrameInfo> r = cam_.capture(*view, 0);
  if (!r) {
    const StatusCode code = r.status().code();
    if (code == StatusCode::kTimeout) return false;  // no frame yet
    if (code == StatusCode::kIoError || code == StatusCode::kNotReady) {
      // The device failed (unplugged, stream stopped): closed here, reopened within a second.
      outage_.failed(now_ns, cfg_.map_device.c_str(), r.status().message(), io, io.downward_device_down);
      cam_.close();
      open_ = false;
      return false;
    }
    io.frames_in.fetch_add(1, std::memory_order_relaxed);
    io.camera_rejected.fetch_add(1, std::memory_order_relaxed);  // a buffer that did not convert: the slot is reused
    return true;
  }
  io.frames_in.fetch_add(1, std::memory_order_relaxed);
  if (r->corrupt) {
    io.camera_rejected.fetch_add(1, std::memory_order_relaxed);  // the driver flagged it: the slot is reused
    return true;
  }
  if (!have_slot_) {
    io.frame_overflow.fetch_add(1, std::memory_order_relaxed);  // the nav worker is behind: dropped, never waited for
    return true;
  }
  FrameMsg m;
  m.slot = slot_;
  m.sequence = sequence_++;
  m.width = static_cast<std::uint16_t>(cfg_.map_width);
  m.height = static_cast<std::uint16_t>(cfg_.map_height);
  m.downward = true;
  m.stamp = r->stamp;
  have_slot_ = false;
  if (!pool_.frames->try_push(m)) io.frame_overflow.fetch_add(1, std::memory_order_relaxed);  // cannot happen: one entry per slot
  return true;
}

}  // namespace qnav::daemon
