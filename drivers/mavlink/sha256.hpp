// SHA-256 (FIPS 180-4), small and self-contained, for MAVLink 2 signing. Incremental: update() any
// number of times, then finish(). Big-endian message schedule written with explicit shifts (correct
// on any host byte order). O(n) time, 104 bytes of state, no heap.
#pragma once

#include <cstddef>
#include <cstdint>

namespace qnav::drivers::mavlink {

class Sha256 {
 public:
  Sha256() noexcept { reset(); }
  void reset() noexcept;
  void update(const std::uint8_t* data, std::size_t n) noexcept;
  void finish(std::uint8_t digest[32]) noexcept;

 private:
  void block(const std::uint8_t* p) noexcept;
  std::uint32_t h_[8];
  std::uint8_t buf_[64];
  std::size_t buf_len_ = 0;
  std::uint64_t total_bytes_ = 0;
};

}  // namespace qnav::drivers::mavlink
