// MavlinkLink: one MAVLink link over any hal::SerialPort (hal/linux UdpPort or TermiosSerialPort,
// hal/sim SimSerialPipe): the transport half of drivers/mavlink, the parser and encoder being the
// pure half.
//  - poll(timeout_ms, on_frame): waits at most timeout_ms for the first bytes, then at most
//    kMaxReadsPerPoll non-blocking reads of kReadChunk bytes (a UDP read is one datagram), feeds the
//    parser and calls on_frame(const Frame&, std::int64_t arrival_ns) for every frame. Returns the
//    number of frames, or the port's read error (counted rx_error).
//  - send(message[, sign_timestamp_10us]): encodes one frame from this link's (system, component)
//    with its sequence number and writes it in one write(); with a signing key set
//    (set_signing_key) the frame is signed with the timestamp the caller gives (10 us units since
//    2015-01-01, strictly increasing: the caller owns the clock). A short write (full buffer) or a
//    port error is counted and returned; a frame is never half-retried.
// Memory: a Parser (~600 B), a 2 KiB read buffer and one 280-byte frame buffer, no heap; time per poll bounded by
// kMaxReadsPerPoll * kReadChunk bytes through the parser. Not thread-safe: one thread per link (qnavd's
// io thread), or a reader and a writer thread using separate Link objects over separate ports.
#pragma once

#include <cstddef>
#include <cstdint>

#include "drivers/mavlink/frame.hpp"
#include "drivers/mavlink/messages.hpp"
#include "drivers/mavlink/parser.hpp"
#include "hal/core/serial.hpp"
#include "nav/core/counters.hpp"
#include "nav/core/span.hpp"
#include "nav/core/status.hpp"

namespace qnav::drivers::mavlink {

enum class LinkCounter : std::uint8_t { kRxError, kTxShort, kTxError, kEncodeError, kCount };
inline constexpr const char* kLinkCounterNames[] = {"rx_error", "tx_short", "tx_error", "encode_error"};

struct LinkStats {
  std::uint32_t frames_rx = 0;
  std::uint32_t frames_tx = 0;
};

class Link {
 public:
  static constexpr std::size_t kReadChunk = 2048;  // one UDP datagram of several frames (MTU 1500) whole
  static constexpr int kMaxReadsPerPoll = 16;

  Link(hal::SerialPort& port, std::uint8_t sysid, std::uint8_t compid) noexcept : port_(port), encoder_(sysid, compid) {}

  // Verify incoming signed frames with key (see Parser); sign outgoing frames when sign_outgoing.
  void set_signing_key(const SigningKey& key, bool sign_outgoing) noexcept {
    key_ = key;
    sign_outgoing_ = sign_outgoing;
    parser_.set_signing_key(key);
  }

  template <typename OnFrame>
  Result<int> poll(int timeout_ms, OnFrame&& on_frame) noexcept {
    int frames = 0;
    for (int i = 0; i < kMaxReadsPerPoll; ++i) {
      Result<hal::SerialRead> r = port_.read(Span<std::uint8_t>(rx_, kReadChunk), i == 0 ? timeout_ms : 0);
      if (!r.is_ok()) {
        counters_.increment(LinkCounter::kRxError);
        return r.status();
      }
      const hal::SerialRead got = r.value();
      if (got.bytes == 0) break;
      parser_.feed(Span<const std::uint8_t>(rx_, got.bytes), [&](const Frame& f) {
        ++frames;
        ++stats_.frames_rx;
        on_frame(f, got.arrival_ns);
      });
    }
    return frames;
  }

  template <typename M>
  Status send(const M& m, std::uint64_t sign_timestamp_10us = 0) noexcept {
    std::uint8_t payload[kMaxPayload];
    encode_payload(m, payload);
    const MessageInfo* info = message_info(M::kId);
    return send_payload(M::kId, payload, info != nullptr ? info->full_len : 0, sign_timestamp_10us);
  }
  // The same for a payload already in wire order (full length or shorter).
  Status send_payload(std::uint32_t msgid, const std::uint8_t* payload, std::size_t len,
                      std::uint64_t sign_timestamp_10us) noexcept;

  const Parser& parser() const noexcept { return parser_; }
  Parser& parser() noexcept { return parser_; }
  const CounterSet<LinkCounter>& counters() const noexcept { return counters_; }
  const LinkStats& stats() const noexcept { return stats_; }
  std::uint8_t sysid() const noexcept { return encoder_.sysid(); }
  std::uint8_t compid() const noexcept { return encoder_.compid(); }

 private:
  hal::SerialPort& port_;
  FrameEncoder encoder_;
  Parser parser_;
  SigningKey key_;
  bool sign_outgoing_ = false;
  std::uint8_t rx_[kReadChunk] = {};
  std::uint8_t tx_[kMaxFrameBytes] = {};
  CounterSet<LinkCounter> counters_{kLinkCounterNames};
  LinkStats stats_;
};

}  // namespace qnav::drivers::mavlink
