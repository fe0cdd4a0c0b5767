// Helpers for the fuzz targets (test/fuzz/fuzz_target.hpp): the target registry, an input cursor that
// carves choices out of the fuzz input, a per-process scratch file for readers that take a path, and
// file helpers for the seeds. Test code: allocates freely; POSIX calls (every target incl. qemu).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "test/fuzz/fuzz_target.hpp"

namespace qnav::fuzz {

// Reads choices from the front of the input; the rest is the payload. Past the end, values are 0.
class Cursor {
 public:
  Cursor(const std::uint8_t* data, std::size_t size) noexcept : p_(data), n_(size) {}
  std::uint8_t u8() noexcept { return i_ < n_ ? p_[i_++] : 0; }
  std::uint16_t u16() noexcept { return static_cast<std::uint16_t>(u8() | (u8() << 8)); }
  std::size_t remaining() const noexcept { return n_ - i_; }
  const std::uint8_t* here() const noexcept { return p_ + i_; }
  void skip(std::size_t k) noexcept { i_ += k < remaining() ? k : remaining(); }

 private:
  const std::uint8_t* p_;
  std::size_t n_;
  std::size_t i_ = 0;
};

// Writes bytes to <scratch dir>/<name> (scratch dir: $TMPDIR or /tmp, then qnav-fuzz-<pid>; removed
// at exit) and returns the path. For readers that only take a file name.
std::string write_scratch(const char* name, const void* data, std::size_t size);
// The scratch directory (created on first use), without a trailing slash, and a directory in it
// (parents first; removed at exit with the files).
const std::string& scratch_dir();
std::string scratch_subdir(const char* rel);

// Seeds: up to max_bytes from the front of a file ("" when absent), and whole files.
std::string read_prefix(const std::string& path, std::size_t max_bytes);
void add_file_seed(Seeds& out, const std::string& name, const std::string& path, std::size_t max_bytes = 1u << 20);
// Regular files in a directory, sorted by name (empty when the directory does not exist).
std::vector<std::string> list_files(const std::string& dir);

std::string shared_dir();  // ../shared (QNAV_SHARED_DIR): the real sample data
std::string source_dir();  // the repository (QNAV_SOURCE_DIR)

}  // namespace qnav::fuzz
