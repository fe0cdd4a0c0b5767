// Value types shared by the side-scan stages (nav/sonar) and the drivers that feed them.
//  - SonarPing: one raw ping, both sides, samples in SLANT range, index 0 = nearest sample
//    (drivers reverse channels stored far-range first). Samples are linear amplitude/intensity,
//    any positive scale. The ping does not own its samples (driver or simulator buffers).
//  - CorrectedScanline: the output of ScanlineCorrector: GROUND-range bins per side, index 0 = bin
//    nearest the track, bin i covers [i, i+1) * bin_m; valid[i] = 0 for bins without data (nadir gap,
//    beyond the last sample, shadowed-out nothing): such bins carry value 0 and must be ignored.
// Frames: the navigation frame is local metric North-East (x_m = north, y_m = east) and
// heading_rad is the compass heading (0 = north, +pi/2 = east). The starboard side points to
// heading + 90 deg. Pose2 from nav/core/geometry.hpp is used with exactly this meaning.
#pragma once

#include <cstdint>

#include "nav/core/geometry.hpp"
#include "nav/core/span.hpp"

namespace qnav::sonar {

struct SonarPing {
  std::uint64_t stamp_ns = 0;
  std::uint32_t ping_number = 0;
  Span<const float> port;         // slant-range samples, near first
  Span<const float> stbd;         // slant-range samples, near first
  float slant_range_m = 0.0f;     // range of the far edge of the last sample (sample i covers [i, i+1) * range/n)
  float altitude_m = -1.0f;       // altimeter value above the seabed; <= 0 or NaN = unknown (bottom detection)
};

struct CorrectedScanline {
  std::uint64_t stamp_ns = 0;
  std::uint32_t ping_number = 0;
  float bin_m = 0.0f;             // ground-range bin size
  float altitude_m = 0.0f;        // altitude used for the slant -> ground conversion
  bool altitude_detected = false; // true when it came from bottom detection, not the altimeter
  Span<const float> port;         // ground-range bins, near first, normalised intensity (about 1 = mean)
  Span<const float> stbd;
  Span<const std::uint8_t> port_valid;  // 1 = data, 0 = no data
  Span<const std::uint8_t> stbd_valid;
};

// Starboard unit vector (north, east) for a compass heading.
inline Vec2d starboard_unit(double heading_rad) noexcept { return Vec2d(-std::sin(heading_rad), std::cos(heading_rad)); }
// Forward unit vector (north, east) for a compass heading.
inline Vec2d forward_unit(double heading_rad) noexcept { return Vec2d(std::cos(heading_rad), std::sin(heading_rad)); }

}  // namespace qnav::sonar
