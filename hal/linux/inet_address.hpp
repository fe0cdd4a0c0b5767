// What the TCP and UDP ports share: a numeric IPv4 address and port as the socket calls take it, the
// bounded wait for data before a non-blocking read, and which errno values mean "nothing this time".
#pragma once

#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <poll.h>

#include <cstdint>

namespace qnav::hal {

// False when ipv4 is null or not a dotted-quad numeric address (no name lookups: a vehicle network
// is configured by address, and a resolver would block).
inline bool ipv4_sockaddr(const char* ipv4, std::uint16_t port, sockaddr_in& out) noexcept {
  out = sockaddr_in{};
  out.sin_family = AF_INET;
  out.sin_port = htons(port);
  return ipv4 != nullptr && ::inet_pton(AF_INET, ipv4, &out.sin_addr) == 1;
}

// Waits up to timeout_ms (negative: no wait) for fd to be readable: 1 readable, 0 not yet (timeout,
// or a signal interrupted the wait), -1 poll failed.
inline int wait_readable(int fd, int timeout_ms) noexcept {
  pollfd p{fd, POLLIN, 0};
  const int pr = ::poll(&p, 1, timeout_ms < 0 ? 0 : timeout_ms);
  if (pr < 0) return errno == EINTR ? 0 : -1;
  return pr > 0 ? 1 : 0;
}

// A non-blocking socket call that moved nothing this time (try again), not a failure.
inline bool would_block(int e) noexcept { return e == EAGAIN || e == EWOULDBLOCK || e == EINTR; }

}  // namespace qnav::hal
