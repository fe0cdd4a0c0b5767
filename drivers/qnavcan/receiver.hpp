// QnavCanReceiver: the input side of qnav's CAN interface. on_frame() routes a received frame to its
// decoder and keeps the latest accepted attitude, rates, depth and mode command with their stamps.
// Every rejected frame increments exactly one named counter:
//   unknown_id (not a qnav input id), format (extended/FD/RTR where classic data is expected),
//   length (shorter than the DBC's DLC), range (a signal outside its DBC range), invalid (sender says
//   the data is not valid), stale (rolling counter repeated, or sample time not after the last one),
//   error_frame (bus error frames, counted, never decoded).
// CAN frames carry a hardware CRC; the payload has no checksum of its own, so there is no checksum
// counter here. latest_*() returns kNotReady before the first sample and kTimeout when the newest is
// older than max_age_ns. O(signals) per frame, no heap.
#pragma once

#include <cstdint>

#include "drivers/qnavcan/messages.hpp"
#include "hal/core/can.hpp"
#include "nav/core/counters.hpp"

namespace qnav::drivers::qnavcan {

enum class RxCounter : std::uint8_t { kUnknownId, kFormat, kLength, kRange, kInvalid, kStale, kErrorFrame, kCount };
inline constexpr const char* kRxCounterNames[] = {"unknown_id", "format", "length", "range", "invalid", "stale", "error_frame"};

template <typename T>
struct Stamped {
  T value{};
  hal::SampleStamp stamp;
  bool present = false;
};

class QnavCanReceiver {
 public:
  // Returns ok when the frame was accepted; otherwise the reason (the counter is already bumped).
  Status on_frame(const hal::CanRxFrame& rx) noexcept;

  Status latest_attitude(std::int64_t now_ns, std::int64_t max_age_ns, Stamped<AttitudeIn>& out) const noexcept {
    return latest(attitude_, now_ns, max_age_ns, out);
  }
  Status latest_rates(std::int64_t now_ns, std::int64_t max_age_ns, Stamped<RatesIn>& out) const noexcept {
    return latest(rates_, now_ns, max_age_ns, out);
  }
  Status latest_depth(std::int64_t now_ns, std::int64_t max_age_ns, Stamped<DepthIn>& out) const noexcept {
    return latest(depth_, now_ns, max_age_ns, out);
  }
  const Stamped<ModeCmd>& last_mode() const noexcept { return mode_; }
  const CounterSet<RxCounter>& counters() const noexcept { return counters_; }
  std::uint32_t accepted() const noexcept { return accepted_; }

 private:
  template <typename T>
  static Status latest(const Stamped<T>& s, std::int64_t now_ns, std::int64_t max_age_ns, Stamped<T>& out) noexcept {
    if (!s.present) return Status(StatusCode::kNotReady, "no sample yet");
    out = s;
    if (now_ns - s.stamp.sample_ns > max_age_ns) return Status(StatusCode::kTimeout, "newest sample too old");
    return Status::ok();
  }
  template <typename T>
  Status accept(const hal::CanRxFrame& rx, Stamped<T>& slot) noexcept;

  Stamped<AttitudeIn> attitude_;
  Stamped<RatesIn> rates_;
  Stamped<DepthIn> depth_;
  Stamped<ModeCmd> mode_;
  CounterSet<RxCounter> counters_{kRxCounterNames};
  std::uint32_t accepted_ = 0;
};

}  // namespace qnav::drivers::qnavcan
