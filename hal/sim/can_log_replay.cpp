#include "hal/sim/can_log_replay.hpp"

namespace qnav::hal {

Status CanLogReplay::send(const CanFrame& frame) noexcept {
  QNAV_RETURN_IF_ERROR(validate_can_frame(frame));
  ++stats_.tx_frames;
  return Status::ok();
}

Status CanLogReplay::receive(CanRxFrame& out, int /*timeout_ms*/) noexcept {
  for (std::size_t tries = 0; tries < kMaxSkipPerCall && pos_ < n_; ++tries) {
    std::size_t end = pos_;
    while (end < n_ && text_[end] != '\n') ++end;
    const char* line = text_ + pos_;
    const std::size_t len = end - pos_;
    pos_ = end < n_ ? end + 1 : end;
    ++line_;
    std::size_t k = 0;
    while (k < len && (line[k] == ' ' || line[k] == '\t' || line[k] == '\r')) ++k;
    if (k == len) continue;  // blank line
    CanLogRecord rec;
    if (!parse_can_log_line(line, len, rec).is_ok()) {
      bad_line();
      continue;
    }
    if (rec.has_time && !have_first_) {
      have_first_ = true;
      first_us_ = rec.time_us;
    }
    // Log time relative to the first line, in ns. candump times are 0..1e18 us, so the difference
    // cannot overflow; more than kMaxReplaySpanUs away from the first line (the ns value would
    // overflow 64 bits) is a damaged timestamp: counted as a bad line, not wrapped.
    const std::int64_t rel_us = rec.has_time ? rec.time_us - first_us_ : 0;
    if (rel_us > kMaxReplaySpanUs || rel_us < -kMaxReplaySpanUs) {
      bad_line();
      continue;
    }
    out.frame = rec.frame;
    out.stamp.sample_ns = start_ns_ + rel_us * 1000;
    out.stamp.arrival_ns = out.stamp.sample_ns;
    if (rec.frame.error) {
      ++stats_.error_frames;
      if (rec.frame.id & can_error::kBusOff) ++stats_.bus_off;
    }
    ++stats_.rx_frames;
    return Status::ok();
  }
  return Status(StatusCode::kTimeout, pos_ >= n_ ? "end of log" : "no frame");
}

}  // namespace qnav::hal
