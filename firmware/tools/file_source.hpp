// FileSource: a sidescan::ByteSource over a file, for the host tools (qnav sonar / route / xtf) and the
// tests that read recorded files. Here, above drivers/, because it calls the OS (stdio): the drivers'
// parsers read any ByteSource and stay free of I/O. Header-only.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>

#include "drivers/sidescan/byte_source.hpp"

namespace qnav::tools {

// Owns a FILE*; closes it in the destructor.
class FileSource final : public sidescan::ByteSource {
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

}  // namespace qnav::tools
