// JsfFramer: cuts a live JSF byte stream (TCP socket, serial link, file) into whole messages. Bytes
// may arrive in chunks of any size, split anywhere. One fixed buffer (max_message_bytes, allocated
// in init()); no allocation while framing.
//   while (!chunk.empty()) {
//     const std::size_t used = framer.feed(chunk);   // stops after completing a message
//     chunk = chunk.subspan(used, chunk.size() - used);
//     JsfMessageView m;
//     while (framer.next(m)) handle(m);              // views valid until the next feed()
//   }
// Robustness: bytes before a sync word (0x1601) are dropped and counted; a header whose size
// field is negative, above 16 MiB or larger than the buffer is counted and the framer
// re-synchronises one byte later (a damaged size field is never trusted to skip data); a sonar data
// message (type 80) whose size field disagrees with its own sample count and format is counted as a
// bad header the same way, before its body is read. So it never stalls, loops or swallows the
// messages that follow a damaged one.
// Cost: O(bytes fed) copying; O(16) per re-synchronisation step.
//
// JsfPingAssembler: pairs the port (channel 0) and starboard (channel 1) message-80 records of the
// same ping and subsystem into one sonar::SonarPing (fixed buffers from init()).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>

#include "drivers/sidescan/jsf_parser.hpp"
#include "nav/core/counters.hpp"
#include "nav/sonar/sonar_types.hpp"

namespace qnav::sidescan {

enum class JsfCounter : std::uint8_t {
  kResyncBytes,   // bytes dropped looking for a sync word
  kBadHeader,     // sync found but size field absurd
  kOversize,      // size field larger than the buffer (re-synchronised, not skipped)
  kMessages,      // complete messages delivered
  kCount
};
inline constexpr const char* kJsfCounterNames[] = {"resync_bytes", "bad_header", "oversize", "messages"};

struct JsfMessageView {
  JsfMessageHeader header;
  Span<const std::uint8_t> body;
};

class JsfFramer {
 public:
  Status init(std::size_t max_message_bytes) noexcept;
  std::size_t feed(Span<const std::uint8_t> bytes) noexcept;
  bool next(JsfMessageView& out) noexcept;
  // Bytes held in an incomplete message (for end-of-file truncation reports).
  std::size_t pending_bytes() const noexcept { return have_ - delivered_; }
  const CounterSet<JsfCounter>& counters() const noexcept { return counters_; }

 private:
  void drop_front(std::size_t n) noexcept;
  void consume_front(std::size_t n) noexcept;
  void resync() noexcept;
  bool frame_buffered() noexcept;

  std::unique_ptr<std::uint8_t[]> buf_;
  std::size_t cap_ = 0;
  std::size_t have_ = 0;      // bytes held in buf_, from a (candidate) sync word on
  std::size_t want_ = 0;      // bytes buf_ must hold before the framing can go on
  std::size_t need_ = 0;      // total bytes of the message at the front (0 = not yet known)
  std::size_t delivered_ = 0; // bytes of the message handed out by next(), dropped at the next feed()
  bool ready_ = false;
  JsfMessageHeader header_{};
  CounterSet<JsfCounter> counters_{kJsfCounterNames};
};

enum class JsfPingCounter : std::uint8_t {
  kBadSonarMessage,   // message 80 that failed to decode
  kUnpairedChannel,   // a side replaced before its partner arrived
  kOtherMessages,     // message types other than 80 (skipped)
  kOtherChannels,     // channels other than 0/1 or unselected subsystems
  kCount
};
inline constexpr const char* kJsfPingCounterNames[] = {"bad_sonar_message", "unpaired_channel", "other_messages",
                                                       "other_channels"};

class JsfPingAssembler {
 public:
  // subsystem: which side-scan subsystem to assemble (20 low frequency, 21 high); -1 = the first seen.
  Status init(std::size_t max_samples_per_side, int subsystem = -1) noexcept;
  // Offers one framed message. Returns true when a full ping (both sides) is ready in ping().
  bool add(const JsfMessageView& m) noexcept;
  // The last complete ping; spans point into the assembler's buffers (valid until the next add()).
  const sonar::SonarPing& ping() const noexcept { return ping_; }
  const JsfSonarData& port_data() const noexcept { return data_[0]; }
  const JsfSonarData& stbd_data() const noexcept { return data_[1]; }
  const CounterSet<JsfPingCounter>& counters() const noexcept { return counters_; }
  Status last_error() const noexcept { return last_error_; }

 private:
  std::unique_ptr<float[]> mem_;
  std::size_t cap_ = 0;
  float* side_[2] = {nullptr, nullptr};
  float* scratch_ = nullptr;
  bool have_[2] = {false, false};
  JsfSonarData data_[2];
  int subsystem_ = -1;
  sonar::SonarPing ping_{};
  Status last_error_{};
  CounterSet<JsfPingCounter> counters_{kJsfPingCounterNames};
};

}  // namespace qnav::sidescan
