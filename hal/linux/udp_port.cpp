#include "hal/linux/udp_port.hpp"
#include "hal/linux/inet_address.hpp"

#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include "hal/linux/monotonic_clock.hpp"

namespace qnav::hal {

Status parse_ipv4_endpoint(const char* text, char (&host_out)[16], std::uint16_t& port_out) noexcept {
  host_out[0] = '\0';
  if (text == nullptr) return Status(StatusCode::kInvalidArgument, "endpoint: empty (want HOST:PORT)");
  std::size_t colon = 0;
  std::size_t len = 0;
  for (; text[len] != '\0'; ++len) {
    if (text[len] == ':') colon = len;
  }
  if (colon == 0 || colon > 15) return Status(StatusCode::kInvalidArgument, "endpoint: want HOST:PORT with a numeric IPv4 HOST");
  for (std::size_t i = 0; i < colon; ++i) host_out[i] = text[i];
  host_out[colon] = '\0';
  in_addr a{};
  if (::inet_pton(AF_INET, host_out, &a) != 1) {
    host_out[0] = '\0';
    return Status(StatusCode::kInvalidArgument, "endpoint: HOST is not a numeric IPv4 address");
  }
  std::uint32_t port = 0;
  if (colon + 1 == len || len - colon - 1 > 5) return Status(StatusCode::kInvalidArgument, "endpoint: PORT must be 1..65535");
  for (std::size_t i = colon + 1; i < len; ++i) {
    if (text[i] < '0' || text[i] > '9') return Status(StatusCode::kInvalidArgument, "endpoint: PORT must be 1..65535");
    port = port * 10 + static_cast<std::uint32_t>(text[i] - '0');
  }
  if (port == 0 || port > 65535) return Status(StatusCode::kInvalidArgument, "endpoint: PORT must be 1..65535");
  port_out = static_cast<std::uint16_t>(port);
  return Status::ok();
}

UdpPort::~UdpPort() { close(); }

void UdpPort::close() noexcept {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  has_peer_ = false;
  has_last_ = false;
}

Status UdpPort::open_socket(const char* bind_ipv4, std::uint16_t bind_port) noexcept {
  close();
  sockaddr_in local;
  if (!ipv4_sockaddr(bind_ipv4, bind_port, local))
    return Status(StatusCode::kInvalidArgument, "UDP bind address is not a numeric IPv4 address");
  const int s = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (s < 0) return Status(StatusCode::kIoError, "UDP socket() failed");
  // No SO_REUSEADDR: UDP has no TIME_WAIT, and with it a second process could bind the same port
  // and take half of the datagrams; a port in use is an error instead.
  if (::bind(s, reinterpret_cast<const sockaddr*>(&local), sizeof local) != 0) {
    const int e = errno;
    ::close(s);
    return Status(StatusCode::kIoError, e == EADDRINUSE ? "UDP port already in use" : "UDP bind() failed");
  }
  fd_ = s;
  stats_ = SerialStats{};
  udp_ = UdpStats{};
  return Status::ok();
}

Status UdpPort::open_client(const char* ipv4, std::uint16_t port, std::uint16_t local_port) noexcept {
  in_addr remote{};
  if (ipv4 == nullptr || ::inet_pton(AF_INET, ipv4, &remote) != 1)
    return Status(StatusCode::kInvalidArgument, "UDP remote is not a numeric IPv4 address");
  if (port == 0) return Status(StatusCode::kInvalidArgument, "UDP remote port 0");
  QNAV_RETURN_IF_ERROR(open_socket("0.0.0.0", local_port));
  client_ = true;
  has_peer_ = true;
  peer_addr_ = remote.s_addr;
  peer_port_ = htons(port);
  // connect(): the kernel then delivers only the remote's datagrams and reports ICMP port unreachable.
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_addr.s_addr = peer_addr_;
  to.sin_port = peer_port_;
  if (::connect(fd_, reinterpret_cast<const sockaddr*>(&to), sizeof to) != 0) {
    close();
    return Status(StatusCode::kIoError, "UDP connect() to the remote failed");
  }
  return Status::ok();
}

Status UdpPort::open_server(std::uint16_t port, const char* bind_ipv4) noexcept {
  QNAV_RETURN_IF_ERROR(open_socket(bind_ipv4, port));
  client_ = false;
  has_peer_ = false;
  return Status::ok();
}

std::uint16_t UdpPort::local_port() const noexcept {
  if (fd_ < 0) return 0;
  sockaddr_in a{};
  socklen_t len = sizeof a;
  if (::getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &len) != 0) return 0;
  return ntohs(a.sin_port);
}

