// Underwater degradation filters (underwater paper, Table 1, after Arredondo & Lebart 2005) as a
// deterministic, seeded image transform for robustness tests. Same seed + same input = bit-identical
// output on every platform: own integer PRNG (xorshift64*), Gaussian noise as the Irwin-Hall sum of
// 12 uniforms (integer sum, no libm), and only IEEE-exact double operations (+ - * / sqrt).
//
// Model applied per pixel, in this order:
//  1. non-uniform lighting from a point light at light_distance_m in front of the image centre over a
//     scene spanning scene_width_m: gain = (d0 / d)^2 with d = sqrt(d0^2 + r^2), r the pixel's
//     distance from the centre in metres on the scene plane (inverse-square fall-off);
//  2. attenuation (turbidity): the signal is multiplied by (1 - attenuation) and blended towards the
//     mean back-scatter level: out = (1 - a) * in + a * backscatter_grey;
//  3. additive Gaussian noise of sigma noise_sigma grey levels;
//  4. minimum grey level: values are mapped from [0, 255] to [min_grey, 255] (lifted blacks of a
//     scattering medium);
//  5. marine snow: snow_flakes bright blobs (radius 1..3 px, grey 200..255) at random positions.
// Cost O(W*H + flakes * 49), no allocation.
#pragma once

#include <cstdint>

#include "nav/core/image.hpp"
#include "nav/core/status.hpp"

namespace qnav::vision {

struct UnderwaterDegradation {
  double light_distance_m = 0.25;  // Table 1: 0.2 .. 0.3
  double scene_width_m = 0.5;      // scene width covered by the image at the light's distance
  double attenuation = 0.05;       // Table 1: 0.05 .. 0.06 (fraction)
  double backscatter_grey = 90.0;
  double noise_sigma = 2.0;        // Table 1: 2 .. 4
  int min_grey = 20;               // Table 1: 20 .. 30
  int snow_flakes = 30;            // Table 1: 30
  std::uint64_t seed = 1;
};

// The five filters of Table 1 (index 1..5); returns defaults for other indices.
UnderwaterDegradation table1_filter(int index) noexcept;

// src and dst must have the same size (may be the same view: in-place is fine).
// Errors: kInvalidArgument (empty/mismatched image, NaN or out-of-range parameter).
Status degrade_underwater(ConstImageViewU8 src, const UnderwaterDegradation& p, ImageViewU8 dst) noexcept;

}  // namespace qnav::vision
