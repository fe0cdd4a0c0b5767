#include "hal/linux/posix_file_store.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace qnav::hal {
namespace {

thread_local char t_reason[320];

Status os_error(const char* what, const char* path = nullptr) noexcept {
  const int err = errno;
  if (path)
    std::snprintf(t_reason, sizeof t_reason, "%s %s: %s", what, path, std::strerror(err));
  else
    std::snprintf(t_reason, sizeof t_reason, "%s: %s", what, std::strerror(err));
  const StatusCode code = err == ENOENT                      ? StatusCode::kNotFound
                          : err == EEXIST                    ? StatusCode::kInvalidArgument
                          : (err == ENOSPC || err == EDQUOT) ? StatusCode::kCapacityExceeded
                                                             : StatusCode::kIoError;
  return Status(code, t_reason);
}

}  // namespace

PosixFileStore& host_file_store() noexcept {
  static PosixFileStore store;
  return store;
}

Result<int> PosixFileStore::open(const char* path, FileMode mode) noexcept {
  int flags = O_CLOEXEC;
  switch (mode) {
    case FileMode::kRead: flags |= O_RDONLY; break;
    case FileMode::kReadWrite: flags |= O_RDWR; break;
    case FileMode::kCreateNew: flags |= O_RDWR | O_CREAT | O_EXCL; break;
    case FileMode::kCreateOrTruncate: flags |= O_RDWR | O_CREAT | O_TRUNC; break;
  }
  const int fd = ::open(path, flags, 0644);
  if (fd < 0) return os_error("cannot open", path);
  struct stat st {};
  if (::fstat(fd, &st) == 0 && S_ISDIR(st.st_mode)) {
    ::close(fd);
    errno = EISDIR;
    return os_error("cannot open", path);
  }
  return fd;
}

void PosixFileStore::close(int handle) noexcept {
  if (handle >= 0) ::close(handle);
}

Status PosixFileStore::read_at(int handle, std::uint8_t* p, std::size_t n, std::uint64_t at) noexcept {
  while (n > 0) {
    const ssize_t r = ::pread(handle, p, n, static_cast<off_t>(at));
    if (r < 0) {
      if (errno == EINTR) continue;
      return os_error("read failed");
    }
    if (r == 0) return Status(StatusCode::kTruncated, "unexpected end of file");
    p += r;
    n -= static_cast<std::size_t>(r);
    at += static_cast<std::uint64_t>(r);
  }
  return Status::ok();
}

Status PosixFileStore::write_at(int handle, const std::uint8_t* p, std::size_t n, std::uint64_t at) noexcept {
  while (n > 0) {
    const ssize_t w = ::pwrite(handle, p, n, static_cast<off_t>(at));
    if (w < 0) {
      if (errno == EINTR) continue;
      return os_error("write failed");
    }
    p += w;
    n -= static_cast<std::size_t>(w);
    at += static_cast<std::uint64_t>(w);
  }
  return Status::ok();
}

Result<std::uint64_t> PosixFileStore::size(int handle) noexcept {
  struct stat st {};
  if (::fstat(handle, &st) != 0) return os_error("stat failed");
  return static_cast<std::uint64_t>(st.st_size);
}

Status PosixFileStore::truncate(int handle, std::uint64_t size) noexcept {
  if (::ftruncate(handle, static_cast<off_t>(size)) != 0) return os_error("truncate failed");
  return Status::ok();
}

Status PosixFileStore::sync_data(int handle) noexcept {
  if (::fdatasync(handle) != 0) return os_error("fdatasync failed");
  return Status::ok();
}

Status PosixFileStore::sync(int handle) noexcept {
  if (::fsync(handle) != 0) return os_error("fsync failed");
  return Status::ok();
}

Status PosixFileStore::rename(const char* from, const char* to) noexcept {
  if (::rename(from, to) != 0) return os_error("rename failed", from);
  return sync_name(to);
}

// fsync the directory holding path, so the file's name (create, rename) is durable too.
Status PosixFileStore::sync_name(const char* path) noexcept {
  char dir[4096];
  const char* slash = std::strrchr(path, '/');
  const std::size_t n = slash == nullptr ? 0 : static_cast<std::size_t>(slash - path);
  if (slash == nullptr) {
    std::strcpy(dir, ".");
  } else if (n == 0) {
    std::strcpy(dir, "/");
  } else {
    if (n >= sizeof dir) return Status(StatusCode::kInvalidArgument, "path too long");
    std::memcpy(dir, path, n);
    dir[n] = '\0';
  }
  const int d = ::open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (d < 0) return os_error("cannot open directory", dir);
  const int rc = ::fsync(d);
  ::close(d);
  if (rc != 0) return os_error("directory fsync failed", dir);
  return Status::ok();
}

}  // namespace qnav::hal
