// PNG output for the tool and the tests (waterfalls, tiles, plots, debug images). Host-side only
// (libpng); never used by nav/ or the daemon's hot path. Writes to a temporary file and renames it,
// so a reader never sees a half-written image.
#pragma once

#include <cstdint>
#include <vector>

#include "nav/core/image.hpp"
#include "nav/core/status.hpp"

namespace qnav::tools {

// 8-bit grey.
Status write_png_gray8(const char* path, ConstImageViewU8 image) noexcept;
// 8-bit RGB, interleaved (width * 3 bytes per row, row stride in bytes given).
Status write_png_rgb8(const char* path, const std::uint8_t* rgb, int width, int height, int stride_bytes) noexcept;
// Float image mapped linearly from [lo, hi] to [0, 255] (values outside clamp; NaN -> 0).
Status write_png_float(const char* path, ConstImageViewF32 image, float lo, float hi) noexcept;
// The grey levels write_png_float writes (row-major, width x height; empty on a bad range), for a
// raster_plot.hpp plot of the same image.
std::vector<std::uint8_t> gray8_from_float(ConstImageViewF32 image, float lo, float hi);

}  // namespace qnav::tools
