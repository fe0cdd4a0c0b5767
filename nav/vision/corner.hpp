// Corner: one interest point, as produced by HarrisDetector and consumed by stereo, descriptors and
// the matchers. Plain value type (trivially copyable, default-constructible) so it lives in
// FixedVector / BoundedVector storage carved from an Arena.
#pragma once

#include <cstdint>

namespace qnav::vision {

struct Corner {
  float x = 0.0f;         // column, pixels, sub-pixel when refinement is on (image of detection)
  float y = 0.0f;         // row, pixels
  float score = 0.0f;     // ordering score: neighbourhood-normalised Harris score (or raw, if off)
  float response = 0.0f;  // raw Harris response det(M) - k trace(M)^2 at the integer peak
  std::int16_t level = 0; // pyramid level the corner was detected on (0 = full resolution)
};

}  // namespace qnav::vision
