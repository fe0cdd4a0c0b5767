// Byte sources for the side-scan file readers: the interface and a memory span (tests, fuzzing, files
// already in memory); the file source is the tools' (firmware/tools/file_source.hpp: drivers/ do no I/O).
// read() returns how many bytes it produced (0 = end of data or error; error() tells which). No
// allocation after construction.
#pragma once

#include <cstddef>
#include <cstdint>

#include "nav/core/span.hpp"
#include "nav/core/status.hpp"

namespace qnav::sidescan {

class ByteSource {
 public:
  virtual ~ByteSource() = default;
  virtual std::size_t read(std::uint8_t* dst, std::size_t n) noexcept = 0;
  virtual bool error() const noexcept { return false; }
};

class MemorySource final : public ByteSource {
 public:
  explicit MemorySource(Span<const std::uint8_t> bytes) noexcept : bytes_(bytes) {}
  std::size_t read(std::uint8_t* dst, std::size_t n) noexcept override {
    const std::size_t k = n < bytes_.size() - pos_ ? n : bytes_.size() - pos_;
    for (std::size_t i = 0; i < k; ++i) dst[i] = bytes_[pos_ + i];
    pos_ += k;
    return k;
  }
  std::size_t position() const noexcept { return pos_; }

 private:
  Span<const std::uint8_t> bytes_;
  std::size_t pos_ = 0;
};


}  // namespace qnav::sidescan
