// TcpClientPort: a byte stream over a TCP connection, behind the SerialPort interface, so drivers of
// stream protocols (JSF sonar on TCP, Water Linked PD6 on TCP 1037) run unchanged over a socket.
// open(): numeric IPv4 address only (no DNS: no heap, no blocking resolver), non-blocking connect()
// bounded by connect_timeout_ms, TCP_NODELAY. For a caller that must never wait (qnavd's io thread):
// begin_connect() starts the connection and returns at once, poll_connect() finishes it without
// waiting (kOk: open; kNotReady: still in progress; an error: it failed and the socket is closed).
// read()/write() as TermiosSerialPort: poll() up to the timeout, one read; 0 bytes = timeout; a closed
// peer is kIoError. No heap after open().
#pragma once

#include <cstdint>

#include "hal/linux/fd_serial_port.hpp"

namespace qnav::hal {

class TcpClientPort final : public FdSerialPort {
 public:
  TcpClientPort() noexcept = default;
  ~TcpClientPort() override;
  TcpClientPort(const TcpClientPort&) = delete;
  TcpClientPort& operator=(const TcpClientPort&) = delete;

  Status open(const char* ipv4, std::uint16_t port, int connect_timeout_ms) noexcept;
  Status begin_connect(const char* ipv4, std::uint16_t port) noexcept;
  Status poll_connect() noexcept { return finish_connect(0); }
  bool connecting() const noexcept { return pending_ >= 0; }
  void close() noexcept;

  Result<SerialRead> read(Span<std::uint8_t> buf, int timeout_ms) noexcept override;
  Result<std::size_t> write(Span<const std::uint8_t> data) noexcept override;

 private:
  Status finish_connect(int timeout_ms) noexcept;
  int pending_ = -1;  // a socket whose connect() is in progress
};

}  // namespace qnav::hal
