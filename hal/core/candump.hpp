// can-utils text formats for CAN frames: the candump log line `(1436509052.249713) vcan0 123#DEADBEEF`
// (candump -l / -L, canplayer input) and the bare cansend form `123#DEADBEEF`.
//  - `123#..`   3 hex digits = 11-bit id; `1F334455#..` 8 hex digits = 29-bit id;
//    an 8-digit id with bit 0x20000000 (CAN_ERR_FLAG) set is an error frame.
//  - `123#R` / `123#R5` remote request (optional length); `123##<flags-nibble><data>` CAN FD
//    (flags: 1 = BRS, 2 = ESI). Data is hex pairs, optionally separated by '.'.
// parse_can_log_line() also reads candump's screen format (its default output, no -l): a line with no
// '#' and a "[len]": `  can0  123   [2]  11 22`, with `(sec.usec)` before it under -t a, "RX - -"
// under -x, the ASCII column under -a, "remote request" for RTR and a two-digit length for CAN FD.
// parse_can_log_line(): pure, no heap, O(line length) with the line capped at kMaxCanLogLine bytes
// (longer lines are rejected as kTruncated before any parsing). format_can_log_line() writes the same form.
#pragma once

#include <cstddef>
#include <cstdint>

#include "hal/core/can.hpp"
#include "nav/core/status.hpp"

namespace qnav::hal {

constexpr std::size_t kMaxCanLogLine = 256;
constexpr std::uint32_t kCanErrFlag = 0x20000000u;

struct CanLogRecord {
  CanFrame frame;
  bool has_time = false;
  std::int64_t time_us = 0;     // the log's timestamp (system time in candump -l), microseconds
  char interface[17] = {};      // empty when the line has none
};

// Parses one line (no trailing newline needed; trailing '\r'/'\n'/spaces ignored).
// Errors: kTruncated (too long / ends early), kCorrupt (bad syntax), kOutOfRange (id or length).
Status parse_can_log_line(const char* line, std::size_t n, CanLogRecord& out) noexcept;

// Writes `(sec.usec) iface id#data` (time/iface omitted when absent) with a NUL; returns the length
// or 0 when `cap` is too small.
std::size_t format_can_log_line(const CanLogRecord& rec, char* out, std::size_t cap) noexcept;

}  // namespace qnav::hal
