// Streaming MAVLink parser: bytes in any split (one at a time, whole datagrams, serial reads), frames
// out. Accepts MAVLink 2 and MAVLink 1 frames of the messages in message_info(); the payload is
// restored to the message's full length with zeros (truncated extensions and trailing fields read 0).
// Contract:
//  - feed(bytes, on_frame) calls on_frame(const Frame&) for every valid frame, in stream order. The
//    Frame reference is valid during the call only.
//  - Every byte that is not part of a delivered frame is accounted for by one counter (ParserCounter):
//    bytes before a magic are `garbage_bytes` (counted per byte); a candidate frame that fails is counted
//    once by its reason, and the parser resynchronises at the next magic byte after the failed frame's
//    first byte (a false magic inside garbage never hides a real frame behind it).
//  - Frames of unknown ids cannot be checked (no CRC_EXTRA): counted `unknown_message` and skipped
//    whole by their length field.
//  - Signed frames (incompat flag 0x01): without a key they are refused (`signed_refused`); with a key
//    (set_signing_key) the signature (SHA-256) is verified (`bad_signature`) and the timestamp must
//    increase per (system, component, link) stream (`replay`) and be no more than one minute
//    (kSigningWindow10us = 6,000,000 x 10 us, the signing specification's rule) behind the local
//    timestamp (`stale_timestamp`): the newest of set_local_timestamp() (the caller's clock) and every
//    verified frame's timestamp. So a stream new to this parser (after a restart, or a new link id)
//    cannot replay a captured frame from further back. Verified frames carry
//    Frame::signature_verified. Unknown incompat flags: `incompat_flags`.
// Memory: one 280-byte frame buffer + one Frame (~300 bytes) + kMaxSigningStreams replay entries,
// all members; no heap. Time: O(1) per byte on a clean stream; each rejected candidate costs at most
// O(kMaxFrameBytes) (one CRC + one rescan of the buffer), a signed frame one SHA-256 of <= 300 bytes.
#pragma once

#include <cstddef>
#include <cstdint>

#include "drivers/mavlink/frame.hpp"
#include "nav/core/counters.hpp"
#include "nav/core/span.hpp"

namespace qnav::drivers::mavlink {

enum class ParserCounter : std::uint8_t {
  kGarbageBytes,     // bytes outside any frame (no magic)
  kBadCrc,           // checksum does not match (corrupt frame or false magic)
  kUnknownMessage,   // a frame whose id is not in message_info() (skipped by its length)
  kBadLength,        // longer than the message (MAVLink 1: also shorter than its base length)
  kIncompatFlags,    // incompat flags other than signing
  kSignedRefused,    // signed frame and no signing key configured
  kBadSignature,     // signature does not match the key
  kReplay,           // signature timestamp not newer than the last one of its stream
  kSigningStreams,   // signed frame from a new stream and the stream table is full
  kV1Refused,        // a valid MAVLink 1 frame while set_accept_v1(false)
  kStaleTimestamp,   // signed frame more than one minute behind the local timestamp
  kCount
};
inline constexpr const char* kParserCounterNames[] = {"garbage_bytes",  "bad_crc",        "unknown_message",
                                                      "bad_length",     "incompat_flags", "signed_refused",
                                                      "bad_signature",  "replay",         "signing_streams",
                                                      "v1_refused",     "stale_timestamp"};

struct ParserStats {
  std::uint32_t frames_v2 = 0;      // delivered MAVLink 2 frames
  std::uint32_t frames_v1 = 0;      // delivered MAVLink 1 frames
  std::uint32_t frames_signed = 0;  // delivered frames with a verified signature
};

constexpr std::size_t kMaxSigningStreams = 16;
constexpr std::uint64_t kSigningWindow10us = 6000000;  // one minute in signing timestamp units (10 us)

class Parser {
 public:
  Parser() noexcept = default;

  // Verify signed frames with this key from now on (and reset the replay table).
  void set_signing_key(const SigningKey& key) noexcept;
  void clear_signing_key() noexcept { has_key_ = false; }
  // The local timestamp (10 us units since 2015-01-01) moves up to t if t is newer (never back).
  void set_local_timestamp(std::uint64_t t) noexcept {
    if (t > local_timestamp_) local_timestamp_ = t;
  }
  // The newest of the caller's clock and every verified frame's timestamp.
  std::uint64_t local_timestamp() const noexcept { return local_timestamp_; }
  // Accept MAVLink 1 frames (default true); when false, valid MAVLink 1 frames count `v1_refused`.
  void set_accept_v1(bool accept) noexcept { accept_v1_ = accept; }

  template <typename OnFrame>
  void feed(Span<const std::uint8_t> bytes, OnFrame&& on_frame) noexcept {
    for (std::uint8_t b : bytes) {
      // extract() always leaves len_ < kMaxFrameBytes (a complete candidate is resolved at once);
      // the guard keeps the buffer bounded should that ever change.
      if (len_ == kMaxFrameBytes) {
        counters_.increment(ParserCounter::kGarbageBytes);
        drop(1);
      }
      buf_[len_++] = b;
      if (len_ < need_) continue;  // the candidate at buf_[0] was checked and is still short
      while (extract()) on_frame(static_cast<const Frame&>(frame_));
    }
  }

  const CounterSet<ParserCounter>& counters() const noexcept { return counters_; }
  const ParserStats& stats() const noexcept { return stats_; }
  std::size_t buffered_bytes() const noexcept { return len_; }

 private:
  enum class Step : std::uint8_t { kNeedMore, kFrame, kDropOne, kDropFrame };
  // Looks at the buffer; true when frame_ holds a new frame (already removed from the buffer).
  bool extract() noexcept;
  Step check(std::size_t& frame_len) noexcept;
  bool verify_signature(std::size_t frame_len) noexcept;
  void drop(std::size_t n) noexcept;

  struct SignStream {
    std::uint8_t sysid = 0, compid = 0, link_id = 0;
    bool used = false;
    std::uint64_t last_timestamp = 0;
  };

  std::uint8_t buf_[kMaxFrameBytes] = {};
  std::size_t len_ = 0;
  // Bytes the candidate frame at buf_[0] needs before check() can decide anything new (its header,
  // then its whole length once the header is known); 0 after any drop. Looking the message up again
  // on every byte of a frame was most of a parse (issue 30).
  std::size_t need_ = 0;
  Frame frame_;
  bool accept_v1_ = true;
  bool has_key_ = false;
  SigningKey key_;
  SignStream streams_[kMaxSigningStreams];
  std::uint64_t local_timestamp_ = 0;
  CounterSet<ParserCounter> counters_{kParserCounterNames};
  ParserStats stats_;
};

}  // namespace qnav::drivers::mavlink
