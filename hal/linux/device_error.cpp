#include "hal/linux/device_error.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace qnav::hal {
namespace {
thread_local char t_message[512];
}  // namespace

Status device_error(StatusCode code, const char* what, const char* device, int err, const char* hint) noexcept {
  std::snprintf(t_message, sizeof t_message, "%s %s: %s%s%s%s", what, device != nullptr ? device : "(none)",
                err != 0 ? std::strerror(err) : "unknown error", hint != nullptr ? " (" : "", hint != nullptr ? hint : "",
                hint != nullptr ? ")" : "");
  return Status(code, t_message);
}

const char* v4l2_open_hint(int err) noexcept {
  switch (err) {
    case EACCES:
    case EPERM:
      return "the camera nodes belong to the video group: sudo usermod -aG video $USER and log in again, or give the "
             "service user the device by a udev rule, e.g. SUBSYSTEM==\"video4linux\", GROUP=\"video\", MODE=\"0660\"";
    case ENOENT:
    case ENODEV:
    case ENXIO:
      return "no such camera node: `ls /dev/video*` lists them, v4l2-ctl --list-devices names them; a USB camera needs "
             "the uvcvideo module, a virtual one: sudo modprobe vivid";
    case EBUSY:
      return "another process streams from this camera: fuser /dev/videoN shows it";
    default:
      return nullptr;
  }
}

const char* gpiochip_open_hint(int err) noexcept {
  switch (err) {
    case EACCES:
    case EPERM:
      return "the GPIO chips belong to root: add the user to the gpio group, with a udev rule such as "
             "SUBSYSTEM==\"gpio\", KERNEL==\"gpiochip*\", GROUP=\"gpio\", MODE=\"0660\" (then log in again)";
    case ENOENT:
    case ENODEV:
    case ENXIO:
      return "no such GPIO chip: `gpiodetect` or `ls /dev/gpiochip*` lists them; give the name (gpiochip0) or the "
             "path (/dev/gpiochip0)";
    case ENOTTY:
    case EINVAL:
      return "not a GPIO character device: give gpiochipN or /dev/gpiochipN";
    default:
      return nullptr;
  }
}

}  // namespace qnav::hal
