// XtfReader: walks an XTF stream packet by packet from a ByteSource (file or memory) with one
// fixed packet buffer (max_packet_bytes, allocated once in init()). Decodes side-scan pings
// (type 0), attitude (3) and navigation (42) packets; every other type is skipped by its length
// and counted. Robustness: a bad magic number or a length field shorter than the packet header is
// counted and the reader re-synchronises on the next 0xFACE (it always advances, so it can never
// loop on a zero-length packet); a packet longer than max_packet_bytes is skipped (counted);
// a packet cut short by the end of the file returns kTruncated once, then end of data.
// Cost: O(packet bytes) per next(); no allocation after init().
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>

#include "drivers/sidescan/byte_source.hpp"
#include "drivers/sidescan/xtf_parser.hpp"
#include "nav/core/counters.hpp"

namespace qnav::sidescan {

enum class XtfCounter : std::uint8_t {
  kBadMagic,       // packet start without 0xFACE (re-synchronised)
  kBadLength,      // length field shorter than the packet header
  kResyncBytes,    // bytes skipped while re-synchronising
  kOversize,       // packet longer than max_packet_bytes (skipped)
  kTruncated,      // the data ended inside a packet
  kSkippedPacket,  // packet types the reader does not decode
  kBadPing,        // sonar packets that failed to decode
  kBadAttitude,
  kBadNavigation,
  kPingWithoutNav, // decoded pings whose position is missing/invalid
  kCount
};
inline constexpr const char* kXtfCounterNames[] = {"bad_magic", "bad_length", "resync_bytes", "oversize", "truncated",
                                                   "skipped_packet", "bad_ping", "bad_attitude", "bad_navigation",
                                                   "ping_without_nav"};

struct XtfReaderConfig {
  std::size_t max_packet_bytes = 1u << 20;
};

enum class XtfRecordKind : std::uint8_t { kPing, kAttitude, kNavigation, kOther };

struct XtfRecord {
  XtfRecordKind kind = XtfRecordKind::kOther;
  XtfPacketHeader header;
  XtfPing ping;          // kPing
  XtfAttitude attitude;  // kAttitude
  XtfNavigation navigation;  // kNavigation
};

class XtfReader {
 public:
  Status init(const XtfReaderConfig& config) noexcept;
  // Reads and validates the file header from the source (which must outlive the reader).
  Status open(ByteSource& source) noexcept;
  // Next record. Result true: a record (pings fill port/stbd, near range first); false: end of data.
  // Errors: kTruncated (the data ended inside a packet; next call returns false), kIoError.
  // A packet that fails to decode is counted and skipped, not returned as an error.
  Result<bool> next(XtfRecord& out, Span<float> port, Span<float> stbd) noexcept;

  const XtfFileHeader& header() const noexcept { return header_; }
  const CounterSet<XtfCounter>& counters() const noexcept { return counters_; }
  std::uint64_t packets_read() const noexcept { return packets_; }
  std::uint64_t bytes_read() const noexcept { return offset_; }
  // Status of the last packet that failed to decode (for messages).
  Status last_decode_error() const noexcept { return last_error_; }

 private:
  std::size_t read_exact(std::uint8_t* dst, std::size_t n) noexcept;
  bool resync(std::uint8_t* hdr) noexcept;

  XtfReaderConfig cfg_{};
  std::unique_ptr<std::uint8_t[]> buf_;
  ByteSource* src_ = nullptr;
  XtfFileHeader header_{};
  CounterSet<XtfCounter> counters_{kXtfCounterNames};
  std::uint64_t packets_ = 0;
  std::uint64_t offset_ = 0;
  bool at_end_ = false;
  Status last_error_{};
};

}  // namespace qnav::sidescan
