#include "hal/core/pixel.hpp"

#include <cstring>

namespace qnav::hal {

Status convert_to_gray(const std::uint8_t* src, std::size_t src_bytes, const CameraFormat& fmt,
                       ImageView<std::uint8_t> out) noexcept {
  if (src == nullptr || out.empty()) return Status(StatusCode::kInvalidArgument, "null buffer");
  if (out.width() != fmt.width || out.height() != fmt.height)
    return Status(StatusCode::kInvalidArgument, "output size differs from camera format");
  const std::size_t bpp = fmt.format == PixelFormat::kYuyv ? 2u : 1u;
  const std::size_t row_bytes = static_cast<std::size_t>(fmt.width) * bpp;
  if (fmt.bytes_per_line < 0 || static_cast<std::size_t>(fmt.bytes_per_line) < row_bytes)
    return Status(StatusCode::kInvalidArgument, "bytes_per_line smaller than a row");
  const std::size_t stride = static_cast<std::size_t>(fmt.bytes_per_line);
  if (src_bytes < stride * static_cast<std::size_t>(fmt.height - 1) + row_bytes)
    return Status(StatusCode::kInvalidArgument, "camera buffer smaller than the image");
  for (int y = 0; y < fmt.height; ++y) {
    const std::uint8_t* s = src + stride * static_cast<std::size_t>(y);
    std::uint8_t* d = out.row(y);
    if (fmt.format == PixelFormat::kGrey) {
      std::memcpy(d, s, static_cast<std::size_t>(fmt.width));
    } else {
      for (int x = 0; x < fmt.width; ++x) d[x] = s[2 * x];
    }
  }
  return Status::ok();
}

}  // namespace qnav::hal
