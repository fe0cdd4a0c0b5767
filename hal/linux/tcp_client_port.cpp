#include "hal/linux/tcp_client_port.hpp"
#include "hal/linux/inet_address.hpp"

#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include "hal/linux/monotonic_clock.hpp"

namespace qnav::hal {

TcpClientPort::~TcpClientPort() { close(); }

void TcpClientPort::close() noexcept {
  if (fd_ >= 0) ::close(fd_);
  if (pending_ >= 0) ::close(pending_);
  fd_ = pending_ = -1;
}

Status TcpClientPort::begin_connect(const char* ipv4, std::uint16_t port) noexcept {
  close();
  sockaddr_in addr;
  if (!ipv4_sockaddr(ipv4, port, addr))
    return Status(StatusCode::kInvalidArgument, "not a numeric IPv4 address");
  const int s = ::socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (s < 0) return Status(StatusCode::kIoError, "socket() failed");
  const int one = 1;
  (void)::setsockopt(s, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
  if (::connect(s, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) == 0) {
    fd_ = s;
    stats_ = SerialStats{};
    return Status::ok();
  }
  if (errno != EINPROGRESS) {
    const int e = errno;
    ::close(s);
    return Status(StatusCode::kIoError, e == ECONNREFUSED ? "TCP connection refused" : "connect() failed");
  }
  pending_ = s;
  return Status(StatusCode::kNotReady, "TCP connect in progress");
}

Status TcpClientPort::finish_connect(int timeout_ms) noexcept {
  if (fd_ >= 0) return Status::ok();
  if (pending_ < 0) return Status(StatusCode::kNotReady, "TCP port not connecting");
  pollfd p{pending_, POLLOUT, 0};
  const int pr = ::poll(&p, 1, timeout_ms < 0 ? 0 : timeout_ms);
  if (pr == 0) return Status(StatusCode::kNotReady, "TCP connect in progress");
  int err = 0;
  socklen_t len = sizeof err;
  if (pr < 0 || ::getsockopt(pending_, SOL_SOCKET, SO_ERROR, &err, &len) < 0 || err != 0) {
    ::close(pending_);
    pending_ = -1;
    return Status(StatusCode::kIoError, err == ECONNREFUSED ? "TCP connection refused" : "TCP connect failed");
  }
  fd_ = pending_;
  pending_ = -1;
  stats_ = SerialStats{};
  return Status::ok();
}

Status TcpClientPort::open(const char* ipv4, std::uint16_t port, int connect_timeout_ms) noexcept {
  const Status s = begin_connect(ipv4, port);
  if (s.code() != StatusCode::kNotReady) return s;
  const Status f = finish_connect(connect_timeout_ms);
  if (f.code() == StatusCode::kNotReady) {
    close();
    return Status(StatusCode::kTimeout, "TCP connect timed out");
  }
  return f;
}

Result<SerialRead> TcpClientPort::read(Span<std::uint8_t> buf, int timeout_ms) noexcept {
  if (fd_ < 0) return Status(StatusCode::kNotReady, "TCP port not open");
  SerialRead r;
  if (buf.empty()) return r;
  const int ready = wait_readable(fd_, timeout_ms);
  if (ready < 0) return Status(StatusCode::kIoError, "poll failed");
  if (ready == 0) return r;
  const ssize_t n = ::recv(fd_, buf.data(), buf.size(), MSG_DONTWAIT);
  r.arrival_ns = monotonic_now_ns();
  if (n < 0) {
    if (would_block(errno)) return SerialRead{};
    ++stats_.rx_errors;
    return Status(StatusCode::kIoError, "TCP recv failed");
  }
  if (n == 0) return Status(StatusCode::kIoError, "TCP peer closed the connection");
  r.bytes = static_cast<std::size_t>(n);
  stats_.rx_bytes += static_cast<std::uint32_t>(n);
  return r;
}

Result<std::size_t> TcpClientPort::write(Span<const std::uint8_t> data) noexcept {
  if (fd_ < 0) return Status(StatusCode::kNotReady, "TCP port not open");
  if (data.empty()) return std::size_t{0};
  const ssize_t n = ::send(fd_, data.data(), data.size(), MSG_DONTWAIT | MSG_NOSIGNAL);
  if (n < 0) {
    if (would_block(errno)) {
      ++stats_.tx_short;
      return std::size_t{0};
    }
    return Status(StatusCode::kIoError, "TCP send failed");
  }
  if (static_cast<std::size_t>(n) < data.size()) ++stats_.tx_short;
  stats_.tx_bytes += static_cast<std::uint32_t>(n);
  return static_cast<std::size_t>(n);
}

}  // namespace qnav::hal
