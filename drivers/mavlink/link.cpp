#include "drivers/mavlink/link.hpp"

namespace qnav::drivers::mavlink {

Status Link::send_payload(std::uint32_t msgid, const std::uint8_t* payload, std::size_t len,
                          std::uint64_t sign_timestamp_10us) noexcept {
  Result<std::size_t> n = encoder_.encode(msgid, payload, len, Span<std::uint8_t>(tx_));
  if (!n.is_ok()) {
    counters_.increment(LinkCounter::kEncodeError);
    return n.status();
  }
  std::size_t frame_len = n.value();
  if (sign_outgoing_) {
    Result<std::size_t> s = sign_frame(tx_, frame_len, sizeof(tx_), key_, sign_timestamp_10us);
    if (!s.is_ok()) {
      counters_.increment(LinkCounter::kEncodeError);
      return s.status();
    }
    frame_len = s.value();
  }
  Result<std::size_t> w = port_.write(Span<const std::uint8_t>(tx_, frame_len));
  if (!w.is_ok()) {
    counters_.increment(LinkCounter::kTxError);
    return w.status();
  }
  if (w.value() != frame_len) {
    counters_.increment(LinkCounter::kTxShort);
    return Status(StatusCode::kCapacityExceeded, "mavlink: the port took part of the frame (buffer full)");
  }
  ++stats_.frames_tx;
  return Status::ok();
}

}  // namespace qnav::drivers::mavlink
