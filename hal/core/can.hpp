// CAN bus interface and value types (classic CAN 2.0A/B and CAN FD).
//  - CanFrame: id (11 or 29 bit), flags, len (bytes, 0..8 classic, 0..64 FD), data.
//  - CanFilter: kernel-style acceptance filter, match when (rx_id & mask) == (id & mask); the
//    extended/rtr bits take part in the match when `match_ide_rtr` is set (the exact-ID fast path).
//  - CanBus: send() never blocks (a full TX queue is kCapacityExceeded, "not now"); receive() waits
//    at most timeout_ms (0 = poll) and returns kTimeout when nothing arrived. Error frames are
//    delivered as frames with `error` set (class bits in id, details in data, as linux/can/error.h).
// Implementations: hal/linux SocketCanBus (CAN_RAW), hal/sim SimCanBus (in-process), CanLogReplay.
// No call allocates after open.
#pragma once

#include <cstddef>
#include <cstdint>

#include "hal/core/stamp.hpp"
#include "nav/core/status.hpp"

namespace qnav::hal {

constexpr std::uint32_t kCanSffMask = 0x7FFu;
constexpr std::uint32_t kCanEffMask = 0x1FFFFFFFu;
constexpr std::size_t kCanMaxDataClassic = 8;
constexpr std::size_t kCanMaxDataFd = 64;

// Error-frame class bits (linux/can/error.h values, kept here so nothing above hal/ needs the header).
namespace can_error {
constexpr std::uint32_t kTxTimeout = 0x001;
constexpr std::uint32_t kLostArbitration = 0x002;
constexpr std::uint32_t kController = 0x004;
constexpr std::uint32_t kProtocol = 0x008;
constexpr std::uint32_t kTransceiver = 0x010;
constexpr std::uint32_t kNoAck = 0x020;
constexpr std::uint32_t kBusOff = 0x040;
constexpr std::uint32_t kBusError = 0x080;
constexpr std::uint32_t kRestarted = 0x100;
constexpr std::uint32_t kCounters = 0x200;
}  // namespace can_error

struct CanFrame {
  std::uint32_t id = 0;      // 11-bit or 29-bit identifier; for error frames, the class bits
  bool extended = false;     // 29-bit identifier
  bool rtr = false;          // remote request (classic only)
  bool error = false;        // error frame (receive only)
  bool fd = false;           // CAN FD frame
  bool brs = false;          // FD bit-rate switch
  bool esi = false;          // FD error state indicator
  std::uint8_t len = 0;      // payload bytes
  std::uint8_t data[kCanMaxDataFd] = {};
};

// Valid FD payload lengths are 0..8, 12, 16, 20, 24, 32, 48, 64.
constexpr bool can_fd_len_valid(std::size_t len) noexcept {
  return len <= 8 || len == 12 || len == 16 || len == 20 || len == 24 || len == 32 || len == 48 || len == 64;
}
// Checks id range, length and flag combinations; the one validity rule every backend applies.
Status validate_can_frame(const CanFrame& f) noexcept;

struct CanRxFrame {
  CanFrame frame;
  SampleStamp stamp;
};

struct CanFilter {
  std::uint32_t id = 0;
  std::uint32_t mask = 0;
  bool extended = false;
  bool match_ide_rtr = true;  // compare the extended/rtr flags too (kernel fast path, no alias of 0x123 on 0x1xxxx123)
  bool invert = false;
};

// The filter rule every backend implements (the kernel's for SocketCAN, this function for sim).
bool can_filter_matches(const CanFilter& f, const CanFrame& frame) noexcept;

struct CanBusStats {
  std::uint32_t rx_frames = 0;
  std::uint32_t tx_frames = 0;
  std::uint32_t rx_dropped = 0;   // kernel/sim queue overflow
  std::uint32_t tx_busy = 0;      // send() refused: TX queue full
  std::uint32_t error_frames = 0;
  std::uint32_t bus_off = 0;
};

class CanBus {
 public:
  virtual ~CanBus() = default;
  virtual Status send(const CanFrame& frame) noexcept = 0;
  virtual Status receive(CanRxFrame& out, int timeout_ms) noexcept = 0;
  virtual CanBusStats stats() const noexcept = 0;
};

}  // namespace qnav::hal
