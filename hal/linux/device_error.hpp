// The message of a failed device open: what failed, on which device, the OS reason (strerror) and,
// for the common causes, the fix ("cannot open video device /dev/video0: Permission denied (...)").
// The text lives in a thread-local buffer, valid until the thread's next device_error call (the
// Status keeps a pointer to it); open paths only, no allocation.
#pragma once

#include "nav/core/status.hpp"

namespace qnav::hal {

// `what` and `device` name the failure; err is the errno; hint (may be null) is appended in brackets.
Status device_error(StatusCode code, const char* what, const char* device, int err, const char* hint) noexcept;

// The fix for a V4L2 node that would not open (/dev/videoN), by errno, or null when there is none to give.
const char* v4l2_open_hint(int err) noexcept;
// The fix for a GPIO character device (gpiochipN or /dev/gpiochipN) that would not open, by errno.
const char* gpiochip_open_hint(int err) noexcept;

}  // namespace qnav::hal
