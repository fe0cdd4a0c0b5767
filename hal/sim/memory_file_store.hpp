// MemoryFileStore: hal::FileStore in caller-owned memory, for targets without a file system (the
// freestanding LEON build) and for tests. Up to kMaxFiles files; each may grow to
// storage.size() / kMaxFiles bytes (kCapacityExceeded past that). A file is open at most once at a
// time; the handle is its slot. Names up to kMaxName - 1 characters. "Durable" means written to the
// storage span (sync calls succeed; a power cut of this store is the caller's memory going away).
// fail_writes_after() makes the medium fail (kIoError) after a number of bytes, for fault tests.
// No heap; O(kMaxFiles) per open/rename, O(n) per read/write. Single-threaded.
#pragma once

#include <cstddef>
#include <cstdint>

#include "hal/core/file_store.hpp"
#include "nav/core/span.hpp"

namespace qnav::hal {

class MemoryFileStore final : public FileStore {
 public:
  static constexpr std::size_t kMaxFiles = 8;
  static constexpr std::size_t kMaxName = 96;

  explicit MemoryFileStore(Span<std::uint8_t> storage) noexcept;
  std::size_t file_capacity() const noexcept { return capacity_; }
  // After `bytes` more bytes are written, every write fails with kIoError (SIZE_MAX = never).
  void fail_writes_after(std::size_t bytes) noexcept { write_budget_ = bytes; }
  bool exists(const char* path) const noexcept { return find(path) >= 0; }

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

 private:
  struct File {
    char name[kMaxName] = {};
    std::size_t size = 0;
    bool used = false;
    bool open = false;
    bool writable = false;
  };
  int find(const char* path) const noexcept;
  File* file(int handle) noexcept;
  std::uint8_t* data(int slot) noexcept { return storage_.data() + static_cast<std::size_t>(slot) * capacity_; }
  Span<std::uint8_t> storage_;
  std::size_t capacity_ = 0;
  std::size_t write_budget_ = static_cast<std::size_t>(-1);
  File files_[kMaxFiles];
};

}  // namespace qnav::hal
