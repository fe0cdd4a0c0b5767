// MavlinkWire: the bytes of qnavd's MAVLink side on the nav thread (part of MavlinkEndpoint,
// mavlink_endpoint.hpp): one drivers/mavlink Parser per link (0 UDP client, 1 UDP server, 2 serial),
// the frame encoder, the signing of what is sent and the counters of every refusal (MavCounter).
//  Signing (mavlink.key_file; the key read and checked at start by Daemon::init, mavlink_key.hpp):
//    every parser verifies signed frames with the key (bad_signature, replay, stale_timestamp: counted
//    by the parser). Everything qnavd sends is signed (link id kSignLinkId), the timestamp the newest
//    of the UTC clock (10 us units since 2015-01-01), every verified incoming timestamp, and the last
//    one sent + 1; the same timestamp is the parsers' local one (a signed frame more than a minute
//    behind it is stale). The policy (which commands must be signed) is MavlinkEndpoint's.
// Owns: the parsers (~1 KB each), the encoder, the key. Memory: no heap. Time: one encode (and one
// SHA-256 signature with a key) per frame sent.
#pragma once

#include <cstdint>

#include "drivers/mavlink/frame.hpp"
#include "drivers/mavlink/messages.hpp"
#include "drivers/mavlink/parser.hpp"
#include "firmware/qnavd/config.hpp"
#include "firmware/qnavd/messages.hpp"
#include "hal/core/clock.hpp"
#include "hal/linux/monotonic_clock.hpp"
#include "nav/core/counters.hpp"
#include "nav/core/spsc_ring.hpp"

namespace qnav::daemon {

constexpr std::uint8_t kSignLinkId = 0;  // the link id of qnavd's signatures (one stream: the same bytes go to every link)

enum class MavCounter : std::uint8_t {
  kRxQueueOverflow,  // (io) bytes dropped before parsing: reported from IoCounters
  kParserRejects,    // every parser reject (garbage, bad CRC, unknown id, bad length, signing ...)
  kForeignSystem,    // a frame from a system other than the autopilot's (ignored)
  kUnusedMessage,    // a known message qnavd does not read (ignored)
  kCmdWrongSender,   // a mode command from another system / component: refused (DENIED)
  kCmdNotForUs,      // a COMMAND_LONG addressed to another system or component (ignored)
  kCmdUnsupported,   // a COMMAND_LONG of another command from the autopilot (UNSUPPORTED)
  kCmdBadParam,      // a mode command with parameters out of range (DENIED)
  kBadAttitude,      // an ATTITUDE with non-finite angles
  kTxQueueFull,      // a frame not sent: the mav_tx queue was full
  kCmdUnsigned,      // a mode command not signed with mavlink.key_file's key: refused (no answer)
  kCount
};
inline constexpr const char* kMavCounterNames[] = {"rx_overflow",     "parser_rejects", "foreign_system", "unused_message", "cmd_wrong_sender",
                                                   "cmd_not_for_us", "cmd_unsupported", "cmd_bad_param",  "bad_attitude",   "tx_queue_full",
                                                   "cmd_unsigned"};

class MavlinkWire {
 public:
  static constexpr int kLinks = 3;
  // utc: the wall clock of signing timestamps (ns since 1970); nullptr = the system's (CLOCK_REALTIME).
  MavlinkWire(const DaemonConfig& c, const hal::Clock* utc) noexcept;
  MavlinkWire(const MavlinkWire&) = delete;
  MavlinkWire& operator=(const MavlinkWire&) = delete;
  drivers::mavlink::Parser& parser(std::uint8_t link) noexcept { return parsers_[link < kLinks ? link : kLinks - 1]; }
  CounterSet<MavCounter>& counters() noexcept { return counters_; }
  const CounterSet<MavCounter>& counters() const noexcept { return counters_; }

  // mavlink.key_file configured: mode commands must be signed; has_key: the key loaded (what is sent is signed).
  bool signing_required() const noexcept { return signing_required_; }
  bool has_key() const noexcept { return has_key_; }
  // Before parsing (with a key): the parsers' local timestamp moves up to the clock or the newest seen or sent.
  void refresh_local_timestamp() noexcept;
  // The newest signing timestamp (10 us units since 2015-01-01): qnavd's local one.
  std::uint64_t local_timestamp() const noexcept;
  std::uint32_t parser_rejects() const noexcept;
  // The parsers' signing refusals summed (bad_signature, replay, stale_timestamp, signed_refused, signing_streams).
  std::uint32_t signing_rejects() const noexcept;
  // The parsers' counter c summed over the links.
  std::uint32_t parser_count(drivers::mavlink::ParserCounter c) const noexcept;

  // m encoded (and signed) into tx; a full queue is counted (kTxQueueFull).
  template <typename M>
  void send(const M& m, SpscRing<MavBytes>& tx) noexcept {
    MavBytes b;
    Result<std::size_t> n = drivers::mavlink::encode(enc_, m, Span<std::uint8_t>(b.data, kMavBytes));
    if (!n) return;  // every message here is in the codec's table and fits
    push(b, n.value(), tx);
  }
  void status_text(std::uint8_t severity, const char* text, SpscRing<MavBytes>& tx) noexcept;

 private:
  void push(MavBytes& b, std::size_t len, SpscRing<MavBytes>& tx) noexcept;
  // The next signing timestamp to send (strictly increasing), and the parsers' local timestamp moved up to it.
  std::uint64_t next_sign_timestamp() noexcept;
  std::uint64_t utc_10us() const noexcept;

  drivers::mavlink::FrameEncoder enc_;
  drivers::mavlink::Parser parsers_[kLinks];
  hal::RealtimeClock system_utc_;
  const hal::Clock* utc_;
  bool signing_required_ = false, has_key_ = false;
  drivers::mavlink::SigningKey key_;
  std::uint64_t last_sign_ts_ = 0;
  CounterSet<MavCounter> counters_{kMavCounterNames};
};

}  // namespace qnav::daemon
