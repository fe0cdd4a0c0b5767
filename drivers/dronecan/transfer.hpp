// DroneCAN (UAVCAN v0) transport on classic CAN, receive side (libcanard v0 rules):
//  - 29-bit id: message = priority<<24 | data_type_id<<8 | source_node (service bit 7 = 0).
//  - tail byte (last byte of every frame): bit7 start, bit6 end, bit5 toggle, bits4..0 transfer id.
//  - multi-frame: first frame starts with the transfer CRC (low byte first); toggle starts at 0 and
//    alternates; CRC-16/CCITT-FALSE over the 64-bit data type signature (LSB first) then the payload.
//  - a session per (source node, data type), reset after kTransferTimeoutNs (2 s) without a frame.
// Reassembler: kMaxSessions sessions of kMaxPayload bytes, fixed at compile time. Rejected frames
// bump one counter each (see ReasmCounter). Worst case per frame: O(kMaxSessions + 8) plus, at the
// end of a transfer, O(kMaxPayload) for the CRC. No heap.
#pragma once

#include <cstddef>
#include <cstdint>

#include "hal/core/can.hpp"
#include "nav/core/counters.hpp"
#include "nav/core/fixed_vector.hpp"
#include "nav/core/span.hpp"

namespace qnav::drivers::dronecan {

constexpr std::int64_t kTransferTimeoutNs = 2000000000LL;
constexpr std::size_t kMaxPayload = 128;  // RawIMU is at most 120 bytes
constexpr std::size_t kMaxSessions = 8;

struct FrameId {
  std::uint8_t priority = 0;
  std::uint16_t data_type_id = 0;
  std::uint8_t source_node = 0;
  bool service = false;
};
FrameId parse_frame_id(std::uint32_t id) noexcept;
std::uint32_t make_message_id(std::uint8_t priority, std::uint16_t data_type_id, std::uint8_t source_node) noexcept;

constexpr std::uint8_t kTailStart = 0x80, kTailEnd = 0x40, kTailToggle = 0x20;

// CRC-16/CCITT-FALSE seeded with the data type signature (what libcanard calls crcAddSignature).
std::uint16_t signature_crc_seed(std::uint64_t signature) noexcept;
std::uint16_t transfer_crc(std::uint64_t signature, const std::uint8_t* payload, std::size_t n) noexcept;

struct Transfer {
  std::uint16_t data_type_id = 0;
  std::uint8_t source_node = 0;
  std::uint8_t transfer_id = 0;
  std::uint8_t priority = 0;
  hal::SampleStamp stamp;  // sample_ns of the first frame, arrival_ns of the last
  std::uint8_t payload[kMaxPayload] = {};
  std::size_t payload_len = 0;
};

enum class ReasmCounter : std::uint8_t {
  kNotExtended, kService, kAnonymous, kEmptyFrame, kCrc, kToggle, kMissedStart, kLength, kTimeout,
  kIncomplete, kNoSession, kCount
};
inline constexpr const char* kReasmCounterNames[] = {"not_extended", "service", "anonymous", "empty_frame",
                                                     "crc", "toggle", "missed_start", "length", "timeout",
                                                     "incomplete", "no_session"};

// Data types the reassembler accepts, with their signatures; other types are ignored (counted in
// ignored_frames(), not as errors: a bus carries many types).
struct DataTypeSpec {
  std::uint16_t id;
  std::uint64_t signature;
  std::size_t max_payload;
};

class Reassembler {
 public:
  explicit Reassembler(Span<const DataTypeSpec> types) noexcept : types_(types) {}
  // Returns true when `out` holds a complete, CRC-checked transfer.
  bool on_frame(const hal::CanRxFrame& rx, Transfer& out) noexcept;
  const CounterSet<ReasmCounter>& counters() const noexcept { return counters_; }
  std::uint32_t ignored_frames() const noexcept { return ignored_; }

 private:
  struct Session {
    std::uint16_t data_type_id = 0;
    std::uint8_t source_node = 0;
    bool active = false;
    std::uint8_t transfer_id = 0;
    bool next_toggle = false;
    std::uint16_t crc = 0;
    std::int64_t first_ns = 0;
    std::int64_t last_ns = 0;
    std::uint8_t priority = 0;
    std::size_t len = 0;
    std::uint8_t buf[kMaxPayload] = {};
  };
  const DataTypeSpec* find_type(std::uint16_t id) const noexcept;
  Session* find_session(std::uint16_t dtid, std::uint8_t src, bool create) noexcept;

  Span<const DataTypeSpec> types_;
  FixedVector<Session, kMaxSessions> sessions_;
  CounterSet<ReasmCounter> counters_{kReasmCounterNames};
  std::uint32_t ignored_ = 0;
};

// Transmit side, for simulators, tests and the `qnav can` demo: splits a payload into classic CAN
// frames (single frame when <= 7 bytes, else CRC + 7 bytes per frame). Returns the frame count or 0
// when `out` is too small.
std::size_t split_transfer(std::uint64_t signature, std::uint32_t can_id, std::uint8_t transfer_id,
                           const std::uint8_t* payload, std::size_t n, hal::CanFrame* out, std::size_t max_frames) noexcept;

}  // namespace qnav::drivers::dronecan
