// XTF (Triton eXtended Triton Format, Rev. 41) decoding: pure functions over byte spans, no I/O,
// no allocation, fuzz-ready (test/fuzz/sidescan). Field layouts: ../shared/reference/sidescan-formats.md.
// All multi-byte fields go through nav/core/byte_order.hpp (XTF is little-endian; correct on SPARC).
//  - parse_xtf_file_header: XTFFILEHEADER (1024 B, +1024 B per 8 channels beyond 6) + CHANINFO.
//  - parse_xtf_packet_header: the 14-byte common packet start (magic 0xFACE, type, length).
//  - parse_xtf_sonar_ping: a HeaderType-0 packet: XTFPINGHEADER + per-channel XTFPINGCHANHEADER +
//    8/16/32-bit samples, decoded into caller float buffers as port/starboard, NEAR RANGE FIRST
//    (the port channel is stored far range first and is reversed here).
//  - parse_xtf_attitude / parse_xtf_navigation: packet types 3 and 42.
// Every length field is checked against the bytes actually present before it is used; a bad
// field returns kCorrupt/kTruncated/kUnsupported with a message, never reads out of bounds.
// Cost: O(packet bytes).
#pragma once

#include <cstddef>
#include <cstdint>

#include "nav/core/fixed_vector.hpp"
#include "nav/core/span.hpp"
#include "nav/core/status.hpp"

namespace qnav::sidescan {

constexpr std::size_t kXtfFileHeaderBytes = 1024;
constexpr std::size_t kXtfPacketHeaderBytes = 14;
constexpr std::size_t kXtfPingHeaderBytes = 256;
constexpr std::size_t kXtfPingChanHeaderBytes = 64;
constexpr std::size_t kXtfMaxChannels = 16;       // channel infos decoded from the file header
constexpr std::size_t kXtfMaxPingChannels = 8;    // channels decoded per ping packet
constexpr std::uint16_t kXtfMagic = 0xFACE;
constexpr std::uint8_t kXtfFileFormat = 123;
constexpr double kXtfMaxProjectedM = 2.0e7;        // |northing|, |easting| beyond: a damaged field

enum class XtfPacketType : std::uint8_t {
  kSonar = 0,
  kBathy = 2,
  kAttitude = 3,
  kNavigation = 42,
  kGyro = 84,
  kRawPosition = 107,
};

struct XtfChannelInfo {
  std::uint8_t type_of_channel = 0;  // 0 subbottom, 1 port, 2 stbd, 3 bathy
  std::uint8_t sub_channel = 0;
  std::uint16_t correction_flags = 0;  // 1 slant range, 2 ground range
  std::uint16_t unipolar = 0;
  std::uint16_t bytes_per_sample = 0;
  char name[17] = {};
  float volt_scale = 0.0f;
  float frequency_khz = 0.0f;
  float horiz_beam_angle_deg = 0.0f;
  float tilt_angle_deg = 0.0f;
  float beam_width_deg = 0.0f;
  std::uint8_t sample_format = 0;
};

struct XtfFileHeader {
  std::uint8_t file_format = 0;
  std::uint8_t system_type = 0;
  char recording_program[9] = {};
  char recording_version[9] = {};
  char sonar_name[17] = {};
  std::uint16_t sonar_type = 0;
  char note[65] = {};
  std::uint16_t nav_units = 0;  // 0 metres (projected), 3 lat/lon degrees
  std::uint16_t num_sonar_channels = 0;
  std::uint16_t num_bathy_channels = 0;
  std::uint32_t header_bytes = 0;  // bytes before the first packet
  FixedVector<XtfChannelInfo, kXtfMaxChannels> channels;
};

struct XtfPacketHeader {
  std::uint8_t header_type = 0;
  std::uint8_t sub_channel = 0;
  std::uint16_t num_chans_to_follow = 0;
  std::uint32_t num_bytes = 0;  // whole packet including this header and padding
};

struct XtfPingChannel {
  std::uint16_t channel_number = 0;
  std::uint16_t downsample_method = 0;
  float slant_range_m = 0.0f;
  float ground_range_m = 0.0f;
  float time_delay_s = 0.0f;
  float time_duration_s = 0.0f;
  float seconds_per_ping = 0.0f;
  std::uint16_t processing_flags = 0;
  std::uint16_t frequency = 0;
  std::uint32_t num_samples = 0;
  std::int16_t weight = 0;
};

struct XtfPing {
  std::uint16_t year = 0;
  std::uint8_t month = 0, day = 0, hour = 0, minute = 0, second = 0, hundredths = 0;
  std::uint16_t julian_day = 0;
  std::uint32_t event_number = 0;
  std::uint32_t ping_number = 0;
  float sound_velocity_mps = 0.0f;
  double ship_y = 0.0, ship_x = 0.0;
  double sensor_y = 0.0;   // latitude (deg) or northing (m), per the file's nav_units
  double sensor_x = 0.0;   // longitude (deg) or easting (m)
  float sensor_speed_knots = 0.0f;
  float sensor_depth_m = 0.0f;
  float altitude_m = 0.0f;
  float pitch_deg = 0.0f;
  float roll_deg = 0.0f;
  float heading_deg = 0.0f;
  std::uint64_t stamp_ns = 0;  // UTC from the ping's date/time (ns since 1970), 0 when the date is invalid
  bool nav_valid = false;      // known nav units, finite, in range, and not the (0, 0) placeholder
  float slant_range_m = 0.0f;  // of the port/stbd channels
  std::uint32_t samples_per_side = 0;  // samples written to each side's buffer
  FixedVector<XtfPingChannel, kXtfMaxPingChannels> channels;
};

struct XtfAttitude {
  float pitch_deg = 0.0f, roll_deg = 0.0f, heave_m = 0.0f, yaw_deg = 0.0f, heading_deg = 0.0f;
  std::uint32_t time_tag_ms = 0;
};

struct XtfNavigation {
  std::uint32_t time_tag_ms = 0;
  double raw_y = 0.0, raw_x = 0.0;
  float raw_altitude_m = 0.0f;
};

Result<XtfFileHeader> parse_xtf_file_header(Span<const std::uint8_t> bytes) noexcept;
Result<XtfPacketHeader> parse_xtf_packet_header(Span<const std::uint8_t> bytes) noexcept;
// packet = the whole packet (num_bytes long). port/stbd receive samples_per_side samples each;
// a ping with more samples per side than the buffers hold is rejected (kCapacityExceeded).
Status parse_xtf_sonar_ping(Span<const std::uint8_t> packet, const XtfFileHeader& header, XtfPing& out,
                            Span<float> port, Span<float> stbd) noexcept;
Result<XtfAttitude> parse_xtf_attitude(Span<const std::uint8_t> packet) noexcept;
Result<XtfNavigation> parse_xtf_navigation(Span<const std::uint8_t> packet) noexcept;

// Days since 1970-01-01 for a proleptic Gregorian date (for stamps); negative before 1970.
std::int64_t days_from_civil(int year, unsigned month, unsigned day) noexcept;

}  // namespace qnav::sidescan
