// UdpPort: datagrams over UDP/IPv4 (MAVLink's usual transport to an autopilot or mavlink-router),
// behind the SerialPort interface so a stream parser runs unchanged over serial or UDP.
//  - open_client(ipv4, port): sends every datagram to that endpoint (the autopilot's or router's
//    UDP port) from an ephemeral local port (or local_port); the socket is connected, so the kernel
//    delivers only that endpoint's datagrams (any other that slips through is dropped and counted in
//    UdpStats::rx_foreign) and reports "port unreachable".
//  - open_server(port, bind_ipv4): listens on a port (all interfaces by default); receives from
//    anyone and replies to the last sender; write() before the first datagram is kNotReady. With
//    set_adopt_senders(false) a sender becomes the peer only when the caller says so
//    (adopt_last_sender(): e.g. once its datagram held a valid frame), so a flood of junk from
//    another address cannot take the replies away from the peer.
//  - read(buf, timeout_ms): waits at most timeout_ms (0 = poll) for a datagram, returns one datagram
//    (0 bytes on timeout); a datagram longer than buf is cut and counted in rx_truncated.
//  - write(data): one datagram, non-blocking: a full socket buffer returns 0 bytes (tx_short); an
//    ICMP "port unreachable" from an earlier datagram (nothing listening there yet) is
//    kIoError "UDP peer refused", counted in tx_refused; the port stays usable.
// Numeric IPv4 only (no DNS: no heap, no blocking resolver). Errors are values, never exceptions.
// No heap after open; each call is one or two system calls.
#pragma once

#include <cstddef>
#include <cstdint>

#include "hal/linux/fd_serial_port.hpp"

namespace qnav::hal {

// "HOST:PORT" with a numeric IPv4 HOST and PORT 1..65535 (the [mavlink] udp_remote form). host_out
// receives the HOST text (NUL-terminated, at most 15 characters). kInvalidArgument with the reason.
Status parse_ipv4_endpoint(const char* text, char (&host_out)[16], std::uint16_t& port_out) noexcept;

struct UdpStats {
  std::uint32_t datagrams_rx = 0;
  std::uint32_t datagrams_tx = 0;
  std::uint32_t rx_foreign = 0;    // client: datagrams from another endpoint (dropped)
  std::uint32_t rx_truncated = 0;  // datagrams longer than the read buffer (cut)
  std::uint32_t tx_refused = 0;    // ICMP port unreachable reported for an earlier send
};

class UdpPort final : public FdSerialPort {
 public:
  UdpPort() noexcept = default;
  ~UdpPort() override;
  UdpPort(const UdpPort&) = delete;
  UdpPort& operator=(const UdpPort&) = delete;

  Status open_client(const char* ipv4, std::uint16_t port, std::uint16_t local_port = 0) noexcept;
  Status open_server(std::uint16_t port, const char* bind_ipv4 = "0.0.0.0") noexcept;
  void close() noexcept;
  // The local port bound (after open_server(0) or open_client: the kernel's choice).
  std::uint16_t local_port() const noexcept;
  // Server: a sender has been seen (write() has somewhere to go). Client: always true when open.
  bool has_peer() const noexcept { return has_peer_; }
  // Server: whether read() makes each datagram's sender the peer (default true).
  void set_adopt_senders(bool adopt) noexcept { adopt_senders_ = adopt; }
  // Server: the sender of the last datagram read is the peer (already, or from now on).
  bool last_sender_is_peer() const noexcept { return has_peer_ && last_addr_ == peer_addr_ && last_port_ == peer_port_; }
  void adopt_last_sender() noexcept {
    if (client_ || !has_last_) return;
    peer_addr_ = last_addr_, peer_port_ = last_port_, has_peer_ = true;
  }

  Result<SerialRead> read(Span<std::uint8_t> buf, int timeout_ms) noexcept override;
  Result<std::size_t> write(Span<const std::uint8_t> data) noexcept override;
  const UdpStats& udp_stats() const noexcept { return udp_; }

 private:
  Status open_socket(const char* bind_ipv4, std::uint16_t bind_port) noexcept;
  bool client_ = false;
  bool has_peer_ = false;
  bool adopt_senders_ = true;
  bool has_last_ = false;
  std::uint32_t last_addr_ = 0;  // the last datagram's sender (server), network byte order
  std::uint16_t last_port_ = 0;
  std::uint32_t peer_addr_ = 0;  // network byte order
  std::uint16_t peer_port_ = 0;  // network byte order
  UdpStats udp_;
};

}  // namespace qnav::hal
