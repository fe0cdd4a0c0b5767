#include "hal/linux/tcp_server_port.hpp"
#include "hal/linux/inet_address.hpp"

#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include "hal/linux/device_error.hpp"

namespace qnav::hal {

TcpServerPort::~TcpServerPort() { close(); }

void TcpServerPort::drop_client() noexcept {
  if (client_ >= 0) ::close(client_);
  client_ = -1;
}

void TcpServerPort::close() noexcept {
  drop_client();
  if (listen_fd_ >= 0) ::close(listen_fd_);
  listen_fd_ = -1;
}

Status TcpServerPort::listen(const char* ipv4, std::uint16_t port) noexcept {
  close();
  sockaddr_in a;
  if (!ipv4_sockaddr(ipv4, port, a)) {
    return Status(StatusCode::kInvalidArgument, "listen address is not a numeric IPv4 address");
  }
  listen_fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (listen_fd_ < 0) return device_error(StatusCode::kIoError, "socket(AF_INET) failed for", ipv4, errno, nullptr);
  const int one = 1;
  (void)::setsockopt(listen_fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  if (::bind(listen_fd_, reinterpret_cast<const sockaddr*>(&a), sizeof a) != 0 || ::listen(listen_fd_, 1) != 0) {
    const int err = errno;
    close();
    return device_error(StatusCode::kIoError, "cannot listen on", ipv4, err,
                        err == EADDRINUSE ? "another program holds the port" : nullptr);
  }
  return Status::ok();
}

std::uint16_t TcpServerPort::local_port() const noexcept {
  sockaddr_in a{};
  socklen_t n = sizeof a;
  if (listen_fd_ < 0 || ::getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&a), &n) != 0) return 0;
  return ntohs(a.sin_port);
}

bool TcpServerPort::poll_accept() noexcept {
  if (listen_fd_ < 0) return false;
  const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC);
  if (fd >= 0) {
    drop_client();  // a restarted daemon's new connection replaces the old one
    const int one = 1;
    (void)::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    client_ = fd;
    ++connections_;
  }
  return client_ >= 0;
}

Status TcpServerPort::write(Span<const std::uint8_t> data, int timeout_ms) noexcept {
  if (client_ < 0) return Status(StatusCode::kNotReady, "no client connected");
  std::size_t off = 0;
  while (off < data.size()) {
    const ssize_t n = ::send(client_, data.data() + off, data.size() - off, MSG_NOSIGNAL | MSG_DONTWAIT);
    if (n > 0) {
      off += static_cast<std::size_t>(n);
      continue;
    }
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
      pollfd p{client_, POLLOUT, 0};
      if (::poll(&p, 1, timeout_ms) > 0 && (p.revents & POLLOUT) != 0) continue;
      if (p.revents == 0) return Status(StatusCode::kTimeout, "client does not read");
    }
    drop_client();
    ++drops_;
    return Status(StatusCode::kIoError, "client closed the connection");
  }
  return Status::ok();
}

}  // namespace qnav::hal
