#include "drivers/qnavcan/receiver.hpp"

namespace qnav::drivers::qnavcan {

template <typename T>
Status QnavCanReceiver::accept(const hal::CanRxFrame& rx, Stamped<T>& slot) noexcept {
  T v;
  const Status s = decode(rx.frame, v);
  if (!s.is_ok()) {
    if (s == StatusCode::kTruncated) counters_.increment(RxCounter::kLength);
    else if (s == StatusCode::kOutOfRange) counters_.increment(RxCounter::kRange);
    else counters_.increment(RxCounter::kFormat);
    return s;
  }
  if (slot.present && (v.counter == slot.value.counter || rx.stamp.sample_ns <= slot.stamp.sample_ns)) {
    counters_.increment(RxCounter::kStale);
    return Status(StatusCode::kInvalidArgument, "stale: counter repeated or time not increasing");
  }
  slot.value = v;
  slot.stamp = rx.stamp;
  slot.present = true;
  ++accepted_;
  return Status::ok();
}

Status QnavCanReceiver::on_frame(const hal::CanRxFrame& rx) noexcept {
  const hal::CanFrame& f = rx.frame;
  if (f.error) {
    counters_.increment(RxCounter::kErrorFrame);
    return Status(StatusCode::kIoError, "CAN error frame");
  }
  if (f.extended || f.fd || f.rtr) {
    counters_.increment(RxCounter::kFormat);
    return Status(StatusCode::kUnsupported, "not a classic 11-bit data frame");
  }
  switch (f.id) {
    case kIdAttitudeIn: {
      AttitudeIn probe;
      // Decode first to reject `Valid = 0` only after format/length/range checks passed.
      const Status s = decode(f, probe);
      if (s.is_ok() && !probe.valid) {
        counters_.increment(RxCounter::kInvalid);
        return Status(StatusCode::kInvalidArgument, "AHRS reports no valid solution");
      }
      return accept(rx, attitude_);
    }
    case kIdRatesIn: return accept(rx, rates_);
    case kIdDepthIn: {
      DepthIn probe;
      const Status s = decode(f, probe);
      if (s.is_ok() && !probe.depth_valid) {
        counters_.increment(RxCounter::kInvalid);
        return Status(StatusCode::kInvalidArgument, "depth sensor reports invalid depth");
      }
      return accept(rx, depth_);
    }
    case kIdModeCmd: return accept(rx, mode_);
    default:
      counters_.increment(RxCounter::kUnknownId);
      return Status(StatusCode::kNotFound, "not a qnav input id");
  }
}

}  // namespace qnav::drivers::qnavcan
