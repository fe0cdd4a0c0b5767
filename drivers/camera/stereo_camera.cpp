#include "drivers/camera/stereo_camera.hpp"
#include "nav/core/assert.hpp"

#include <new>

namespace qnav::drivers::camera {

Status StereoCamera::allocate(int width, int height, int sides) {
  if (width <= 0 || height <= 0 || width > kMaxImageSide || height > kMaxImageSide)
    return Status(StatusCode::kInvalidArgument, "camera size out of range");
  busy_[0] = busy_[1] = 0;
  // Reopened with the same geometry (a device that came back): the slots are reused, not reallocated.
  if (pixels_ && width == width_ && height == height_ && sides == sides_) return Status::ok();
  width_ = width;
  height_ = height;
  sides_ = sides;
  const std::size_t n = static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * kSlots * static_cast<std::size_t>(sides);
  pixels_.reset(new (std::nothrow) std::uint8_t[n]);
  if (!pixels_) return Status(StatusCode::kCapacityExceeded, "cannot allocate stereo frame slots");
  busy_[0] = busy_[1] = 0;
  return Status::ok();
}

Status StereoCamera::open(hal::Camera& left, hal::Camera& right, const StereoConfig& c, hal::GpioOutput* trigger,
                          hal::GpioInput* strobe) {
  const hal::CameraFormat a = left.format();
  const hal::CameraFormat b = right.format();
  if (a.width != b.width || a.height != b.height) return Status(StatusCode::kInvalidArgument, "left and right sizes differ");
  QNAV_RETURN_IF_ERROR(allocate(a.width, a.height, 2));
  cams_[0] = &left;
  cams_[1] = &right;
  side_by_side_ = false;
  trigger_ = trigger;
  strobe_ = strobe;
  config_ = c;
  pairer_ = StereoPairer(c.pair_tolerance_ns);
  return Status::ok();
}

Status StereoCamera::open_side_by_side(hal::Camera& both, const StereoConfig& c, hal::GpioOutput* trigger, hal::GpioInput* strobe) {
  const hal::CameraFormat f = both.format();
  if (f.width % 2 != 0) return Status(StatusCode::kInvalidArgument, "side-by-side width must be even");
  QNAV_RETURN_IF_ERROR(allocate(f.width, f.height, 1));
  cams_[0] = &both;
  cams_[1] = nullptr;
  side_by_side_ = true;
  trigger_ = trigger;
  strobe_ = strobe;
  config_ = c;
  return Status::ok();
}

ImageView<std::uint8_t> StereoCamera::slot_view(Side side, int slot) const noexcept {
  const std::size_t plane = static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_);
  std::uint8_t* p = pixels_.get() + plane * (static_cast<std::size_t>(static_cast<int>(side)) * kSlots + static_cast<std::size_t>(slot));
  return ImageView<std::uint8_t>::unchecked(p, width_, height_, width_);
}

int StereoCamera::free_slot(Side side) const noexcept {
  const std::uint32_t used = pairer_.queued_slots(side) | busy_[static_cast<int>(side)];
  for (int i = 0; i < kSlots; ++i)
    if (!(used & (1u << i))) return i;
  QNAV_ASSERT(false, "stereo camera: no free frame slot (kSlots > kDepth + 1 guarantees one)");
  return -1;
}

Status StereoCamera::capture_side(Side side, hal::Camera& cam, FrameRef& ref) noexcept {
  const int slot = free_slot(side);
  if (slot < 0) return Status(StatusCode::kCapacityExceeded, "no free frame slot");
  auto r = cam.capture(slot_view(side, slot), config_.capture_timeout_ms);
  if (!r.is_ok()) {
    counters_.increment(r.status() == StatusCode::kTimeout ? CamCounter::kTimeout : CamCounter::kCaptureError);
    return r.status();
  }
  if (r.value().corrupt) {
    counters_.increment(CamCounter::kCorrupt);
    return Status(StatusCode::kCorrupt, "driver flagged the frame");
  }
  ref.sequence = r.value().sequence;
  ref.stamp = r.value().stamp;
  ref.slot = static_cast<std::uint8_t>(slot);
  return Status::ok();
}

Result<bool> StereoCamera::step(StereoFrame& out) noexcept {
  if (cams_[0] == nullptr) return Status(StatusCode::kNotReady, "stereo camera not open");
  if (trigger_ != nullptr) {
    QNAV_RETURN_IF_ERROR(trigger_->set(true));
    QNAV_RETURN_IF_ERROR(trigger_->set(false));
  }
  bool has_exposure = false;
  std::int64_t exposure_ns = 0;
  if (strobe_ != nullptr) {
    auto e = strobe_->wait_event(config_.strobe_timeout_ms);
    if (e.is_ok()) {
      has_exposure = true;
      exposure_ns = e.value().stamp.sample_ns;
    } else {
      counters_.increment(CamCounter::kStrobeMissing);
    }
  }
  if (side_by_side_) {
    FrameRef ref;
    busy_[0] = 0;
    QNAV_RETURN_IF_ERROR(capture_side(Side::kLeft, *cams_[0], ref));
    busy_[0] = 1u << ref.slot;
    const ImageView<std::uint8_t> full = slot_view(Side::kLeft, ref.slot);
    const int half = width_ / 2;
    out.left = ImageView<const std::uint8_t>::unchecked(full.data(), half, height_, width_);
    out.right = ImageView<const std::uint8_t>::unchecked(full.data() + half, half, height_, width_);
    out.pair.left = ref;
    out.pair.right = ref;
    out.pair.skew_ns = 0;
    out.has_exposure = has_exposure;
    out.exposure_ns = exposure_ns;
    return true;
  }
  bool paired = false;
  PairRef pair;
  std::uint8_t dropped[StereoPairer::kDepth + 1];
  std::size_t n_dropped = 0;
  for (int s = 0; s < 2; ++s) {
    const Side side = static_cast<Side>(s);
    FrameRef ref;
    const Status st = capture_side(side, *cams_[s], ref);
    if (!st.is_ok()) {
      if (st == StatusCode::kTimeout || st == StatusCode::kCorrupt) continue;  // counted; the other side may still pair
      return st;
    }
    PairRef p;
    if (pairer_.push(side, ref, p, dropped, n_dropped)) {
      pair = p;
      paired = true;
    }
  }
  if (!paired) return false;
  busy_[0] = 1u << pair.left.slot;
  busy_[1] = 1u << pair.right.slot;
  const ImageView<std::uint8_t> l = slot_view(Side::kLeft, pair.left.slot);
  const ImageView<std::uint8_t> r = slot_view(Side::kRight, pair.right.slot);
  out.left = ImageView<const std::uint8_t>::unchecked(l.data(), width_, height_, width_);
  out.right = ImageView<const std::uint8_t>::unchecked(r.data(), width_, height_, width_);
  out.pair = pair;
  out.has_exposure = has_exposure;
  out.exposure_ns = exposure_ns;
  return true;
}

}  // namespace qnav::drivers::camera
