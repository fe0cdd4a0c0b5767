// StereoCamera: a stereo pair from two hal::Cameras (pairs matched by sample time within
// pair_tolerance_ns through StereoPairer) or from one side-by-side camera (left half / right half of
// one frame, same stamp). Optional hardware trigger (a GpioOutput pulsed before each capture) and
// strobe (a GpioInput whose edge time is reported as the exposure time of the pair).
// open() allocates kSlots grey images per side once (the only heap use; a reopen with the same
// geometry reuses them); step() never allocates.
// step(): [trigger] -> capture left -> capture right -> pair. A view returned in StereoFrame stays
// valid until the next step(). Counters: capture errors, corrupt frames, pairing drops, strobe misses.
// Worst case per step: 2 captures (each bounded by capture_timeout_ms) + a strobe wait + O(kDepth).
#pragma once

#include <cstdint>
#include <memory>

#include "drivers/camera/stereo_pairer.hpp"
#include "hal/core/camera.hpp"
#include "hal/core/gpio.hpp"
#include "nav/core/counters.hpp"
#include "nav/core/image.hpp"

namespace qnav::drivers::camera {

struct StereoConfig {
  std::int64_t pair_tolerance_ns = 2000000;  // 2 ms: hardware-triggered pairs are within ~100 us
  int capture_timeout_ms = 100;
  int strobe_timeout_ms = 20;
};

struct StereoFrame {
  ImageView<const std::uint8_t> left;
  ImageView<const std::uint8_t> right;
  PairRef pair;
  bool has_exposure = false;
  std::int64_t exposure_ns = 0;  // strobe edge time, when a strobe line is configured
};

enum class CamCounter : std::uint8_t { kCaptureError, kCorrupt, kTimeout, kStrobeMissing, kCount };
inline constexpr const char* kCamCounterNames[] = {"capture_error", "corrupt", "timeout", "strobe_missing"};

class StereoCamera {
 public:
  static constexpr int kSlots = static_cast<int>(StereoPairer::kDepth) + 2;

  StereoCamera() noexcept : pairer_(0) {}
  Status open(hal::Camera& left, hal::Camera& right, const StereoConfig& config, hal::GpioOutput* trigger = nullptr,
              hal::GpioInput* strobe = nullptr);
  Status open_side_by_side(hal::Camera& both, const StereoConfig& config, hal::GpioOutput* trigger = nullptr,
                           hal::GpioInput* strobe = nullptr);

  // ok(true): `out` holds a new pair; ok(false): no pair this time (frames queued or dropped).
  Result<bool> step(StereoFrame& out) noexcept;

  const CounterSet<CamCounter>& counters() const noexcept { return counters_; }
  const StereoPairer& pairer() const noexcept { return pairer_; }

 private:
  Status allocate(int width, int height, int sides);
  Status capture_side(Side side, hal::Camera& cam, FrameRef& ref) noexcept;
  int free_slot(Side side) const noexcept;
  ImageView<std::uint8_t> slot_view(Side side, int slot) const noexcept;

  hal::Camera* cams_[2] = {nullptr, nullptr};
  bool side_by_side_ = false;
  hal::GpioOutput* trigger_ = nullptr;
  hal::GpioInput* strobe_ = nullptr;
  StereoConfig config_;
  StereoPairer pairer_;
  int width_ = 0, height_ = 0, sides_ = 0;
  std::unique_ptr<std::uint8_t[]> pixels_;
  std::uint32_t busy_[2] = {0, 0};  // slots held by the last returned pair
  CounterSet<CamCounter> counters_{kCamCounterNames};
};

}  // namespace qnav::drivers::camera
