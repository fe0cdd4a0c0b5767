// TcpServerPort: the listening end of a byte stream, one client at a time: a sonar topside's data
// port that the daemon's TcpClientPort connects to (the HIL scenario player, `qnav hil play`).
//  - listen(): numeric IPv4 address and port (no DNS), SO_REUSEADDR, non-blocking.
//  - poll_accept(): takes a waiting connection without blocking (true when a client is connected
//    after the call). A new connection while one is connected replaces it (a restarted daemon).
//  - write(): sends all of data to the client, waiting at most timeout_ms for the socket to drain
//    (MSG_NOSIGNAL). A client that closed or reset is dropped (kIoError) and counted in drops(); the
//    next poll_accept() takes the next one.
// Errors name the address and the OS reason (strerror). No heap.
#pragma once

#include <cstddef>
#include <cstdint>

#include "nav/core/span.hpp"
#include "nav/core/status.hpp"

namespace qnav::hal {

class TcpServerPort {
 public:
  TcpServerPort() noexcept = default;
  ~TcpServerPort();
  TcpServerPort(const TcpServerPort&) = delete;
  TcpServerPort& operator=(const TcpServerPort&) = delete;

  Status listen(const char* ipv4, std::uint16_t port) noexcept;
  bool poll_accept() noexcept;
  bool connected() const noexcept { return client_ >= 0; }
  Status write(Span<const std::uint8_t> data, int timeout_ms) noexcept;
  void close() noexcept;
  // The port bound (useful after listen(addr, 0): the kernel's choice).
  std::uint16_t local_port() const noexcept;
  std::uint32_t connections() const noexcept { return connections_; }
  std::uint32_t drops() const noexcept { return drops_; }

 private:
  void drop_client() noexcept;
  int listen_fd_ = -1;
  int client_ = -1;
  std::uint32_t connections_ = 0;
  std::uint32_t drops_ = 0;
};

}  // namespace qnav::hal
