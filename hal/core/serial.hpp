// Serial port interface (UART / RS-232 / RS-485, or a pseudo-terminal in tests).
//  - SerialConfig: baud, data bits, parity, stop bits, hardware flow control; raw mode always.
//  - read(): waits at most timeout_ms (0 = poll) for at least one byte, then returns what is
//    available up to buf.size(); returns 0 bytes on timeout (not an error) and stamps the arrival
//    time on the monotonic clock. write(): non-blocking, returns the bytes accepted.
// Implementations: hal/linux TermiosSerialPort, hal/sim SimSerialPipe (in-process byte pipe).
// No call allocates after open.
#pragma once

#include <cstddef>
#include <cstdint>

#include "nav/core/span.hpp"
#include "nav/core/status.hpp"

namespace qnav::hal {

enum class Parity : std::uint8_t { kNone, kEven, kOdd };

struct SerialConfig {
  std::uint32_t baud = 115200;
  std::uint8_t data_bits = 8;  // 5..8
  Parity parity = Parity::kNone;
  std::uint8_t stop_bits = 1;  // 1 or 2
  bool hw_flow_control = false;
};

Status validate_serial_config(const SerialConfig& c) noexcept;

struct SerialRead {
  std::size_t bytes = 0;
  std::int64_t arrival_ns = 0;  // monotonic time when read() returned data
};

struct SerialStats {
  std::uint32_t rx_bytes = 0;
  std::uint32_t tx_bytes = 0;
  std::uint32_t rx_errors = 0;  // framing / parity / overrun where the backend can see them
  std::uint32_t tx_short = 0;   // write() accepted fewer bytes than asked
};

class SerialPort {
 public:
  virtual ~SerialPort() = default;
  virtual Result<SerialRead> read(Span<std::uint8_t> buf, int timeout_ms) noexcept = 0;
  virtual Result<std::size_t> write(Span<const std::uint8_t> data) noexcept = 0;
  virtual SerialStats stats() const noexcept = 0;
};

}  // namespace qnav::hal
