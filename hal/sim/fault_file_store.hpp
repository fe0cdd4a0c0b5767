// FaultFileStore: a FileStore that forwards to another one and, while full() is set, fails every call
// that would add data (write_at, truncate to grow, sync_data, sync, rename, sync_name) the way a full
// disk does (kCapacityExceeded, "No space left on device"); reads and closes still work. Fault tests
// and the sim backend's sim.fault = "disk_full" use it to check that a route stays valid up to its
// last durable node. set_full() may be called from another thread than the store's user (atomic).
// No heap; every target.
#pragma once

#include <atomic>
#include <cstdint>

#include "hal/core/file_store.hpp"

namespace qnav::hal {

class FaultFileStore final : public FileStore {
 public:
  explicit FaultFileStore(FileStore& base) noexcept : base_(base) {}
  void set_full(bool full) noexcept { full_.store(full, std::memory_order_release); }
  bool full() const noexcept { return full_.load(std::memory_order_acquire); }
  std::uint32_t refused() const noexcept { return refused_.load(std::memory_order_relaxed); }

  Result<int> open(const char* path, FileMode mode) noexcept override {
    if ((mode == FileMode::kCreateNew || mode == FileMode::kCreateOrTruncate) && full()) return refuse();
    return base_.open(path, mode);
  }
  void close(int handle) noexcept override { base_.close(handle); }
  Status read_at(int handle, std::uint8_t* data, std::size_t n, std::uint64_t offset) noexcept override {
    return base_.read_at(handle, data, n, offset);
  }
  Status write_at(int handle, const std::uint8_t* data, std::size_t n, std::uint64_t offset) noexcept override {
    if (full()) return refuse();
    return base_.write_at(handle, data, n, offset);
  }
  Result<std::uint64_t> size(int handle) noexcept override { return base_.size(handle); }
  Status truncate(int handle, std::uint64_t size) noexcept override {
    if (full()) return refuse();
    return base_.truncate(handle, size);
  }
  Status sync_data(int handle) noexcept override {
    if (full()) return refuse();
    return base_.sync_data(handle);
  }
  Status sync(int handle) noexcept override {
    if (full()) return refuse();
    return base_.sync(handle);
  }
  Status rename(const char* from, const char* to) noexcept override {
    if (full()) return refuse();
    return base_.rename(from, to);
  }
  Status sync_name(const char* path) noexcept override {
    if (full()) return refuse();
    return base_.sync_name(path);
  }

 private:
  Status refuse() noexcept {
    refused_.fetch_add(1, std::memory_order_relaxed);
    return Status(StatusCode::kCapacityExceeded, "No space left on device (injected: sim.fault = disk_full)");
  }
  FileStore& base_;
  std::atomic<bool> full_{false};
  std::atomic<std::uint32_t> refused_{0};
};

}  // namespace qnav::hal
