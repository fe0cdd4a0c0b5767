// PosixFileStore: hal::FileStore on the Linux file system (open/pread/pwrite/fdatasync/fsync/rename,
// and an fsync of the directory for durable names). Error messages carry strerror(errno). Handles
// are file descriptors. No heap.
#pragma once

#include "hal/core/file_store.hpp"

namespace qnav::hal {

class PosixFileStore final : public FileStore {
 public:
  Result<int> open(const char* path, FileMode mode) noexcept override;
  void close(int handle) noexcept override;
  Status read_at(int handle, std::uint8_t* data, std::size_t n, std::uint64_t offset) noexcept override;
  Status write_at(int handle, const std::uint8_t* data, std::size_t n, std::uint64_t offset) noexcept override;
  Result<std::uint64_t> size(int handle) noexcept override;
  Status truncate(int handle, std::uint64_t size) noexcept override;
  Status sync_data(int handle) noexcept override;
  Status sync(int handle) noexcept override;
  Status rename(const char* from, const char* to) noexcept override;
  Status sync_name(const char* path) noexcept override;
};

// The host's file system (one instance; PosixFileStore holds no state).
PosixFileStore& host_file_store() noexcept;

}  // namespace qnav::hal
