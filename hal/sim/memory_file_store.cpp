#include "hal/sim/memory_file_store.hpp"

#include <cstring>

namespace qnav::hal {

MemoryFileStore::MemoryFileStore(Span<std::uint8_t> storage) noexcept : storage_(storage), capacity_(storage.size() / kMaxFiles) {}

int MemoryFileStore::find(const char* path) const noexcept {
  for (std::size_t i = 0; i < kMaxFiles; ++i)
    if (files_[i].used && std::strncmp(files_[i].name, path, kMaxName) == 0) return static_cast<int>(i);
  return -1;
}

MemoryFileStore::File* MemoryFileStore::file(int handle) noexcept {
  if (handle < 0 || static_cast<std::size_t>(handle) >= kMaxFiles || !files_[handle].used || !files_[handle].open) return nullptr;
  return &files_[handle];
}

Result<int> MemoryFileStore::open(const char* path, FileMode mode) noexcept {
  if (path == nullptr || std::strlen(path) >= kMaxName) return Status(StatusCode::kInvalidArgument, "memory store: name too long");
  int slot = find(path);
  if (slot >= 0 && files_[slot].open) return Status(StatusCode::kInvalidArgument, "memory store: file already open");
  if (slot < 0) {
    if (mode == FileMode::kRead || mode == FileMode::kReadWrite) return Status(StatusCode::kNotFound, "memory store: no such file");
    for (std::size_t i = 0; i < kMaxFiles && slot < 0; ++i)
      if (!files_[i].used) slot = static_cast<int>(i);
    if (slot < 0) return Status(StatusCode::kCapacityExceeded, "memory store: no free file slot");
    File& f = files_[slot];
    f = File{};
    std::strncpy(f.name, path, kMaxName - 1);
    f.used = true;
  } else if (mode == FileMode::kCreateNew) {
    return Status(StatusCode::kInvalidArgument, "memory store: file exists");
  } else if (mode == FileMode::kCreateOrTruncate) {
    files_[slot].size = 0;
  }
  files_[slot].open = true;
  files_[slot].writable = mode != FileMode::kRead;
  return slot;
}

void MemoryFileStore::close(int handle) noexcept {
  if (File* f = file(handle)) f->open = false;
}

Status MemoryFileStore::read_at(int handle, std::uint8_t* p, std::size_t n, std::uint64_t at) noexcept {
  File* f = file(handle);
  if (!f) return Status(StatusCode::kInvalidArgument, "memory store: bad handle");
  if (at > f->size || n > f->size - at) return Status(StatusCode::kTruncated, "unexpected end of file");
  std::memcpy(p, data(handle) + at, n);
  return Status::ok();
}

Status MemoryFileStore::write_at(int handle, const std::uint8_t* p, std::size_t n, std::uint64_t at) noexcept {
  File* f = file(handle);
  if (!f || !f->writable) return Status(StatusCode::kInvalidArgument, "memory store: bad handle or read only");
  if (at > capacity_ || n > capacity_ - at) return Status(StatusCode::kCapacityExceeded, "memory store: file full");
  if (n > write_budget_) {
    write_budget_ = 0;
    return Status(StatusCode::kIoError, "memory store: medium failed (injected)");
  }
  if (write_budget_ != static_cast<std::size_t>(-1)) write_budget_ -= n;
  if (at > f->size) std::memset(data(handle) + f->size, 0, static_cast<std::size_t>(at) - f->size);  // a hole reads as zeros
  std::memcpy(data(handle) + at, p, n);
  if (at + n > f->size) f->size = static_cast<std::size_t>(at + n);
  return Status::ok();
}

Result<std::uint64_t> MemoryFileStore::size(int handle) noexcept {
  File* f = file(handle);
  if (!f) return Status(StatusCode::kInvalidArgument, "memory store: bad handle");
  return static_cast<std::uint64_t>(f->size);
}

Status MemoryFileStore::truncate(int handle, std::uint64_t size) noexcept {
  File* f = file(handle);
  if (!f || !f->writable) return Status(StatusCode::kInvalidArgument, "memory store: bad handle or read only");
  if (size > f->size) return Status(StatusCode::kInvalidArgument, "memory store: truncate only shrinks");
  f->size = static_cast<std::size_t>(size);
  return Status::ok();
}

Status MemoryFileStore::sync_data(int handle) noexcept { return file(handle) ? Status::ok() : Status(StatusCode::kInvalidArgument, "memory store: bad handle"); }
Status MemoryFileStore::sync(int handle) noexcept { return sync_data(handle); }

Status MemoryFileStore::rename(const char* from, const char* to) noexcept {
  const int a = find(from);
  if (a < 0) return Status(StatusCode::kNotFound, "memory store: no such file");
  if (std::strlen(to) >= kMaxName) return Status(StatusCode::kInvalidArgument, "memory store: name too long");
  const int b = find(to);
  if (b >= 0 && b != a) {
    if (files_[b].open) return Status(StatusCode::kInvalidArgument, "memory store: target open");
    files_[b] = File{};
  }
  std::memset(files_[a].name, 0, kMaxName);
  std::strncpy(files_[a].name, to, kMaxName - 1);
  return Status::ok();
}

Status MemoryFileStore::sync_name(const char* path) noexcept {
  return find(path) >= 0 ? Status::ok() : Status(StatusCode::kNotFound, "memory store: no such file");
}

}  // namespace qnav::hal
