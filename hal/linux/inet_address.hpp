// A numeric IPv4 address and port as the socket calls take it (the TCP and UDP ports share it).
#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>

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

}  // namespace qnav::hal