Result<SerialRead> UdpPort::read(Span<std::uint8_t> buf, int timeout_ms) noexcept {
  if (fd_ < 0) return Status(StatusCode::kNotReady, "UDP port not open");
  SerialRead r;
  if (buf.empty()) return r;
  const int ready = wait_readable(fd_, timeout_ms);
  if (ready < 0) return Status(StatusCode::kIoError, "poll failed");
  if (ready == 0) return r;
  // Up to a bounded number of datagrams per call: foreign ones are dropped and the next one read.
  for (int tries = 0; tries < 16; ++tries) {
    sockaddr_in from{};
    socklen_t from_len = sizeof from;
    const ssize_t n = ::recvfrom(fd_, buf.data(), buf.size(), MSG_DONTWAIT | MSG_TRUNC,
                                 reinterpret_cast<sockaddr*>(&from), &from_len);
    if (n < 0) {
      if (would_block(errno)) return SerialRead{};
      if (errno == ECONNREFUSED) {  // ICMP port unreachable for an earlier send: not a read error
        ++udp_.tx_refused;
        continue;
      }
      ++stats_.rx_errors;
      return Status(StatusCode::kIoError, "UDP recvfrom failed");
    }
    if (client_ && (from.sin_addr.s_addr != peer_addr_ || from.sin_port != peer_port_)) {
      ++udp_.rx_foreign;
      continue;
    }
    std::size_t got = static_cast<std::size_t>(n);
    if (got > buf.size()) {
      ++udp_.rx_truncated;
      got = buf.size();
    }
    if (!client_) {
      last_addr_ = from.sin_addr.s_addr;
      last_port_ = from.sin_port;
      has_last_ = true;
      if (adopt_senders_) adopt_last_sender();
    }
    r.arrival_ns = monotonic_now_ns();
    r.bytes = got;
    ++udp_.datagrams_rx;
    stats_.rx_bytes += static_cast<std::uint32_t>(got);
    return r;
  }
  return r;
}

Result<std::size_t> UdpPort::write(Span<const std::uint8_t> data) noexcept {
  if (fd_ < 0) return Status(StatusCode::kNotReady, "UDP port not open");
  if (!has_peer_) return Status(StatusCode::kNotReady, "UDP server port: no sender seen yet");
  if (data.empty()) return std::size_t{0};
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_addr.s_addr = peer_addr_;
  to.sin_port = peer_port_;
  const ssize_t n = client_ ? ::send(fd_, data.data(), data.size(), MSG_DONTWAIT | MSG_NOSIGNAL)
                            : ::sendto(fd_, data.data(), data.size(), MSG_DONTWAIT | MSG_NOSIGNAL,
                                       reinterpret_cast<const sockaddr*>(&to), sizeof to);
  if (n < 0) {
    if (would_block(errno) || errno == ENOBUFS) {
      ++stats_.tx_short;
      return std::size_t{0};
    }
    if (errno == ECONNREFUSED) {
      ++udp_.tx_refused;
      return Status(StatusCode::kIoError, "UDP peer refused (nothing listening)");
    }
    return Status(StatusCode::kIoError, "UDP sendto failed");
  }
  ++udp_.datagrams_tx;
  stats_.tx_bytes += static_cast<std::uint32_t>(n);
  return static_cast<std::size_t>(n);
}

}  // namespace qnav::hal
