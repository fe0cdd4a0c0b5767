// LineAssembler: bytes from a serial port -> complete lines (terminated by '\n' or '\r'; empty lines
// are skipped). A line longer than kMaxLine is dropped up to its terminator and counted
// (overlong()); the next line starts clean. line() is valid until the next push(). No heap, O(1)/byte.
#pragma once

#include <cstddef>
#include <cstdint>

namespace qnav::drivers::dvl {

class LineAssembler {
 public:
  static constexpr std::size_t kMaxLine = 256;
  // Feeds one byte; returns true when a complete line is available in line()/size().
  bool push(std::uint8_t b) noexcept;
  const char* line() const noexcept { return buf_; }
  std::size_t size() const noexcept { return done_len_; }
  std::uint32_t overlong() const noexcept { return overlong_; }

 private:
  char buf_[kMaxLine + 1] = {};
  std::size_t len_ = 0;
  std::size_t done_len_ = 0;
  bool discarding_ = false;
  std::uint32_t overlong_ = 0;
};

}  // namespace qnav::drivers::dvl
