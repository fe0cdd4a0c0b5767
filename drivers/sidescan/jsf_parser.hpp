// EdgeTech JSF decoding (doc 0023492 Rev G): pure functions over byte spans, no I/O, no allocation,
// fuzz-ready. A JSF file or live stream is a sequence of messages: a 16-byte header (sync 0x1601,
// version, session, type, command, subsystem, channel, sequence, body size) and a body. Message 80
// (sonar data) = 240-byte header + samples of ONE channel of one ping (0 port, 1 starboard).
// Field layouts: ../shared/reference/sidescan-formats.md. Little-endian via nav/core/byte_order.hpp.
// Sample formats decoded: 0 envelope (u16), 1 analytic (i16 I,Q -> magnitude), 2 raw (i16 ->
// magnitude); others kUnsupported. Values are scaled by 2^-weighting_factor. Cost O(body bytes).
// Also: encode_jsf_sonar_message (writer for the simulator and the tests).
#pragma once

#include <cstddef>
#include <cstdint>

#include "nav/core/span.hpp"
#include "nav/core/status.hpp"

namespace qnav::sidescan {

constexpr std::uint16_t kJsfSync = 0x1601;
constexpr std::size_t kJsfHeaderBytes = 16;
constexpr std::size_t kJsfSonarHeaderBytes = 240;
constexpr std::uint16_t kJsfSonarDataType = 80;
constexpr std::int32_t kJsfMaxBodyBytes = 16 * 1024 * 1024;  // larger size fields are treated as corrupt

struct JsfMessageHeader {
  std::uint8_t protocol_version = 0;
  std::uint8_t session = 0;
  std::uint16_t message_type = 0;
  std::uint8_t command_type = 0;
  std::uint8_t subsystem = 0;   // 0 sub-bottom, 20/21/22 side-scan low/high/very high
  std::uint8_t channel = 0;     // 0 port, 1 starboard
  std::uint8_t sequence = 0;
  std::int32_t body_bytes = 0;
};

struct JsfSonarData {
  std::uint8_t subsystem = 0;
  std::uint8_t channel = 0;
  std::uint32_t ping_number = 0;
  std::uint64_t stamp_ns = 0;          // TimeSince1970 + ms of the second (from milliseconds today)
  std::uint32_t samples = 0;
  std::uint32_t sample_interval_ns = 0;
  std::int16_t data_format = 0;
  std::int16_t weighting_factor = 0;
  float sound_speed_mps = 0.0f;        // 1500 assumed when the field is 0 or absurd
  float slant_range_m = 0.0f;          // samples * interval * c / 2
  float altitude_m = 0.0f;             // < 0 when the validity flag is not set
  float heading_deg = 0.0f;
  float pitch_deg = 0.0f, roll_deg = 0.0f;
  float speed_knots = 0.0f;
  std::int16_t coordinate_units = 0;   // 1 mm, 2 lat/lon (arcmin x 10000), 3 dm
  double y = 0.0, x = 0.0;             // latitude/longitude degrees (units 2) or metres
  std::uint16_t validity = 0;
  bool position_valid = false;
};

Result<JsfMessageHeader> parse_jsf_message_header(Span<const std::uint8_t> bytes) noexcept;
// body = the message body (header.body_bytes long). samples receives data.samples magnitudes.
Status parse_jsf_sonar_data(const JsfMessageHeader& header, Span<const std::uint8_t> body, JsfSonarData& out,
                            Span<float> samples) noexcept;

struct JsfWriteSonar {
  std::uint8_t subsystem = 20;
  std::uint8_t channel = 0;
  std::uint32_t ping_number = 0;
  std::uint64_t stamp_ns = 0;
  std::uint32_t sample_interval_ns = 20000;
  float sound_speed_mps = 1500.0f;
  float altitude_m = 0.0f;
  float heading_deg = 0.0f;
  std::int16_t coordinate_units = 2;  // 2: lat_deg/lon_deg (arcmin x 10^4, ~0.19 m steps); 1: y_m/x_m in mm
  double lat_deg = 0.0, lon_deg = 0.0;
  double y_m = 0.0, x_m = 0.0;         // northing/easting for coordinate_units 1 (|v| < 2147 km)
  Span<const float> samples;           // stored as envelope u16 = clamp(round(v * 2^weighting)), near first
  std::int16_t weighting_factor = 0;
};
std::size_t jsf_sonar_message_bytes(std::size_t samples) noexcept;
// The body size a sonar data message (type 80) must have, from its 240-byte sonar header: the header
// plus samples x bytes per sample of its data format. kUnsupported for an unknown format.
Result<std::size_t> jsf_sonar_body_bytes(Span<const std::uint8_t> sonar_header) noexcept;
Result<std::size_t> encode_jsf_sonar_message(Span<std::uint8_t> out, const JsfWriteSonar& w) noexcept;

}  // namespace qnav::sidescan
