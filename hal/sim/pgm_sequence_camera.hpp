// PgmSequenceCamera: a hal::Camera that replays a numbered sequence of binary PGM (P5, 8-bit) files,
// e.g. "run1/left_%06d.pgm" for index first..first+count-1. Frame i is stamped sample_ns =
// stamps[i] when a stamp list is given (e.g. from a recording's index), else start_ns + i * period_ns.
// open() reads the first file's header to fix the format and allocates one file buffer (the only
// heap use); capture() reads the next file with open()/read() (no stdio, no heap), checks that its
// size matches, and copies it into the caller's view. After the last frame capture() returns kEmpty.
// A missing or malformed file is an error (kNotFound / kCorrupt) and counts `corrupt`; the sequence
// moves on. Worst case per capture: one file of the fixed size.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>

#include "hal/core/camera.hpp"
#include "nav/core/span.hpp"

namespace qnav::hal {

struct PgmSequenceConfig {
  const char* pattern = nullptr;  // one %d or %0Nd conversion, e.g. "left_%06d.pgm"
  int first = 0;
  int count = 0;
  std::int64_t start_ns = 0;
  std::int64_t period_ns = 50000000;
  Span<const std::int64_t> stamps;  // optional, count entries
};

// Expands a pattern with exactly one %d / %0Nd conversion (no other printf features; "%%" = '%').
bool expand_sequence_pattern(const char* pattern, int index, char* out, std::size_t cap) noexcept;
// Parses a P5 header; on success `offset` is the first pixel byte. Pure; exposed for tests/fuzzing.
Status parse_pgm_header(const std::uint8_t* p, std::size_t n, int& width, int& height, std::size_t& offset) noexcept;

class PgmSequenceCamera final : public Camera {
 public:
  Status open(const PgmSequenceConfig& config);
  CameraFormat format() const noexcept override { return format_; }
  Result<CameraFrameInfo> capture(ImageView<std::uint8_t> gray_out, int timeout_ms) noexcept override;
  CameraStats stats() const noexcept override { return stats_; }
  int remaining() const noexcept { return config_.count - next_; }

 private:
  Result<std::size_t> read_file(int index) noexcept;
  PgmSequenceConfig config_;
  CameraFormat format_;
  std::unique_ptr<std::uint8_t[]> buf_;
  std::size_t cap_ = 0;
  int next_ = 0;
  CameraStats stats_;
};

}  // namespace qnav::hal
