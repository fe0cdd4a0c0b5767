// Camera interface (V4L2 mmap streaming or a file sequence).
//  - CameraConfig: requested size and pixel format and the number of driver buffers (fixed at open;
//    format changes at run time are not supported).
//  - capture(): waits at most timeout_ms for the next frame and converts it to 8-bit grey into the
//    caller's view (which must have the negotiated size); the driver buffer is re-queued before
//    return, so no driver memory escapes. kTimeout when no frame arrived.
//  - CameraFrameInfo: sequence number (gaps = dropped frames), stamps on the monotonic clock,
//    `corrupt` when the driver flagged the buffer (V4L2_BUF_FLAG_ERROR).
// Implementations: hal/linux V4l2Camera, hal/sim PgmSequenceCamera / SimCamera.
#pragma once

#include <cstdint>

#include "hal/core/stamp.hpp"
#include "nav/core/image.hpp"
#include "nav/core/status.hpp"

namespace qnav::hal {

enum class PixelFormat : std::uint8_t { kGrey, kYuyv };

struct CameraConfig {
  const char* device = "/dev/video0";
  int width = 640;
  int height = 480;
  PixelFormat format = PixelFormat::kGrey;
  int buffer_count = 4;  // 2..16
};

struct CameraFormat {
  int width = 0;
  int height = 0;
  PixelFormat format = PixelFormat::kGrey;
  int bytes_per_line = 0;
};

struct CameraFrameInfo {
  std::uint32_t sequence = 0;
  SampleStamp stamp;
  bool corrupt = false;
};

struct CameraStats {
  std::uint32_t frames = 0;
  std::uint32_t dropped = 0;   // sequence gaps
  std::uint32_t corrupt = 0;
  std::uint32_t timeouts = 0;
};

class Camera {
 public:
  virtual ~Camera() = default;
  virtual CameraFormat format() const noexcept = 0;
  virtual Result<CameraFrameInfo> capture(ImageView<std::uint8_t> gray_out, int timeout_ms) noexcept = 0;
  virtual CameraStats stats() const noexcept = 0;
};

}  // namespace qnav::hal
