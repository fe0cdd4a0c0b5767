// Synthetic test images for the vision tests (deterministic, no files).
#pragma once

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

}  // namespace qnav::vision::testing
