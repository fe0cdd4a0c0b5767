// XTF encoding of side-scan data (the subset qnav reads back): a 1024-byte file header with two
// channels (port, starboard; 16-bit unsigned samples) and type-0 ping packets padded to 64 bytes.
// Used by the simulator tool (qnav sonar simulate) and by the reader tests; pure, no allocation.
#pragma once

#include <cstddef>
#include <cstdint>

#include "nav/core/span.hpp"
#include "nav/core/status.hpp"

namespace qnav::sidescan {

struct XtfWritePing {
  std::uint64_t stamp_ns = 0;   // UTC ns since 1970
  std::uint32_t ping_number = 0;
  double sensor_y = 0.0;        // latitude deg (nav_units 3) or northing m (nav_units 0)
  double sensor_x = 0.0;
  float heading_deg = 0.0f;
  float speed_knots = 0.0f;
  float altitude_m = 0.0f;
  float depth_m = 0.0f;
  float pitch_deg = 0.0f, roll_deg = 0.0f;
  float slant_range_m = 0.0f;
  float sound_velocity_mps = 750.0f;  // XTF convention: one-way
  Span<const float> port;       // near range first (written far range first, as real files store it)
  Span<const float> stbd;
  float sample_scale = 1.0f;    // stored = clamp(round(value * scale), 0, 65535)
};

// Writes the 1024-byte header into out (>= 1024 bytes). nav_units: 0 metres, 3 lat/lon degrees.
Status encode_xtf_file_header(Span<std::uint8_t> out, std::uint16_t nav_units, const char* sonar_name) noexcept;
// Bytes encode_xtf_ping needs for n samples per side.
std::size_t xtf_ping_bytes(std::size_t samples_per_side) noexcept;
// Writes one ping packet; returns its size in bytes.
Result<std::size_t> encode_xtf_ping(Span<std::uint8_t> out, const XtfWritePing& ping) noexcept;

}  // namespace qnav::sidescan
