#include "hal/core/candump.hpp"
#include "nav/core/assert.hpp"

#include <cstdio>
#include <cstring>

namespace qnav::hal {

namespace {
int hex_value(char c) noexcept {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}
bool is_space(char c) noexcept { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }
// "(sec.usec)" at line[i] (both formats write it so, usec always 6 digits) into out.time_us; `i`
// moves past it and the blanks after it.
Status read_timestamp(const char* line, std::size_t& i, std::size_t n, CanLogRecord& out) noexcept {
  ++i;  // '('
  std::int64_t sec = 0, usec = 0;
  int digits = 0, frac = 0;
  while (i < n && line[i] >= '0' && line[i] <= '9' && digits < 12) sec = sec * 10 + (line[i++] - '0'), ++digits;
  if (digits == 0 || i >= n || line[i] != '.') return Status(StatusCode::kCorrupt, "bad timestamp");
  ++i;
  while (i < n && line[i] >= '0' && line[i] <= '9' && frac < 6) usec = usec * 10 + (line[i++] - '0'), ++frac;
  if (frac != 6 || i >= n || line[i] != ')') return Status(StatusCode::kCorrupt, "bad timestamp");
  ++i;
  out.has_time = true;
  out.time_us = sec * 1000000 + usec;
  while (i < n && is_space(line[i])) ++i;
  return Status::ok();
}
// The interface name (one word) at line[i]; `i` moves past it.
Status read_interface(const char* line, std::size_t& i, std::size_t n, CanLogRecord& out) noexcept {
  std::size_t k = 0;
  while (i < n && !is_space(line[i])) {
    if (k + 1 >= sizeof out.interface) return Status(StatusCode::kCorrupt, "interface name too long");
    out.interface[k++] = line[i++];
  }
  out.interface[k] = '\0';
  return Status::ok();
}
// The frame's id from its hex digits, as both candump formats write it: 3 digits = 11-bit, 8 digits =
// 29-bit, or an error frame when CAN_ERR_FLAG is set (its class bits kept).
Status set_frame_id(std::uint32_t id, std::size_t digits, CanFrame& f) noexcept {
  if (digits == 3) {
    if (id > kCanSffMask) return Status(StatusCode::kOutOfRange, "11-bit id > 0x7FF");
    f.id = id;
    return Status::ok();
  }
  if (digits != 8) return Status(StatusCode::kCorrupt, "CAN id must have 3 or 8 hex digits");
  if (id & kCanErrFlag) {
    f.error = true;
    f.extended = false;
    f.id = id & kCanEffMask & ~kCanErrFlag;
    return Status::ok();
  }
  if (id > kCanEffMask) return Status(StatusCode::kOutOfRange, "29-bit id too large");
  f.extended = true;
  f.id = id;
  return Status::ok();
}
}  // namespace

Status validate_can_frame(const CanFrame& f) noexcept {
  if (f.extended ? (f.id > kCanEffMask) : (f.id > kCanSffMask)) {
    if (!f.error) return Status(StatusCode::kOutOfRange, "CAN id does not fit its format");
  }
  if (f.fd) {
    if (f.rtr) return Status(StatusCode::kInvalidArgument, "CAN FD has no remote frames");
    if (!can_fd_len_valid(f.len)) return Status(StatusCode::kOutOfRange, "CAN FD length not a valid DLC size");
  } else {
    if (f.len > kCanMaxDataClassic) return Status(StatusCode::kOutOfRange, "classic CAN length > 8");
    if (f.brs || f.esi) return Status(StatusCode::kInvalidArgument, "BRS/ESI on a classic frame");
  }
  return Status::ok();
}

bool can_filter_matches(const CanFilter& f, const CanFrame& frame) noexcept {
  bool match = ((frame.id ^ f.id) & f.mask) == 0;
  if (f.match_ide_rtr) match = match && frame.extended == f.extended && !frame.rtr;
  return f.invert ? !match : match;
}

namespace {
// candump's screen format (its default output, what `candump can0 > file` writes):
//   [(sec.usec)]  IFACE  [RX - -]  ID   [LEN]  B0 B1 ...  ['ascii' | ERRORFRAME ...]
// ID 3 hex digits = 11-bit, 8 = 29-bit (bit 0x20000000: error frame); "remote request" = RTR;
// [LEN] two digits for CAN FD. `i` is past leading blanks, `n` before trailing ones.
Status parse_screen_line(const char* line, std::size_t i, std::size_t n, CanLogRecord& out) noexcept {
  if (line[i] == '(') QNAV_RETURN_IF_ERROR(read_timestamp(line, i, n, out));
  QNAV_RETURN_IF_ERROR(read_interface(line, i, n, out));
  // The identifier is the last word before '[' (candump -x puts "RX - -" before it).
  std::size_t open = i;
  while (open < n && line[open] != '[') ++open;
  if (open >= n) return Status(StatusCode::kTruncated, "no [length] in the candump line");
  std::size_t id_end = open;
  while (id_end > i && is_space(line[id_end - 1])) --id_end;
  std::size_t id_begin = id_end;
  while (id_begin > i && !is_space(line[id_begin - 1])) --id_begin;
  const std::size_t id_digits = id_end - id_begin;
  std::uint32_t id = 0;
  for (std::size_t j = id_begin; j < id_end; ++j) {
    const int h = hex_value(line[j]);
    if (h < 0 || id_digits > 8) return Status(StatusCode::kCorrupt, "bad CAN id");
    id = (id << 4) | static_cast<std::uint32_t>(h);
  }
  CanFrame& f = out.frame;
  QNAV_RETURN_IF_ERROR(set_frame_id(id, id_digits, f));
  i = open + 1;
  std::size_t len = 0;
  int len_digits = 0;
  while (i < n && line[i] >= '0' && line[i] <= '9' && len_digits < 2) len = len * 10 + static_cast<std::size_t>(line[i++] - '0'), ++len_digits;
  if (len_digits == 0 || i >= n || line[i] != ']') return Status(StatusCode::kCorrupt, "bad [length]");
  ++i;
  f.fd = len_digits == 2;  // candump prints an FD frame's length with two digits ("[12]", "[08]")
  if (len > (f.fd ? kCanMaxDataFd : kCanMaxDataClassic) || (f.fd && !can_fd_len_valid(len)))
    return Status(StatusCode::kOutOfRange, "bad CAN length");
  while (i < n && is_space(line[i])) ++i;
  static constexpr char kRemote[] = "remote request";
  if (n - i >= sizeof kRemote - 1 && std::memcmp(line + i, kRemote, sizeof kRemote - 1) == 0) {
    if (f.fd) return Status(StatusCode::kCorrupt, "CAN FD has no remote frames");
    f.rtr = true;
    f.len = static_cast<std::uint8_t>(len);
    return Status::ok();
  }
  for (std::size_t b = 0; b < len; ++b) {
    if (i + 2 > n) return Status(StatusCode::kTruncated, "fewer data bytes than [length]");
    const int hi = hex_value(line[i]);
    const int lo = hex_value(line[i + 1]);
    if (hi < 0 || lo < 0 || (i + 2 < n && !is_space(line[i + 2]))) return Status(StatusCode::kCorrupt, "bad hex data");
    f.data[b] = static_cast<std::uint8_t>((hi << 4) | lo);
    i += 2;
    while (i < n && is_space(line[i])) ++i;
  }
  // What follows the data is candump's ASCII column ('...') or its error-frame text: not data.
  if (i < n && line[i] != '\'' && !f.error) return Status(StatusCode::kCorrupt, "more data bytes than [length]");
  f.len = static_cast<std::uint8_t>(len);
  return Status::ok();
}
}  // namespace

Status parse_can_log_line(const char* line, std::size_t n, CanLogRecord& out) noexcept {
  if (line == nullptr) return Status(StatusCode::kInvalidArgument, "null line");
  if (n > kMaxCanLogLine) return Status(StatusCode::kTruncated, "CAN log line too long");
  while (n > 0 && is_space(line[n - 1])) --n;
  std::size_t i = 0;
  while (i < n && is_space(line[i])) ++i;
  out = CanLogRecord{};
  // No '#' but a '[': candump's screen format.
  if (i < n && std::memchr(line + i, '#', n - i) == nullptr && std::memchr(line + i, '[', n - i) != nullptr)
    return parse_screen_line(line, i, n, out);
  if (i < n && line[i] == '(') {
    QNAV_RETURN_IF_ERROR(read_timestamp(line, i, n, out));
    QNAV_RETURN_IF_ERROR(read_interface(line, i, n, out));
    while (i < n && is_space(line[i])) ++i;
  }
  // Identifier.
  std::size_t id_digits = 0;
  std::uint32_t id = 0;
  while (i < n && line[i] != '#') {
    const int h = hex_value(line[i]);
    if (h < 0 || id_digits >= 8) return Status(StatusCode::kCorrupt, "bad CAN id");
    id = (id << 4) | static_cast<std::uint32_t>(h);
    ++id_digits;
    ++i;
  }
  if (i >= n) return Status(StatusCode::kTruncated, "no '#' in CAN frame");
  ++i;  // '#'
  CanFrame& f = out.frame;
  QNAV_RETURN_IF_ERROR(set_frame_id(id, id_digits, f));
  std::size_t cap = kCanMaxDataClassic;
  if (i < n && line[i] == '#') {
    ++i;
    if (i >= n) return Status(StatusCode::kTruncated, "FD frame without flags");
    const int flags = hex_value(line[i++]);
    if (flags < 0) return Status(StatusCode::kCorrupt, "bad FD flags");
    f.fd = true;
    f.brs = (flags & 1) != 0;
    f.esi = (flags & 2) != 0;
    cap = kCanMaxDataFd;
  } else if (i < n && (line[i] == 'R' || line[i] == 'r')) {
    ++i;
    f.rtr = true;
    if (i < n) {
      const int l = hex_value(line[i++]);
      if (l < 0 || l > 8 || i != n) return Status(StatusCode::kCorrupt, "bad RTR length");
      f.len = static_cast<std::uint8_t>(l);
    }
    return Status::ok();
  }
  std::size_t len = 0;
  while (i < n) {
    if (line[i] == '.') {
      ++i;
      continue;
    }
    if (i + 1 >= n) return Status(StatusCode::kTruncated, "odd number of hex digits");
    const int hi = hex_value(line[i]);
    const int lo = hex_value(line[i + 1]);
    if (hi < 0 || lo < 0) return Status(StatusCode::kCorrupt, "bad hex data");
    if (len >= cap) return Status(StatusCode::kOutOfRange, "too many data bytes");
    f.data[len++] = static_cast<std::uint8_t>((hi << 4) | lo);
    i += 2;
  }
  if (f.fd && !can_fd_len_valid(len)) return Status(StatusCode::kOutOfRange, "FD length not a DLC size");
  f.len = static_cast<std::uint8_t>(len);
  return Status::ok();
}

std::size_t format_can_log_line(const CanLogRecord& rec, char* out, std::size_t cap) noexcept {
  if (out == nullptr || cap == 0) return 0;
  static constexpr char kHex[] = "0123456789ABCDEF";
  char buf[kMaxCanLogLine];
  std::size_t k = 0;
  if (rec.has_time) {
    const int w = std::snprintf(buf, sizeof buf, "(%lld.%06lld) %s ", static_cast<long long>(rec.time_us / 1000000),
                                static_cast<long long>(rec.time_us % 1000000), rec.interface[0] ? rec.interface : "can0");
    // The prefix is at most ~47 characters (a 64-bit time, a 16-character interface): the buffer
    // holds it and the longest frame after it.
    if (!QNAV_ASSERT(w >= 0 && w < 64, "candump: time and interface prefix longer than the line buffer allows")) return 0;
    k = static_cast<std::size_t>(w);
  }
  const CanFrame& f = rec.frame;
  const bool eight = f.extended || f.error;
  const std::uint32_t id = f.error ? (f.id | kCanErrFlag) : f.id;
  for (int d = eight ? 7 : 2; d >= 0; --d) buf[k++] = kHex[(id >> (4 * d)) & 0xF];
  buf[k++] = '#';
  if (f.rtr) {
    buf[k++] = 'R';
    if (f.len > 0 && f.len <= 8) buf[k++] = kHex[f.len];  // "123#R1": the requested length (can-utils)
  } else {
    if (f.fd) {
      buf[k++] = '#';
      buf[k++] = kHex[(f.brs ? 1 : 0) | (f.esi ? 2 : 0)];
    }
    const std::size_t len = f.len > kCanMaxDataFd ? kCanMaxDataFd : f.len;
    for (std::size_t j = 0; j < len; ++j) {
      buf[k++] = kHex[f.data[j] >> 4];
      buf[k++] = kHex[f.data[j] & 0xF];
    }
  }
  if (k + 1 > cap) return 0;
  std::memcpy(out, buf, k);
  out[k] = '\0';
  return k;
}

}  // namespace qnav::hal
