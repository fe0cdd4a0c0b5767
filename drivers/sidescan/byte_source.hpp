// Byte sources for the side-scan file readers: a memory span (tests, fuzzing, files already in
// memory) and a stdio file (the tool and the daemon's replay). read() returns how many bytes it
// produced (0 = end of data or error; error() tells which). No allocation after construction.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>

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

// Owns a FILE*; closes it in the destructor.
class FileSource final : public ByteSource {
 public:
  FileSource() noexcept = default;
  ~FileSource() override {
    if (f_ != nullptr) std::fclose(f_);
  }
  FileSource(const FileSource&) = delete;
  FileSource& operator=(const FileSource&) = delete;
  Status open(const char* path) noexcept {
    if (f_ != nullptr) std::fclose(f_);
    f_ = std::fopen(path, "rb");
    if (f_ == nullptr) return Status(StatusCode::kIoError, "cannot open file");
    return Status::ok();
  }
  std::size_t read(std::uint8_t* dst, std::size_t n) noexcept override {
    if (f_ == nullptr) return 0;
    return std::fread(dst, 1, n, f_);
  }
  bool error() const noexcept override { return f_ == nullptr || std::ferror(f_) != 0; }

 private:
  std::FILE* f_ = nullptr;
};

}  // namespace qnav::sidescan
