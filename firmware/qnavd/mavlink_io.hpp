// MavlinkIo: the io thread's MAVLink links ([mavlink] configuration): a UDP client to udp_remote, a
// UDP server on udp_listen_port, and the serial device (termios, baud); any that are configured.
//  - poll(rx, io): non-blocking reads of every open link; a link's reads of one poll go into the
//    mav_rx queue packed back to back as MavBytes items of up to kMavBytes (one item per 280 bytes, not
//    per datagram: a flood of small datagrams cannot fill the queue item by item), each stamped with
//    the sample clock at its first read (mission time on the sim backend). A full queue drops the
//    item and counts mav_rx_overflow.
//  - send(item, io): writes one encoded frame to every open link (a UDP server only once a peer has
//    been heard); a failed write is counted (mav_tx_errors), never retried.
//  - The UDP server's peer (where qnavd's frames go) is a sender whose datagram held a valid MAVLink
//    frame (CRC and length checked by a drivers/mavlink Parser here); it stays the peer while it sends
//    valid frames, and another sender takes over only after kPeerSilenceNs without one. Junk, foreign
//    floods and a second station cannot divert the outputs from a live ground station.
//  - A link that fails to open or read is counted (mav_device_errors) and reopened once a second.
// Memory: the ports and a 2 KiB read buffer, no heap after open. Time: at most kMaxReadsPerPoll
// reads per link per poll. Runs on the io thread only (both backends).
#pragma once

#include <cstdint>
#include <cstdio>

#include "firmware/qnavd/config.hpp"
#include "firmware/qnavd/messages.hpp"
#include "hal/core/clock.hpp"
#include "hal/linux/termios_serial.hpp"
#include "hal/linux/udp_port.hpp"
#include "nav/core/spsc_ring.hpp"

namespace qnav::daemon {

class MavlinkIo {
 public:
  static constexpr int kMaxReadsPerPoll = 8;
  static constexpr std::int64_t kPeerSilenceNs = 3000000000;  // three missed 1 Hz HEARTBEATs
  MavlinkIo(const DaemonConfig& c, const hal::Clock& clock, FILE* log) noexcept : cfg_(c), clock_(clock), log_(log) {}
  // Opens the configured links; a UDP endpoint that does not parse is an error (the configuration
  // checked its form), a serial device that is absent is retried.
  Status open() noexcept;
  bool poll(SpscRing<MavBytes>& rx, IoCounters& io) noexcept;
  void send(const MavBytes& m, IoCounters& io) noexcept;
  // The UDP server's bound port and the client's local port (0 when not open).
  std::uint16_t server_port() const noexcept { return server_.is_open() ? server_.local_port() : 0; }
  std::uint16_t client_local_port() const noexcept { return client_.is_open() ? client_.local_port() : 0; }
  // The open links' descriptors (-1 when closed), for the io thread's wait.
  void fds(int (&out)[3]) const noexcept { out[0] = client_.fd(), out[1] = server_.fd(), out[2] = serial_.fd(); }

 private:
  Status open_links(bool first) noexcept;
  bool read_link(hal::SerialPort& port, std::uint8_t link, SpscRing<MavBytes>& rx, IoCounters& io, bool& failed) noexcept;
  void judge_server_sender(std::size_t bytes) noexcept;

  const DaemonConfig& cfg_;
  const hal::Clock& clock_;
  FILE* log_;
  hal::UdpPort client_, server_;
  hal::TermiosSerialPort serial_;
  std::int64_t next_retry_ns_ = 0;
  std::int64_t peer_valid_ns_ = 0;  // the server peer's last valid frame (sample clock)
  std::uint8_t buf_[2048] = {};
};

}  // namespace qnav::daemon
