// SplitPort: a hal::SerialPort that delivers a byte stream in pieces of 1..max_piece bytes whose sizes
// come from a generator seeded by the fuzz input, so a stream parser sees the same bytes split at
// arbitrary points (mid-sync-word, mid-line, mid-checksum). Arrival time advances 1 ms per read.
// Header-only test helper; no heap.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

#include "hal/core/serial.hpp"

namespace qnav::fuzz {

class SplitPort final : public hal::SerialPort {
 public:
  SplitPort(const std::uint8_t* data, std::size_t size, std::uint32_t seed, std::size_t max_piece) noexcept
      : p_(data), n_(size), rng_(seed | 1u), max_piece_(max_piece == 0 ? 1 : max_piece) {}
  Result<hal::SerialRead> read(Span<std::uint8_t> buf, int) noexcept override {
    hal::SerialRead r;
    r.arrival_ns = (now_ns_ += 1000000);
    if (pos_ >= n_ || buf.empty()) return r;
    rng_ ^= rng_ << 13;
    rng_ ^= rng_ >> 17;
    rng_ ^= rng_ << 5;
    std::size_t k = 1 + rng_ % max_piece_;
    if (k > buf.size()) k = buf.size();
    if (k > n_ - pos_) k = n_ - pos_;
    std::memcpy(buf.data(), p_ + pos_, k);
    pos_ += k;
    r.bytes = k;
    stats_.rx_bytes += static_cast<std::uint32_t>(k);
    return r;
  }
  Result<std::size_t> write(Span<const std::uint8_t> data) noexcept override { return data.size(); }
  hal::SerialStats stats() const noexcept override { return stats_; }
  bool finished() const noexcept { return pos_ >= n_; }

 private:
  const std::uint8_t* p_;
  std::size_t n_;
  std::size_t pos_ = 0;
  std::uint32_t rng_;
  std::size_t max_piece_;
  std::int64_t now_ns_ = 0;
  hal::SerialStats stats_{};
};

}  // namespace qnav::fuzz
