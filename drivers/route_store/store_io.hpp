// What the route file and the experience file share on a hal::FileStore (internal to
// drivers/route_store, included by its .cpp files only): opening a file with its size, and reading one
// fixed-size record after the header. No allocation; one store call per step.
#pragma once

#include <cstdint>

#include "hal/core/file_store.hpp"
#include "nav/core/span.hpp"
#include "nav/core/status.hpp"

namespace qnav::drivers::route_store {

// Opens path and takes its size: ok with fd and size set, or the error with fd untouched (the file
// closed again when its size could not be read).
inline Status open_sized(hal::FileStore& store, const char* path, hal::FileMode mode, int& fd, std::uint64_t& size) noexcept {
  Result<int> h = store.open(path, mode);
  if (!h) return h.status();
  Result<std::uint64_t> n = store.size(*h);
  if (!n) {
    store.close(*h);
    return n.status();
  }
  fd = *h;
  size = *n;
  return Status::ok();
}

// Reads record `index` of `count` (each record.size() bytes, after header_bytes of header) into
// record. not_open / beyond: the errors' messages when fd < 0 / index >= count.
inline Status read_fixed_record(hal::FileStore& store, int fd, Span<std::uint8_t> record, std::uint64_t header_bytes, std::uint32_t index,
                                std::uint32_t count, const char* not_open, const char* beyond) noexcept {
  if (fd < 0) return Status(StatusCode::kNotReady, not_open);
  if (index >= count) return Status(StatusCode::kOutOfRange, beyond);
  return store.read_at(fd, record.data(), record.size(), header_bytes + static_cast<std::uint64_t>(index) * record.size());
}

}  // namespace qnav::drivers::route_store
