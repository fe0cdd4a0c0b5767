// PtyDevice: a pseudo-terminal that plays a serial device (the HIL scenario player's DVL, `qnav hil
// play`). The master side is ours; the slave side is what the daemon opens as its UART, through a
// symlink at a stable path (/tmp/dvl0), as udev names a USB serial adapter.
//  - open(): posix_openpt + grantpt + unlockpt, the slave set to raw mode and kept open by us (so the
//    line stays up while the daemon closes and reopens it), then the link. An existing symlink at the
//    path is replaced; anything else there (a user's file, a real device node) is an error, never
//    removed.
//  - unplug(): master and slave closed and the link removed: the daemon's next read sees a hang-up,
//    as when an adapter is pulled. open() again plugs it back (a new slave behind the same link).
//  - write(): non-blocking, returns the bytes the line accepted. drain(): reads and discards what the
//    daemon wrote, so the master's buffer never fills.
// Errors name the call, the path and the OS reason (strerror). No heap.
#pragma once

#include <cstddef>
#include <cstdint>

#include "nav/core/span.hpp"
#include "nav/core/status.hpp"

namespace qnav::hal {

class PtyDevice {
 public:
  PtyDevice() noexcept = default;
  ~PtyDevice();
  PtyDevice(const PtyDevice&) = delete;
  PtyDevice& operator=(const PtyDevice&) = delete;

  Status open(const char* link_path) noexcept;
  void unplug() noexcept;
  bool is_open() const noexcept { return master_ >= 0; }
  const char* slave_path() const noexcept { return slave_name_; }
  Result<std::size_t> write(Span<const std::uint8_t> data) noexcept;
  std::size_t drain() noexcept;

 private:
  int master_ = -1;
  int slave_ = -1;
  char slave_name_[64] = {};
  char link_[256] = {};
};

}  // namespace qnav::hal
