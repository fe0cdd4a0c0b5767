#include "hal/linux/pty_device.hpp"

#include <errno.h>
#include <fcntl.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include <cstring>

#include "hal/linux/device_error.hpp"

namespace qnav::hal {

PtyDevice::~PtyDevice() { unplug(); }

void PtyDevice::unplug() noexcept {
  if (link_[0] != '\0') {
    struct stat st {};
    if (::lstat(link_, &st) == 0 && S_ISLNK(st.st_mode)) (void)::unlink(link_);
  }
  if (slave_ >= 0) ::close(slave_);
  if (master_ >= 0) ::close(master_);
  slave_ = master_ = -1;
  slave_name_[0] = '\0';
}

Status PtyDevice::open(const char* link_path) noexcept {
  unplug();
  if (link_path == nullptr || link_path[0] == '\0' || std::strlen(link_path) >= sizeof link_) {
    return Status(StatusCode::kInvalidArgument, "pseudo-terminal link path missing or too long");
  }
  std::strcpy(link_, link_path);
  struct stat st {};
  if (::lstat(link_, &st) == 0 && !S_ISLNK(st.st_mode)) {
    link_[0] = '\0';
    return device_error(StatusCode::kInvalidArgument, "will not replace (not a symlink)", link_path, EEXIST,
                        "remove it or choose another path for the pseudo-terminal");
  }
  master_ = ::posix_openpt(O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (master_ < 0) return device_error(StatusCode::kIoError, "posix_openpt failed for", link_path, errno, "is /dev/pts mounted?");
  const char* name = nullptr;
  if (::grantpt(master_) != 0 || ::unlockpt(master_) != 0 || (name = ::ptsname(master_)) == nullptr ||
      std::strlen(name) >= sizeof slave_name_) {
    const int err = errno;
    unplug();
    return device_error(StatusCode::kIoError, "cannot unlock the pseudo-terminal for", link_path, err, nullptr);
  }
  std::strcpy(slave_name_, name);
  slave_ = ::open(slave_name_, O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  termios t{};
  if (slave_ < 0 || ::tcgetattr(slave_, &t) != 0) {
    const int err = errno;
    unplug();
    return device_error(StatusCode::kIoError, "cannot open the pseudo-terminal's slave for", link_path, err, nullptr);
  }
  ::cfmakeraw(&t);
  (void)::tcsetattr(slave_, TCSANOW, &t);
  (void)::unlink(link_);  // a stale symlink from an earlier run (checked above)
  if (::symlink(slave_name_, link_) != 0) {
    const int err = errno;
    link_[0] = '\0';  // not ours: unplug() must not remove what is there
    unplug();
    return device_error(StatusCode::kIoError, "cannot make the pseudo-terminal's link", link_path, err, nullptr);
  }
  return Status::ok();
}

Result<std::size_t> PtyDevice::write(Span<const std::uint8_t> data) noexcept {
  if (master_ < 0) return Status(StatusCode::kNotReady, "pseudo-terminal unplugged");
  const ssize_t n = ::write(master_, data.data(), data.size());
  if (n < 0) {
    if (errno == EAGAIN || errno == EWOULDBLOCK) return std::size_t{0};
    return Status(StatusCode::kIoError, "pseudo-terminal write failed");
  }
  return static_cast<std::size_t>(n);
}

std::size_t PtyDevice::drain() noexcept {
  std::size_t total = 0;
  std::uint8_t buf[512];
  while (master_ >= 0) {
    const ssize_t n = ::read(master_, buf, sizeof buf);
    if (n <= 0) break;
    total += static_cast<std::size_t>(n);
  }
  return total;
}

}  // namespace qnav::hal
