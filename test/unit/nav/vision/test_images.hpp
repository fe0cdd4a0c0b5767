// Synthetic test images for the vision tests (deterministic, no files).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "nav/core/image.hpp"

namespace qnav::vision::testing {

// Small deterministic PRNG (xorshift64*), same sequence on every platform.
struct Rng {
  std::uint64_t s;
  explicit Rng(std::uint64_t seed) : s(seed ? seed : 0x9E3779B97F4A7C15ull) {}
  std::uint64_t next() {
    s ^= s >> 12;
    s ^= s << 25;
    s ^= s >> 27;
    return s * 2685821657736338717ull;
  }
  double uniform() { return static_cast<double>(next() >> 11) * (1.0 / 9007199254740992.0); }
};

// Filled rectangles on a uniform background: every rectangle corner is a true corner.
inline void draw_rect(ImageViewU8 img, int x0, int y0, int x1, int y1, std::uint8_t v) {
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x)
      if (img.contains(x, y)) img(x, y) = v;
}

inline void fill(ImageViewU8 img, std::uint8_t v) {
  for (int y = 0; y < img.height(); ++y)
    for (int x = 0; x < img.width(); ++x) img(x, y) = v;
}

// Smooth random texture (sum of a few random sinusoids plus blobs), values in 20..235; good for
// correlation tests (unique matches everywhere).
inline void texture(ImageViewU8 img, std::uint64_t seed) {
  Rng rng(seed);
  double fx[6], fy[6], ph[6];
  for (int i = 0; i < 6; ++i) {
    fx[i] = 0.05 + 0.4 * rng.uniform();
    fy[i] = 0.05 + 0.4 * rng.uniform();
    ph[i] = 6.28 * rng.uniform();
  }
  for (int y = 0; y < img.height(); ++y)
    for (int x = 0; x < img.width(); ++x) {
      double v = 0;
      for (int i = 0; i < 6; ++i) v += std::sin(fx[i] * x + ph[i]) * std::cos(fy[i] * y + 0.7 * ph[i]);
      v = 128.0 + 17.0 * v + 20.0 * (rng.uniform() - 0.5);
      if (v < 20) v = 20;
      if (v > 235) v = 235;
      img(x, y) = static_cast<std::uint8_t>(v);
    }
}

// dst(p) = src(A^-1 (p - c) + c): rotation by angle_rad and scaling about the image centre c,
// bilinear, plus Gaussian noise of sigma grey levels (fixed seed). Outside the source: 0.
// The forward map of a source point q is p = c + scale * Rot(angle) (q - c).
inline void warp_similarity(ImageView<const std::uint8_t> src, double angle_rad, double scale, double noise, ImageViewU8 dst) {
  const double cx = 0.5 * (src.width() - 1), cy = 0.5 * (src.height() - 1);
  const double c = std::cos(angle_rad) / scale, s = std::sin(angle_rad) / scale;
  Rng rng(77);
  for (int y = 0; y < dst.height(); ++y)
    for (int x = 0; x < dst.width(); ++x) {
      const double dx = x - cx, dy = y - cy;
      const double sx = c * dx + s * dy + cx, sy = -s * dx + c * dy + cy;
      double v = 0;
      if (sx >= 0 && sy >= 0 && sx < src.width() - 1 && sy < src.height() - 1) {
        const int x0 = static_cast<int>(sx), y0 = static_cast<int>(sy);
        const double fx = sx - x0, fy = sy - y0;
        v = (1 - fy) * ((1 - fx) * src(x0, y0) + fx * src(x0 + 1, y0)) + fy * ((1 - fx) * src(x0, y0 + 1) + fx * src(x0 + 1, y0 + 1));
      }
      if (noise > 0) {
        const double u1 = std::max(rng.uniform(), 1e-12), u2 = rng.uniform();
        v += noise * std::sqrt(-2 * std::log(u1)) * std::cos(6.283185307179586 * u2);
      }
      dst(x, y) = static_cast<std::uint8_t>(std::lround(std::min(255.0, std::max(0.0, v))));
    }
}

inline void warp_point(int w, int h, double angle_rad, double scale, double qx, double qy, double& px, double& py) {
  const double cx = 0.5 * (w - 1), cy = 0.5 * (h - 1);
  const double c = std::cos(angle_rad) * scale, s = std::sin(angle_rad) * scale;
  px = c * (qx - cx) - s * (qy - cy) + cx;
  py = s * (qx - cx) + c * (qy - cy) + cy;
}

inline void warp_point(int w, int h, double angle_rad, double scale, float qx, float qy, double& px, double& py) {
  warp_point(w, h, angle_rad, scale, static_cast<double>(qx), static_cast<double>(qy), px, py);
}

}  // namespace qnav::vision::testing
