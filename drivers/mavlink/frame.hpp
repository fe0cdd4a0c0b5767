// MAVLink framing, written from the MAVLink 2 specification (not from a generated library).
//  - MAVLink 2 frame: 0xFD | len | incompat_flags | compat_flags | seq | sysid | compid | msgid (3 bytes,
//    little endian) | payload (len bytes) | checksum (2 bytes, little endian) | signature (13 bytes, only
//    when incompat_flags & kIncompatSigned). MAVLink 1 frame: 0xFE | len | seq | sysid | compid | msgid
//    (1 byte) | payload | checksum.
//  - Checksum: CRC-16/MCRF4XX (X.25: polynomial 0x1021 reflected, init 0xFFFF, no final xor) over every
//    byte after the magic up to the end of the payload, then over the message's CRC_EXTRA byte.
//  - Payload: little endian, fields largest type first, extension fields after in definition order;
//    trailing zero bytes are cut on send (never below 1 byte) and restored as zeros on receive.
// message_info() is the table of the messages this codec knows (id, CRC_EXTRA, lengths): a frame of
// any other id cannot be checked (no CRC_EXTRA) and is counted by the parser as unknown.
// FrameEncoder writes frames for one sender (system id, component id) with its own sequence number.
// Bounds: a frame is at most kMaxFrameBytes (280); encoding is O(payload); no heap, no OS call.
#pragma once

#include <cstddef>
#include <cstdint>

#include "nav/core/span.hpp"
#include "nav/core/status.hpp"

namespace qnav::drivers::mavlink {

constexpr std::uint8_t kMagicV2 = 0xFD;
constexpr std::uint8_t kMagicV1 = 0xFE;
constexpr std::size_t kHeaderV2 = 10;  // magic .. msgid
constexpr std::size_t kHeaderV1 = 6;
constexpr std::size_t kChecksumBytes = 2;
constexpr std::size_t kSignatureBytes = 13;
constexpr std::size_t kMaxPayload = 255;
constexpr std::size_t kMaxFrameBytes = kHeaderV2 + kMaxPayload + kChecksumBytes + kSignatureBytes;  // 280
constexpr std::uint8_t kIncompatSigned = 0x01;

// CRC-16/MCRF4XX, one byte at a time (the X.25 accumulate step of the specification).
constexpr std::uint16_t crc_accumulate(std::uint8_t b, std::uint16_t crc) noexcept {
  std::uint8_t t = static_cast<std::uint8_t>(b ^ static_cast<std::uint8_t>(crc & 0xFF));
  t = static_cast<std::uint8_t>(t ^ static_cast<std::uint8_t>(t << 4));
  return static_cast<std::uint16_t>((crc >> 8) ^ (static_cast<std::uint16_t>(t) << 8) ^
                                    (static_cast<std::uint16_t>(t) << 3) ^ (t >> 4));
}
constexpr std::uint16_t kCrcInit = 0xFFFF;
std::uint16_t crc_mcrf4xx(const std::uint8_t* data, std::size_t n, std::uint16_t crc = kCrcInit) noexcept;

// One known message: id, CRC_EXTRA, payload length without extensions (MAVLink 1) and with them.
struct MessageInfo {
  std::uint32_t id;
  std::uint8_t crc_extra;
  std::uint8_t base_len;
  std::uint8_t full_len;
  const char* name;
};
// nullptr when the id is not in the table. O(table size) = O(17).
const MessageInfo* message_info(std::uint32_t id) noexcept;
Span<const MessageInfo> known_messages() noexcept;

// A received (or to-be-sent) frame; payload always restored to the message's full length with zeros.
struct Frame {
  std::uint8_t version = 2;      // 1 or 2
  std::uint8_t wire_len = 0;     // payload bytes on the wire (after truncation)
  std::uint8_t incompat_flags = 0;
  std::uint8_t compat_flags = 0;
  std::uint8_t seq = 0;
  std::uint8_t sysid = 0;
  std::uint8_t compid = 0;
  std::uint32_t msgid = 0;
  bool is_signed = false;        // carried a signature
  bool signature_verified = false;  // signature checked against the configured key (and not a replay)
  std::uint8_t link_id = 0;         // signed frames: the signature's link id
  std::uint64_t sign_timestamp = 0; // signed frames: 10 us units since 2015-01-01
  std::uint8_t payload_len = 0;  // = message_info(msgid)->full_len
  std::uint8_t payload[kMaxPayload] = {};
};

// Writes complete frames for one sender. Not thread-safe (one encoder per sending thread).
class FrameEncoder {
 public:
  FrameEncoder(std::uint8_t sysid, std::uint8_t compid) noexcept : sysid_(sysid), compid_(compid) {}

  // Encodes msgid's payload (payload_len bytes, <= the message's full length; shorter = zero-extended)
  // as a MAVLink 2 frame into out, truncating trailing zeros; returns the frame size in bytes.
  // kNotFound: id not in message_info(); kInvalidArgument: payload longer than the message;
  // kCapacityExceeded: out too small (nothing written, sequence unchanged).
  Result<std::size_t> encode(std::uint32_t msgid, const std::uint8_t* payload, std::size_t payload_len,
                             Span<std::uint8_t> out) noexcept;

  std::uint8_t next_seq() const noexcept { return seq_; }
  std::uint8_t sysid() const noexcept { return sysid_; }
  std::uint8_t compid() const noexcept { return compid_; }

 private:
  std::uint8_t sysid_;
  std::uint8_t compid_;
  std::uint8_t seq_ = 0;
};

// The signing secret (32 bytes) and the link id this side signs with.
struct SigningKey {
  std::uint8_t secret[32] = {};
  std::uint8_t link_id = 0;
};

// Appends a MAVLink 2 signature to a complete unsigned frame `frame` (frame_len bytes, as FrameEncoder
// wrote it) in place: sets the signed incompat flag, recomputes the CRC, appends link id, timestamp
// (10 us units since 2015-01-01, 48 bits) and the first 6 bytes of SHA-256(secret + frame + link id +
// timestamp). frame must have room for 13 more bytes (capacity); returns the new length.
Result<std::size_t> sign_frame(std::uint8_t* frame, std::size_t frame_len, std::size_t capacity, const SigningKey& key,
                               std::uint64_t timestamp_10us) noexcept;

}  // namespace qnav::drivers::mavlink
