#include "firmware/qnavd/mavlink_io.hpp"

#include <algorithm>
#include <cstring>

#include "drivers/mavlink/parser.hpp"

namespace qnav::daemon {

Status MavlinkIo::open() noexcept { return open_links(true); }

Status MavlinkIo::open_links(bool first) noexcept {
  if (!cfg_.mavlink_udp_remote.empty() && !client_.is_open()) {
    char host[16];
    std::uint16_t port = 0;
    QNAV_RETURN_IF_ERROR(hal::parse_ipv4_endpoint(cfg_.mavlink_udp_remote.c_str(), host, port));
    const Status s = client_.open_client(host, port);
    if (!s) {
      if (first) return s;
      if (log_) std::fprintf(log_, "{\"event\":\"warning\",\"what\":\"mavlink.udp_remote: %s\"}\n", s.message());
    }
  }
  if (cfg_.mavlink_udp_listen_port != 0 && !server_.is_open()) {
    server_.set_adopt_senders(false);  // judge_server_sender() chooses the peer
    const Status s = server_.open_server(static_cast<std::uint16_t>(cfg_.mavlink_udp_listen_port));
    if (!s) {
      if (first) return s;
      if (log_) std::fprintf(log_, "{\"event\":\"warning\",\"what\":\"mavlink.udp_listen_port: %s\"}\n", s.message());
    }
  }
  if (!cfg_.mavlink_serial_device.empty() && cfg_.backend == Backend::kLinux && !serial_.is_open()) {
    hal::SerialConfig sc;
    sc.baud = static_cast<std::uint32_t>(cfg_.mavlink_baud);
    const Status s = serial_.open(cfg_.mavlink_serial_device.c_str(), sc);
    if (!s && log_) std::fprintf(log_, "{\"event\":\"warning\",\"what\":\"mavlink.serial_device %s: %s\"}\n", cfg_.mavlink_serial_device.c_str(), s.message());
  }
  return Status::ok();
}

bool MavlinkIo::read_link(hal::SerialPort& port, std::uint8_t link, SpscRing<MavBytes>& rx, IoCounters& io, bool& failed) noexcept {
  // The reads of one poll are packed back to back into as few items as they fill: the link is one byte
  // stream to its parser (a UDP datagram's end means nothing to it), so a flood of small datagrams
  // takes a queue item per kMavBytes, not one per datagram, and leaves room for the autopilot's frames.
  bool did = false;
  MavBytes m;
  m.link = link;
  m.len = 0;
  const auto flush = [&]() {
    if (m.len == 0) return;
    if (!rx.try_push(m)) io.mav_rx_overflow.fetch_add(1, std::memory_order_relaxed);
    m.len = 0;
  };
  for (int i = 0; i < kMaxReadsPerPoll; ++i) {
    Result<hal::SerialRead> r = port.read(Span<std::uint8_t>(buf_, sizeof buf_), 0);
    if (!r) {
      failed = true;
      io.mav_device_errors.fetch_add(1, std::memory_order_relaxed);
      break;
    }
    const std::size_t n = r.value().bytes;
    if (n == 0) break;
    did = true;
    if (&port == &server_) judge_server_sender(n);
    const std::int64_t t = clock_.now_ns();
    for (std::size_t off = 0; off < n;) {
      if (m.len == 0) m.arrival_ns = t;  // an item's time is its first read's
      const std::size_t k = std::min<std::size_t>(kMavBytes - m.len, n - off);
      std::memcpy(m.data + m.len, buf_ + off, k);
      m.len = static_cast<std::uint16_t>(m.len + k);
      off += k;
      if (m.len == kMavBytes) flush();
    }
  }
  flush();
  return did;
}

void MavlinkIo::judge_server_sender(std::size_t bytes) noexcept {
  drivers::mavlink::Parser check;  // a datagram holds whole frames: judged on its own
  bool valid = false;
  check.feed(Span<const std::uint8_t>(buf_, bytes), [&](const drivers::mavlink::Frame&) { valid = true; });
  if (!valid) return;
  const std::int64_t now = clock_.now_ns();
  if (server_.last_sender_is_peer()) {
    peer_valid_ns_ = now;
  } else if (!server_.has_peer() || now - peer_valid_ns_ > kPeerSilenceNs) {
    server_.adopt_last_sender();
    peer_valid_ns_ = now;
  }
}

bool MavlinkIo::poll(SpscRing<MavBytes>& rx, IoCounters& io) noexcept {
  const std::int64_t now = clock_.now_ns();
  if (now >= next_retry_ns_) {
    (void)open_links(false);  // failures are logged; retried in a second
    next_retry_ns_ = now + 1000000000;
  }
  bool did = false, failed = false;
  if (client_.is_open()) did |= read_link(client_, 0, rx, io, failed);  // a "refused" read error leaves the socket usable
  failed = false;
  if (server_.is_open()) did |= read_link(server_, 1, rx, io, failed);
  failed = false;
  if (serial_.is_open()) {
    did |= read_link(serial_, 2, rx, io, failed);
    if (failed) serial_.close();  // reopened within a second
  }
  return did;
}

void MavlinkIo::send(const MavBytes& m, IoCounters& io) noexcept {
  const Span<const std::uint8_t> bytes(m.data, m.len);
  const auto write = [&](hal::SerialPort& p) {
    Result<std::size_t> w = p.write(bytes);
    if (!w || w.value() != m.len) io.mav_tx_errors.fetch_add(1, std::memory_order_relaxed);
  };
  if (client_.is_open()) write(client_);
  if (server_.is_open() && server_.has_peer()) write(server_);
  if (serial_.is_open()) write(serial_);
}

}  // namespace qnav::daemon
