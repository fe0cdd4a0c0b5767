// TcpClientPort: a byte stream over a TCP connection, behind the SerialPort interface, so drivers of
// stream protocols (JSF sonar on TCP, Water Linked PD6 on TCP 1037) run unchanged over a socket.
// open(): numeric IPv4 address only (no DNS: no heap, no blocking resolver), non-blocking connect()
// bounded by connect_timeout_ms, TCP_NODELAY. read()/write() as TermiosSerialPort: poll() up to the
// timeout, one read; 0 bytes = timeout; a closed peer is kIoError. No heap after open().
#pragma once

#include <cstdint>

#include "hal/core/serial.hpp"

namespace qnav::hal {

class TcpClientPort final : public SerialPort {
 public:
  TcpClientPort() noexcept = default;
  ~TcpClientPort() override;
  TcpClientPort(const TcpClientPort&) = delete;
  TcpClientPort& operator=(const TcpClientPort&) = delete;

  Status open(const char* ipv4, std::uint16_t port, int connect_timeout_ms) noexcept;
  void close() noexcept;
  bool is_open() const noexcept { return fd_ >= 0; }
  int fd() const noexcept { return fd_; }

  Result<SerialRead> read(Span<std::uint8_t> buf, int timeout_ms) noexcept override;
  Result<std::size_t> write(Span<const std::uint8_t> data) noexcept override;
  SerialStats stats() const noexcept override { return stats_; }

 private:
  int fd_ = -1;
  SerialStats stats_;
};

}  // namespace qnav::hal
