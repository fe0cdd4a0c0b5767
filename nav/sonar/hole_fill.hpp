// hole_fill: the side-scan tile's hole filling (coverage 2), split out of TileBuilder (which calls it
// once per tile, after normalise()). Free functions over caller-owned rasters: no state, no memory
// of their own, no allocation.
// Rule: an empty pixel (coverage 0) inside the box is filled when measured pixels (coverage 1) lie
// within radius_px on both sides along its row or along its column, and in at least min_neighbours
// of the 4 axis directions; its value is the inverse-distance mean (weights 1/k, directions summed
// left, right, up, down) of the nearest measured pixel in each direction found. Only measured pixels
// are read, so filling never cascades: holes wider than 2 radius_px - 1 and the swath's edges stay empty.
// Bounds: radius_px <= 8 (TileBuilderConfig's range); the search stays inside the box. Cost: covered
// pixels are skipped four at a time; an empty pixel costs at most 4 radius_px coverage reads, fewer
// where one or two directions already rule a pair out (a wide gap such as the nadir).
#pragma once

#include <cstddef>
#include <cstdint>

namespace qnav::sonar {

struct RasterBox {
  int x0 = 0, y0 = 0, x1 = -1, y1 = -1;  // inclusive pixel box inside the raster (x1 < x0: empty)
};

// Rasters of one tile, row-major, width pixels a row (intensity and coverage: the whole raster).
struct HoleFillRaster {
  float* intensity = nullptr;
  std::uint8_t* coverage = nullptr;  // 0 no data, 1 measured, 2 filled (set here)
  std::uint8_t* u8 = nullptr;        // quantised intensity of the filled pixels is written here; nullptr: none
  int width = 0;
};

// The tile's u8 quantisation: intensity * scale + 0.5 clamped to [0, 255] and truncated (scale =
// 255 / display_max, as TileBuilder::normalise() computes it).
inline std::uint8_t intensity_to_u8(float intensity, float scale) noexcept {
  float u = intensity * scale + 0.5f;
  u = u < 0.0f ? 0.0f : (u > 255.0f ? 255.0f : u);
  return static_cast<std::uint8_t>(static_cast<std::int32_t>(u));
}

// Fills the holes of the box by the rule above; returns how many pixels it filled (coverage 2).
// radius_px outside [1, 8] or an empty box: nothing (returns 0). min_neighbours in [1, 4].
std::size_t fill_holes(const HoleFillRaster& raster, const RasterBox& box, int radius_px, int min_neighbours,
                       float u8_scale) noexcept;

}  // namespace qnav::sonar
