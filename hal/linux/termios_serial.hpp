// TermiosSerialPort: SerialPort over a tty (UART, USB-serial, or a pseudo-terminal in tests).
// open(): O_RDWR|O_NOCTTY|O_NONBLOCK, raw mode (cfmakeraw), baud/size/parity/stop/flow from the
// config, CLOCAL|CREAD, VMIN=0 VTIME=0 (timing is done with poll()), input queue flushed.
// read(): poll() up to timeout_ms, then one read(); 0 bytes = timeout; arrival stamped after read().
// write(): one non-blocking write(); partial writes are reported (tx_short), EAGAIN = 0 bytes.
// No heap after open().
#pragma once

#include <termios.h>

#include "hal/linux/fd_serial_port.hpp"

namespace qnav::hal {

// The termios settings open() applies (raw, size, parity, stop bits, flow control, speed), from a
// zeroed or current termios. Separate so the bits can be checked where a pty ignores them.
Status build_termios(const SerialConfig& config, termios& t) noexcept;

class TermiosSerialPort final : public FdSerialPort {
 public:
  TermiosSerialPort() noexcept = default;
  ~TermiosSerialPort() override;
  TermiosSerialPort(const TermiosSerialPort&) = delete;
  TermiosSerialPort& operator=(const TermiosSerialPort&) = delete;

  Status open(const char* path, const SerialConfig& config) noexcept;
  void close() noexcept;

  Result<SerialRead> read(Span<std::uint8_t> buf, int timeout_ms) noexcept override;
  Result<std::size_t> write(Span<const std::uint8_t> data) noexcept override;
};

}  // namespace qnav::hal
