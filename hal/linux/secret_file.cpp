#include "hal/linux/secret_file.hpp"

#include <cerrno>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include "hal/linux/device_error.hpp"

namespace qnav::hal {

Result<SecretFileInfo> read_secret_file(const char* path, Span<std::uint8_t> out) noexcept {
  if (path == nullptr || path[0] == '\0') return Status(StatusCode::kInvalidArgument, "secret file: no path");
  const int fd = ::open(path, O_RDONLY | O_NOFOLLOW | O_CLOEXEC | O_NOCTTY | O_NONBLOCK);
  if (fd < 0) {
    const int err = errno;
    return device_error(err == ENOENT ? StatusCode::kNotFound : StatusCode::kIoError, "cannot open secret file", path, err,
                        err == ELOOP ? "a symbolic link is not accepted: name the file itself" : nullptr);
  }
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    const int err = errno;
    ::close(fd);
    return device_error(StatusCode::kIoError, "cannot stat secret file", path, err, nullptr);
  }
  SecretFileInfo info;
  info.regular = S_ISREG(st.st_mode);
  info.owner_uid = static_cast<std::uint32_t>(st.st_uid);
  info.mode = static_cast<std::uint32_t>(st.st_mode & 07777);
  if (info.regular) {
    while (info.bytes < out.size()) {
      const ssize_t n = ::read(fd, out.data() + info.bytes, out.size() - info.bytes);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) {
        const int err = errno;
        ::close(fd);
        return device_error(StatusCode::kIoError, "cannot read secret file", path, err, nullptr);
      }
      if (n == 0) break;
      info.bytes += static_cast<std::size_t>(n);
    }
    if (info.bytes == out.size()) {
      std::uint8_t extra = 0;
      ssize_t n = 0;
      do {
        n = ::read(fd, &extra, 1);
      } while (n < 0 && errno == EINTR);
      info.truncated = n > 0;
    }
  }
  ::close(fd);
  return info;
}

std::uint32_t current_uid() noexcept { return static_cast<std::uint32_t>(::getuid()); }

}  // namespace qnav::hal
