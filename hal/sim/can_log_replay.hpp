// CanLogReplay: a CanBus that replays a candump log (text already in memory, e.g. a file read at
// start-up) frame by frame. Each receive() returns the next parseable line; lines that do not parse
// are skipped and counted (bad_lines, first_bad_line). A caller reads to the end with
// `while (!finished())`: receive() returns kTimeout after kMaxSkipPerCall bad lines in a row. Stamps: sample_ns = the log time shifted so the first record
// is at `start_ns`; arrival_ns = the same (replay has no transport). send() is accepted and counted.
// Bounds: one receive() scans at most kMaxCanLogLine * kMaxSkipPerCall bytes; no heap.
#pragma once

#include <cstddef>
#include <cstdint>

#include "hal/core/can.hpp"
#include "hal/core/candump.hpp"

namespace qnav::hal {

class CanLogReplay final : public CanBus {
 public:
  static constexpr std::size_t kMaxSkipPerCall = 64;
  // A line further than this from the log's first timestamp is counted bad (100 days).
  static constexpr std::int64_t kMaxReplaySpanUs = 100LL * 86400 * 1000000;
  CanLogReplay(const char* text, std::size_t n, std::int64_t start_ns = 0) noexcept
      : text_(text), n_(n), start_ns_(start_ns) {}

  Status send(const CanFrame& frame) noexcept override;
  Status receive(CanRxFrame& out, int timeout_ms) noexcept override;
  CanBusStats stats() const noexcept override { return stats_; }
  std::uint32_t bad_lines() const noexcept { return bad_lines_; }
  // 1-based line number of the first line that did not parse (0: none yet).
  std::uint32_t first_bad_line() const noexcept { return first_bad_line_; }
  bool finished() const noexcept { return pos_ >= n_; }

 private:
  const char* text_;
  std::size_t n_;
  std::size_t pos_ = 0;
  std::int64_t start_ns_;
  bool have_first_ = false;
  std::int64_t first_us_ = 0;
  CanBusStats stats_;
  std::uint32_t bad_lines_ = 0;
  std::uint32_t line_ = 0;
  std::uint32_t first_bad_line_ = 0;
  void bad_line() noexcept {
    ++bad_lines_;
    if (first_bad_line_ == 0) first_bad_line_ = line_;
  }
};

}  // namespace qnav::hal
