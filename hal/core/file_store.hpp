// FileStore: durable random-access files, the storage qnav keeps its routes in. An interface so the
// route store (drivers/route_store) is the same code on a Linux flight computer (hal/linux
// PosixFileStore), in tests and replay, and on a LEON without an OS (hal/sim MemoryFileStore, or a
// flash driver behind the same calls).
//  - open() returns a small integer handle; read_at()/write_at() move exactly n bytes or fail
//    (kTruncated when a read runs past the end); sync_data() makes the data written so far durable,
//    sync() data and metadata; rename() replaces `to` atomically and makes the new name durable;
//    sync_name() makes a newly created file's name durable.
//  - Errors: kNotFound (no such file), kInvalidArgument (kCreateNew on an existing file, bad handle),
//    kIoError (the OS or the medium failed; the message says why), kCapacityExceeded (store full).
// No call allocates.
#pragma once

#include <cstddef>
#include <cstdint>

#include "nav/core/status.hpp"

namespace qnav::hal {

enum class FileMode : std::uint8_t {
  kRead,              // existing file, read only
  kReadWrite,         // existing file
  kCreateNew,         // a new file; fails when one exists
  kCreateOrTruncate,  // a new file, or an existing one emptied
};

class FileStore {
 public:
  virtual ~FileStore() = default;
  virtual Result<int> open(const char* path, FileMode mode) noexcept = 0;
  virtual void close(int handle) noexcept = 0;
  virtual Status read_at(int handle, std::uint8_t* data, std::size_t n, std::uint64_t offset) noexcept = 0;
  virtual Status write_at(int handle, const std::uint8_t* data, std::size_t n, std::uint64_t offset) noexcept = 0;
  virtual Result<std::uint64_t> size(int handle) noexcept = 0;
  virtual Status truncate(int handle, std::uint64_t size) noexcept = 0;
  virtual Status sync_data(int handle) noexcept = 0;
  virtual Status sync(int handle) noexcept = 0;
  virtual Status rename(const char* from, const char* to) noexcept = 0;
  virtual Status sync_name(const char* path) noexcept = 0;
};

}  // namespace qnav::hal
