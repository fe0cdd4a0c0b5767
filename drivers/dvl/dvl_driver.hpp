// DvlSerialDriver: a DVL on a hal::SerialPort (a UART on the vehicle, a pty in tests, a sim pipe in
// replay). poll() reads what the port has (waiting at most timeout_ms for the first bytes, then at
// most kMaxReadsPerPoll non-blocking reads of kReadChunk bytes), assembles lines, parses them with
// the protocol's parser and queues velocity samples (kQueueDepth; when full the oldest is dropped and
// counted). Arrival time of a line = the read that delivered its terminator. Water Linked sample time:
// the report's time_of_validity (the DVL's clock) mapped onto the monotonic clock by hal::SensorClockMap
// from arrival - the DVL's stated latency, so reports read in one burst keep their spacing; PD6 (no
// clock of its own in the velocity lines) keeps the ensemble's first arrival.
// Bounded: one poll() handles at most kMaxReadsPerPoll * kReadChunk bytes. No heap after construction.
#pragma once

#include <cstddef>
#include <cstdint>

#include "drivers/dvl/line_assembler.hpp"
#include "drivers/dvl/pd6_parser.hpp"
#include "drivers/dvl/wl_parser.hpp"
#include "hal/core/clock_map.hpp"
#include "hal/core/serial.hpp"
#include "nav/core/ring_buffer.hpp"

namespace qnav::drivers::dvl {

enum class DvlProtocol : std::uint8_t { kWaterLinked, kPd6 };

class DvlSerialDriver {
 public:
  static constexpr std::size_t kReadChunk = 256;
  static constexpr int kMaxReadsPerPoll = 16;
  static constexpr std::size_t kQueueDepth = 16;

  DvlSerialDriver(hal::SerialPort& port, DvlProtocol protocol) noexcept : port_(port), protocol_(protocol) {}

  // Returns the number of velocity samples queued by this call.
  Result<int> poll(int timeout_ms) noexcept;
  bool pop(DvlVelocity& out) noexcept { return queue_.pop(out).is_ok(); }
  // Water Linked only: sends "<body>*xx\n" (e.g. "wcv", "wcr").
  Status send_command(const char* body) noexcept;

  // Rejections of the active parser (length includes over-long lines dropped by the assembler).
  std::uint32_t counter(DvlCounter c) const noexcept;
  std::uint32_t lines() const noexcept { return lines_; }
  std::uint32_t queue_dropped() const noexcept { return dropped_; }
  const WlParser& wl() const noexcept { return wl_; }
  const Pd6Parser& pd6() const noexcept { return pd6_; }

 private:
  void handle_line(std::int64_t arrival_ns, int& produced) noexcept;
  hal::SerialPort& port_;
  DvlProtocol protocol_;
  LineAssembler lines_asm_;
  WlParser wl_;
  Pd6Parser pd6_;
  WlMessage wl_msg_;
  Pd6Ensemble pd6_ens_;
  RingBuffer<DvlVelocity, kQueueDepth> queue_;
  hal::SensorClockMap clock_;
  std::uint8_t buf_[kReadChunk] = {};
  std::uint32_t lines_ = 0;
  std::uint32_t dropped_ = 0;
};

}  // namespace qnav::drivers::dvl
