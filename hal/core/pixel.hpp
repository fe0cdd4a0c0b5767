// Pixel conversion from camera buffers to 8-bit grey (the only pixel type the pipeline uses).
//  - GREY: row copy honouring the source stride (bytes_per_line).
//  - YUYV (YUY2, 4:2:2): the luma bytes (every other byte) are the grey image.
// Pure, no heap, O(width * height). Errors: kInvalidArgument when the buffer is too small for the
// stated format or the output has another size.
#pragma once

#include <cstddef>
#include <cstdint>

#include "hal/core/camera.hpp"
#include "nav/core/image.hpp"
#include "nav/core/status.hpp"

namespace qnav::hal {

Status convert_to_gray(const std::uint8_t* src, std::size_t src_bytes, const CameraFormat& fmt,
                       ImageView<std::uint8_t> out) noexcept;

}  // namespace qnav::hal
