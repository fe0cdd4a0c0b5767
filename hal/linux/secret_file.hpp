// read_secret_file: one small secret (a signing key) read together with what the kernel says of the
// file it came from, so the caller can refuse a key that others could read or replace.
//  - open(O_RDONLY | O_NOFOLLOW | O_CLOEXEC | O_NOCTTY | O_NONBLOCK): a symbolic link as the last path
//    component is refused (ELOOP), a FIFO or device does not block the open;
//  - fstat() on the descriptor that is read (owner, mode and type describe the bytes returned: no
//    window between a stat() and an open() for someone to swap the file);
//  - a regular file only: its first out.size() bytes are read (truncated = it holds more).
// Errors: kNotFound (no such file), kIoError (any other OS error; the message names path and reason,
// in device_error's thread-local buffer). Policy (which owner, which mode) is the caller's.
// O(out.size()) time, no heap. hal/linux only (the one place that calls the OS).
#pragma once

#include <cstddef>
#include <cstdint>

#include "nav/core/span.hpp"
#include "nav/core/status.hpp"

namespace qnav::hal {

struct SecretFileInfo {
  bool regular = false;         // S_ISREG; when false nothing was read
  std::uint32_t owner_uid = 0;  // st_uid
  std::uint32_t mode = 0;       // st_mode & 07777 (permission bits, setuid/setgid/sticky)
  std::size_t bytes = 0;        // bytes read into out
  bool truncated = false;       // the file holds more than out.size() bytes
};

Result<SecretFileInfo> read_secret_file(const char* path, Span<std::uint8_t> out) noexcept;

// The real user id of this process (the tests pass it where production requires root, uid 0).
std::uint32_t current_uid() noexcept;

}  // namespace qnav::hal
