#include "nav/sonar/hole_fill.hpp"

#include <cstring>

namespace qnav::sonar {

std::size_t fill_holes(const HoleFillRaster& raster, const RasterBox& box, int radius_px, int min_neighbours, float u8_scale) noexcept {
  // An empty pixel is filled when measured pixels (coverage 1) lie within R on both sides along a
  // row or along a column: the value is the inverse-distance mean of the nearest measured pixel in
  // each of the four directions found. Reads measured pixels only, so filling never cascades:
  // holes wider than 2R - 1 pixels and the swath edges stay empty. Cost <= 4R reads per empty pixel
  // inside the touched box; covered pixels are skipped four at a time (no zero byte in a word).
  const int W = raster.width, R = radius_px;
  if (R <= 0 || R > 8 || box.x1 < box.x0 || box.y1 < box.y0) return 0;
  float* const intensity = raster.intensity;
  std::uint8_t* const coverage = raster.coverage;
  std::uint8_t* const u8 = raster.u8;
  const std::ptrdiff_t steps[4] = {-1, 1, -static_cast<std::ptrdiff_t>(W), static_cast<std::ptrdiff_t>(W)};
  const int bx0 = box.x0, bx1 = box.x1, by0 = box.y0, by1 = box.y1;
  const int min_dirs = min_neighbours;
  const std::uint8_t* cov = coverage;
  float inv_k[9];  // 1 / k for the distances 1..R (R <= 8): no int-to-float conversion per neighbour
  for (int k = 1; k <= 8; ++k) inv_k[k] = 1.0f / static_cast<float>(k);
  inv_k[0] = 0.0f;
  std::size_t filled = 0;
  for (int y = by0; y <= by1; ++y) {
    const std::uint8_t* cov_row = coverage + static_cast<std::size_t>(y) * static_cast<std::size_t>(W);
    for (int x = bx0;; ++x) {
      // Skip to the next empty pixel: bytes up to a 4-byte boundary, then aligned 4-byte words
      // without a zero byte (the word's byte order does not matter, only whether a byte is zero),
      // then bytes again.
      while (x <= bx1 && (reinterpret_cast<std::uintptr_t>(cov_row + x) & 3u) != 0 && cov_row[x] != 0) ++x;
      if (x <= bx1 && cov_row[x] != 0) {
        while (x + 3 <= bx1) {
          std::uint32_t w;
          std::memcpy(&w, __builtin_assume_aligned(cov_row + x, 4), sizeof w);
          if (((w - 0x01010101u) & ~w & 0x80808080u) != 0) break;
          x += 4;
        }
        while (x <= bx1 && cov_row[x] != 0) ++x;
      }
      if (x > bx1) break;
      const std::ptrdiff_t idx = static_cast<std::ptrdiff_t>(y) * W + x;
      const int room[4] = {x - bx0, bx1 - x, y - by0, by1 - y};
      // Distance (1..R) to the nearest measured pixel in direction d, 0 when there is none.
      const auto nearest = [&](int d) {
        const int lim = room[d] < R ? room[d] : R;
        const std::uint8_t* p = cov + idx;
        for (int k = 1; k <= lim; ++k) {
          if (p[k * steps[d]] == 1) return k;
        }
        return 0;
      };
      // A fill needs a pair (left and right, or up and down): look only as far as that can still hold
      // (in a wide empty run, such as the nadir gap, one or two directions settle it). The pair implies
      // two directions; any further minimum is checked once all four are known.
      int k[4] = {nearest(0), 0, 0, 0};
      const bool row_pair = k[0] != 0 && (k[1] = nearest(1)) != 0;
      k[2] = nearest(2);
      if (!row_pair && k[2] == 0) continue;
      k[3] = nearest(3);
      if (!row_pair && k[3] == 0) continue;
      if (k[0] == 0) k[1] = nearest(1);
      const int dirs = (k[0] != 0) + (k[1] != 0) + (k[2] != 0) + (k[3] != 0);
      if (dirs >= min_dirs) {
        // The inverse-distance mean, the directions summed in the order 0..3 (as always).
        float acc = 0.0f, wsum = 0.0f;
        for (int d = 0; d < 4; ++d) {
          if (k[d] == 0) continue;
          const float w = inv_k[k[d]];
          acc += w * intensity[static_cast<std::size_t>(idx + k[d] * steps[d])];
          wsum += w;
        }
        const float v = acc / wsum;
        intensity[static_cast<std::size_t>(idx)] = v;
        coverage[static_cast<std::size_t>(idx)] = 2;
        if (u8 != nullptr) u8[static_cast<std::size_t>(idx)] = intensity_to_u8(v, u8_scale);
        ++filled;
      }
    }
  }
  return filled;
}

}  // namespace qnav::sonar
