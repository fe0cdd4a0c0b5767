#include "drivers/sidescan/xtf_reader.hpp"
#include "nav/core/assert.hpp"

#include <new>

#include "nav/core/byte_order.hpp"

namespace qnav::sidescan {

Status XtfReader::init(const XtfReaderConfig& c) noexcept {
  if (c.max_packet_bytes < kXtfPingHeaderBytes || c.max_packet_bytes > (256u << 20))
    return Status(StatusCode::kInvalidArgument, "max_packet_bytes outside [256, 256 MiB]");
  buf_.reset(new (std::nothrow) std::uint8_t[c.max_packet_bytes < 4096 ? 4096 : c.max_packet_bytes]);
  if (!buf_) return Status(StatusCode::kCapacityExceeded, "out of memory for the XTF packet buffer");
  cfg_ = c;
  return Status::ok();
}

std::size_t XtfReader::read_exact(std::uint8_t* dst, std::size_t n) noexcept {
  std::size_t got = 0;
  while (got < n) {
    const std::size_t k = src_->read(dst + got, n - got);
    if (k == 0) break;
    got += k;
  }
  offset_ += got;
  return got;
}

Status XtfReader::open(ByteSource& source) noexcept {
  if (!buf_) return Status(StatusCode::kNotReady, "XtfReader not initialised");
  src_ = &source;
  offset_ = 0;
  packets_ = 0;
  at_end_ = false;
  counters_.reset();
  if (read_exact(buf_.get(), kXtfFileHeaderBytes) != kXtfFileHeaderBytes) {
    at_end_ = true;
    return src_->error() ? Status(StatusCode::kIoError, "read error in the XTF file header")
                         : Status(StatusCode::kTruncated, "file shorter than the 1024-byte XTF header");
  }
  // The header may grow in 1024-byte steps; parse once to learn its size, then read the rest.
  Result<XtfFileHeader> h = parse_xtf_file_header(Span<const std::uint8_t>(buf_.get(), kXtfFileHeaderBytes));
  if (!h && h.status() == StatusCode::kTruncated) {
    // Needs the extension blocks: work out their size from the counts at the fixed offsets.
    const std::uint8_t* p = buf_.get();
    const std::uint32_t total = static_cast<std::uint32_t>(load_le_u16(p + 166)) + load_le_u16(p + 168) + p[170] + p[171] +
                                load_le_u16(p + 172) + p[174];
    const std::size_t bytes = kXtfFileHeaderBytes * (1 + (total - 6 + 7) / 8);
    if (bytes > cfg_.max_packet_bytes) return Status(StatusCode::kUnsupported, "XTF header larger than the packet buffer");
    if (read_exact(buf_.get() + kXtfFileHeaderBytes, bytes - kXtfFileHeaderBytes) != bytes - kXtfFileHeaderBytes)
      return Status(StatusCode::kTruncated, "XTF header extension truncated");
    h = parse_xtf_file_header(Span<const std::uint8_t>(buf_.get(), bytes));
  }
  if (!h) {
    at_end_ = true;
    return h.status();
  }
  header_ = h.value();
  return Status::ok();
}

bool XtfReader::resync(std::uint8_t* hdr) noexcept {
  // hdr holds 14 bytes that are not a valid packet start. Drop at least one byte, slide to the next
  // 0xCE (first byte of 0xFACE little-endian), refill to 14 bytes and check again. Always consumes
  // >= 1 byte per round, so it ends at the end of the data at the latest.
  std::size_t have = kXtfPacketHeaderBytes;
  for (;;) {
    std::size_t s = 1;
    while (s < have && hdr[s] != 0xCE) ++s;
    counters_.increment(XtfCounter::kResyncBytes, static_cast<std::uint32_t>(s));
    for (std::size_t i = s; i < have; ++i) hdr[i - s] = hdr[i];
    have -= s;
    have += read_exact(hdr + have, kXtfPacketHeaderBytes - have);
    if (have < kXtfPacketHeaderBytes) return false;
    if (load_le_u16(hdr) == kXtfMagic) {
      if (load_le_u32(hdr + 10) >= kXtfPacketHeaderBytes) return true;
      counters_.increment(XtfCounter::kBadLength);
    }
  }
}

Result<bool> XtfReader::next(XtfRecord& out, Span<float> port, Span<float> stbd) noexcept {
  if (src_ == nullptr) return Status(StatusCode::kNotReady, "XtfReader not opened");
  for (;;) {
    if (at_end_) return false;
    std::uint8_t* hdr = buf_.get();
    const std::size_t got = read_exact(hdr, kXtfPacketHeaderBytes);
    if (got == 0) {
      at_end_ = true;
      if (src_->error()) return Status(StatusCode::kIoError, "read error in the XTF file");
      return false;
    }
    if (got < kXtfPacketHeaderBytes) {
      at_end_ = true;
      counters_.increment(XtfCounter::kTruncated);
      return Status(StatusCode::kTruncated, "XTF file ends inside a packet header");
    }
    const bool magic_ok = load_le_u16(hdr) == kXtfMagic;
    const bool length_ok = load_le_u32(hdr + 10) >= kXtfPacketHeaderBytes;
    if (!magic_ok || !length_ok) {
      counters_.increment(magic_ok ? XtfCounter::kBadLength : XtfCounter::kBadMagic);
      if (!resync(hdr)) {
        at_end_ = true;
        return false;
      }
    }
    const Result<XtfPacketHeader> ph = parse_xtf_packet_header(Span<const std::uint8_t>(hdr, kXtfPacketHeaderBytes));
    if (!QNAV_ASSERT(ph.is_ok(), "xtf: a packet header that passed the magic and length checks failed to parse")) {
      counters_.increment(XtfCounter::kBadMagic);
      continue;
    }
    const std::uint32_t len = ph->num_bytes;
    ++packets_;
    if (len > cfg_.max_packet_bytes) {
      counters_.increment(XtfCounter::kOversize);
      std::size_t left = len - kXtfPacketHeaderBytes;
      while (left > 0) {
        const std::size_t chunk = left < cfg_.max_packet_bytes - kXtfPacketHeaderBytes ? left : cfg_.max_packet_bytes - kXtfPacketHeaderBytes;
        const std::size_t k = read_exact(buf_.get() + kXtfPacketHeaderBytes, chunk);
        if (k < chunk) {
          at_end_ = true;
          counters_.increment(XtfCounter::kTruncated);
          return Status(StatusCode::kTruncated, "XTF file ends inside an oversize packet");
        }
        left -= k;
      }
      continue;
    }
    const std::size_t body = len - kXtfPacketHeaderBytes;
    if (read_exact(buf_.get() + kXtfPacketHeaderBytes, body) != body) {
      at_end_ = true;
      counters_.increment(XtfCounter::kTruncated);
      return Status(StatusCode::kTruncated, "XTF file ends inside a packet");
    }
    const Span<const std::uint8_t> packet(buf_.get(), len);
    out.header = ph.value();
    switch (ph->header_type) {
      case static_cast<std::uint8_t>(XtfPacketType::kSonar): {
        const Status s = parse_xtf_sonar_ping(packet, header_, out.ping, port, stbd);
        if (!s) {
          counters_.increment(XtfCounter::kBadPing);
          last_error_ = s;
          continue;
        }
        if (!out.ping.nav_valid) counters_.increment(XtfCounter::kPingWithoutNav);
        out.kind = XtfRecordKind::kPing;
        return true;
      }
      case static_cast<std::uint8_t>(XtfPacketType::kAttitude): {
        const Result<XtfAttitude> a = parse_xtf_attitude(packet);
        if (!a) {
          counters_.increment(XtfCounter::kBadAttitude);
          last_error_ = a.status();
          continue;
        }
        out.attitude = a.value();
        out.kind = XtfRecordKind::kAttitude;
        return true;
      }
      case static_cast<std::uint8_t>(XtfPacketType::kNavigation): {
        const Result<XtfNavigation> n = parse_xtf_navigation(packet);
        if (!n) {
          counters_.increment(XtfCounter::kBadNavigation);
          last_error_ = n.status();
          continue;
        }
        out.navigation = n.value();
        out.kind = XtfRecordKind::kNavigation;
        return true;
      }
      default:
        counters_.increment(XtfCounter::kSkippedPacket);
        continue;
    }
  }
}

}  // namespace qnav::sidescan
