#include "drivers/dronecan/transfer.hpp"

#include <cstring>

#include "nav/core/crc.hpp"

namespace qnav::drivers::dronecan {

FrameId parse_frame_id(std::uint32_t id) noexcept {
  FrameId f;
  f.priority = static_cast<std::uint8_t>((id >> 24) & 0x1Fu);
  f.service = ((id >> 7) & 1u) != 0;
  f.source_node = static_cast<std::uint8_t>(id & 0x7Fu);
  f.data_type_id = static_cast<std::uint16_t>((id >> 8) & 0xFFFFu);
  return f;
}

std::uint32_t make_message_id(std::uint8_t priority, std::uint16_t data_type_id, std::uint8_t source_node) noexcept {
  return (static_cast<std::uint32_t>(priority & 0x1Fu) << 24) | (static_cast<std::uint32_t>(data_type_id) << 8) |
         (source_node & 0x7Fu);
}

std::uint16_t signature_crc_seed(std::uint64_t signature) noexcept {
  std::uint8_t b[8];
  for (int i = 0; i < 8; ++i) b[i] = static_cast<std::uint8_t>(signature >> (8 * i));
  return crc16_ccitt_false(b, 8, 0xFFFF);
}

std::uint16_t transfer_crc(std::uint64_t signature, const std::uint8_t* payload, std::size_t n) noexcept {
  return crc16_ccitt_false(payload, n, signature_crc_seed(signature));
}

const DataTypeSpec* Reassembler::find_type(std::uint16_t id) const noexcept {
  for (const DataTypeSpec& t : types_)
    if (t.id == id) return &t;
  return nullptr;
}

Reassembler::Session* Reassembler::find_session(std::uint16_t dtid, std::uint8_t src, bool create) noexcept {
  for (Session& s : sessions_)
    if (s.data_type_id == dtid && s.source_node == src) return &s;
  if (!create) return nullptr;
  Session* s = sessions_.emplace_back();
  if (s == nullptr) return nullptr;
  s->data_type_id = dtid;
  s->source_node = src;
  return s;
}

bool Reassembler::on_frame(const hal::CanRxFrame& rx, Transfer& out) noexcept {
  const hal::CanFrame& f = rx.frame;
  if (f.error || f.rtr || !f.extended) {
    counters_.increment(ReasmCounter::kNotExtended);
    return false;
  }
  if (f.len < 1 || f.len > hal::kCanMaxDataClassic || f.fd) {
    counters_.increment(ReasmCounter::kEmptyFrame);
    return false;
  }
  const FrameId id = parse_frame_id(f.id);
  if (id.service) {
    counters_.increment(ReasmCounter::kService);
    return false;
  }
  if (id.source_node == 0) {
    counters_.increment(ReasmCounter::kAnonymous);
    return false;
  }
  const DataTypeSpec* type = find_type(id.data_type_id);
  if (type == nullptr) {
    ++ignored_;
    return false;
  }
  const std::uint8_t tail = f.data[f.len - 1];
  const bool sot = (tail & kTailStart) != 0;
  const bool eot = (tail & kTailEnd) != 0;
  const bool toggle = (tail & kTailToggle) != 0;
  const std::uint8_t tid = tail & 0x1Fu;
  const std::size_t data_len = f.len - 1u;
  const std::int64_t t = rx.stamp.sample_ns;

  if (sot && eot) {  // single-frame transfer: no CRC
    if (toggle) {
      counters_.increment(ReasmCounter::kToggle);
      return false;
    }
    out.data_type_id = id.data_type_id;
    out.source_node = id.source_node;
    out.transfer_id = tid;
    out.priority = id.priority;
    out.stamp = rx.stamp;
    out.payload_len = data_len;
    std::memcpy(out.payload, f.data, data_len);
    return true;
  }
  Session* s = find_session(id.data_type_id, id.source_node, sot);
  if (s == nullptr) {
    counters_.increment(sot ? ReasmCounter::kNoSession : ReasmCounter::kMissedStart);
    return false;
  }
  if (s->active && t - s->last_ns > kTransferTimeoutNs) {
    counters_.increment(ReasmCounter::kTimeout);
    s->active = false;
  }
  if (sot) {
    if (s->active) counters_.increment(ReasmCounter::kIncomplete);  // a previous transfer never ended
    if (toggle) {
      counters_.increment(ReasmCounter::kToggle);
      s->active = false;
      return false;
    }
    if (f.len != hal::kCanMaxDataClassic) {  // a multi-frame start is always a full frame
      counters_.increment(ReasmCounter::kLength);
      s->active = false;
      return false;
    }
    s->active = true;
    s->transfer_id = tid;
    s->next_toggle = true;
    s->crc = static_cast<std::uint16_t>(f.data[0] | (f.data[1] << 8));
    s->first_ns = t;
    s->last_ns = t;
    s->priority = id.priority;
    s->len = data_len - 2;
    std::memcpy(s->buf, f.data + 2, s->len);
    return false;
  }
  if (!s->active || tid != s->transfer_id) {
    counters_.increment(ReasmCounter::kMissedStart);
    return false;
  }
  if (toggle != s->next_toggle) {
    counters_.increment(ReasmCounter::kToggle);
    s->active = false;
    return false;
  }
  if (s->len + data_len > type->max_payload || s->len + data_len > kMaxPayload || (!eot && f.len != hal::kCanMaxDataClassic)) {
    counters_.increment(ReasmCounter::kLength);
    s->active = false;
    return false;
  }
  std::memcpy(s->buf + s->len, f.data, data_len);
  s->len += data_len;
  s->next_toggle = !s->next_toggle;
  s->last_ns = t;
  if (!eot) return false;
  s->active = false;
  if (transfer_crc(type->signature, s->buf, s->len) != s->crc) {
    counters_.increment(ReasmCounter::kCrc);
    return false;
  }
  out.data_type_id = id.data_type_id;
  out.source_node = id.source_node;
  out.transfer_id = tid;
  out.priority = s->priority;
  out.stamp.sample_ns = s->first_ns;
  out.stamp.arrival_ns = rx.stamp.arrival_ns;
  out.payload_len = s->len;
  std::memcpy(out.payload, s->buf, s->len);
  return true;
}

std::size_t split_transfer(std::uint64_t signature, std::uint32_t can_id, std::uint8_t transfer_id,
                           const std::uint8_t* payload, std::size_t n, hal::CanFrame* out, std::size_t max_frames) noexcept {
  const std::uint8_t tid = transfer_id & 0x1Fu;
  if (n <= 7) {
    if (max_frames < 1) return 0;
    hal::CanFrame& f = out[0];
    f = hal::CanFrame{};
    f.id = can_id;
    f.extended = true;
    std::memcpy(f.data, payload, n);
    f.data[n] = static_cast<std::uint8_t>(kTailStart | kTailEnd | tid);
    f.len = static_cast<std::uint8_t>(n + 1);
    return 1;
  }
  const std::uint16_t crc = transfer_crc(signature, payload, n);
  const std::size_t total = n + 2;
  const std::size_t frames = (total + 6) / 7;
  if (frames > max_frames) return 0;
  std::size_t src = 0;  // index into the CRC+payload stream
  bool toggle = false;
  for (std::size_t k = 0; k < frames; ++k) {
    hal::CanFrame& f = out[k];
    f = hal::CanFrame{};
    f.id = can_id;
    f.extended = true;
    std::size_t len = 0;
    while (len < 7 && src < total) {
      f.data[len++] = src == 0 ? static_cast<std::uint8_t>(crc & 0xFF)
                              : src == 1 ? static_cast<std::uint8_t>(crc >> 8) : payload[src - 2];
      ++src;
    }
    std::uint8_t tail = tid;
    if (k == 0) tail |= kTailStart;
    if (k + 1 == frames) tail |= kTailEnd;
    if (toggle) tail |= kTailToggle;
    toggle = !toggle;
    f.data[len] = tail;
    f.len = static_cast<std::uint8_t>(len + 1);
  }
  return frames;
}

}  // namespace qnav::drivers::dronecan
