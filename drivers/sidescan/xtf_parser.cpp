#include "drivers/sidescan/xtf_parser.hpp"

#include <cmath>
#include <cstring>

#include "nav/core/byte_order.hpp"

namespace qnav::sidescan {

namespace {
template <std::size_t N>
void copy_text(char (&dst)[N], const std::uint8_t* src, std::size_t len) noexcept {
  std::size_t n = len < N - 1 ? len : N - 1;
  for (std::size_t i = 0; i < n; ++i) {
    const char c = static_cast<char>(src[i]);
    if (c == '\0') {
      n = i;
      break;
    }
    dst[i] = (c >= 32 && c < 127) ? c : '?';
  }
  dst[n] = '\0';
}

XtfChannelInfo parse_chaninfo(const std::uint8_t* p) noexcept {
  XtfChannelInfo c;
  c.type_of_channel = p[0];
  c.sub_channel = p[1];
  c.correction_flags = load_le_u16(p + 2);
  c.unipolar = load_le_u16(p + 4);
  c.bytes_per_sample = load_le_u16(p + 6);
  copy_text(c.name, p + 12, 16);
  c.volt_scale = load_le_f32(p + 28);
  c.frequency_khz = load_le_f32(p + 32);
  c.horiz_beam_angle_deg = load_le_f32(p + 36);
  c.tilt_angle_deg = load_le_f32(p + 40);
  c.beam_width_deg = load_le_f32(p + 44);
  c.sample_format = p[74];
  return c;
}

bool valid_date(int y, int mo, int d, int h, int mi, int s, int hs) noexcept {
  return y >= 1970 && y <= 2200 && mo >= 1 && mo <= 12 && d >= 1 && d <= 31 && h <= 23 && mi <= 59 && s <= 60 && hs <= 99;
}
}  // namespace

std::int64_t days_from_civil(int y, unsigned m, unsigned d) noexcept {
  // H. Hinnant's algorithm.
  y -= m <= 2 ? 1 : 0;
  const std::int64_t era = (y >= 0 ? y : y - 399) / 400;
  const unsigned yoe = static_cast<unsigned>(y - era * 400);
  const unsigned doy = (153 * (m > 2 ? m - 3 : m + 9) + 2) / 5 + d - 1;
  const unsigned doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return era * 146097 + static_cast<std::int64_t>(doe) - 719468;
}

Result<XtfFileHeader> parse_xtf_file_header(Span<const std::uint8_t> b) noexcept {
  if (b.size() < kXtfFileHeaderBytes) return Status(StatusCode::kTruncated, "XTF file header shorter than 1024 bytes");
  const std::uint8_t* p = b.data();
  if (p[0] != kXtfFileFormat) return Status(StatusCode::kCorrupt, "not an XTF file (FileFormat byte is not 123)");
  XtfFileHeader h;
  h.file_format = p[0];
  h.system_type = p[1];
  copy_text(h.recording_program, p + 2, 8);
  copy_text(h.recording_version, p + 10, 8);
  copy_text(h.sonar_name, p + 18, 16);
  h.sonar_type = load_le_u16(p + 34);
  copy_text(h.note, p + 36, 64);
  h.nav_units = load_le_u16(p + 164);
  h.num_sonar_channels = load_le_u16(p + 166);
  h.num_bathy_channels = load_le_u16(p + 168);
  const std::uint32_t total = static_cast<std::uint32_t>(h.num_sonar_channels) + h.num_bathy_channels + p[170] + p[171] +
                              load_le_u16(p + 172) + p[174];
  if (total > 1024) return Status(StatusCode::kCorrupt, "XTF header declares more than 1024 channels");
  // 6 CHANINFO in the first 1024 bytes; 8 more per extra 1024-byte block.
  const std::uint32_t extra = total > 6 ? (total - 6 + 7) / 8 : 0;
  h.header_bytes = static_cast<std::uint32_t>(kXtfFileHeaderBytes) * (1 + extra);
  if (b.size() < h.header_bytes) return Status(StatusCode::kTruncated, "XTF file header extension truncated");
  const std::uint32_t n = total < kXtfMaxChannels ? total : static_cast<std::uint32_t>(kXtfMaxChannels);
  for (std::uint32_t i = 0; i < n; ++i) {
    const std::size_t off = i < 6 ? 256 + 128 * i : 1024 + 128 * (i - 6);
    (void)h.channels.push_back(parse_chaninfo(p + off));
  }
  return h;
}

Result<XtfPacketHeader> parse_xtf_packet_header(Span<const std::uint8_t> b) noexcept {
  if (b.size() < kXtfPacketHeaderBytes) return Status(StatusCode::kTruncated, "XTF packet header truncated");
  const std::uint8_t* p = b.data();
  if (load_le_u16(p) != kXtfMagic) return Status(StatusCode::kCorrupt, "XTF packet magic is not 0xFACE");
  XtfPacketHeader h;
  h.header_type = p[2];
  h.sub_channel = p[3];
  h.num_chans_to_follow = load_le_u16(p + 4);
  h.num_bytes = load_le_u32(p + 10);
  if (h.num_bytes < kXtfPacketHeaderBytes) return Status(StatusCode::kCorrupt, "XTF packet length shorter than its header");
  return h;
}

Status parse_xtf_sonar_ping(Span<const std::uint8_t> b, const XtfFileHeader& fh, XtfPing& out, Span<float> port,
                            Span<float> stbd) noexcept {
  const Result<XtfPacketHeader> ph = parse_xtf_packet_header(b);
  if (!ph) return ph.status();
  if (ph->header_type != static_cast<std::uint8_t>(XtfPacketType::kSonar)) return Status(StatusCode::kInvalidArgument, "not a sonar packet");
  if (ph->num_bytes > b.size()) return Status(StatusCode::kTruncated, "XTF ping packet shorter than its length field");
  if (ph->num_bytes < kXtfPingHeaderBytes) return Status(StatusCode::kCorrupt, "XTF ping packet shorter than the ping header");
  const std::uint8_t* p = b.data();
  const std::size_t end = ph->num_bytes;
  XtfPing& o = out;
  o = XtfPing{};
  o.year = load_le_u16(p + 14);
  o.month = p[16];
  o.day = p[17];
  o.hour = p[18];
  o.minute = p[19];
  o.second = p[20];
  o.hundredths = p[21];
  o.julian_day = load_le_u16(p + 22);
  o.event_number = load_le_u32(p + 24);
  o.ping_number = load_le_u32(p + 28);
  o.sound_velocity_mps = load_le_f32(p + 32);
  o.ship_y = load_le_f64(p + 128);
  o.ship_x = load_le_f64(p + 136);
  o.sensor_speed_knots = load_le_f32(p + 152);
  o.sensor_y = load_le_f64(p + 160);
  o.sensor_x = load_le_f64(p + 168);
  o.sensor_depth_m = load_le_f32(p + 192);
  o.altitude_m = load_le_f32(p + 196);
  o.pitch_deg = load_le_f32(p + 204);
  o.roll_deg = load_le_f32(p + 208);
  o.heading_deg = load_le_f32(p + 212);
  if (valid_date(o.year, o.month, o.day, o.hour, o.minute, o.second, o.hundredths)) {
    const std::int64_t days = days_from_civil(o.year, o.month, o.day);
    const std::int64_t cs = ((days * 24 + o.hour) * 60 + o.minute) * 6000 + o.second * 100 + o.hundredths;
    o.stamp_ns = static_cast<std::uint64_t>(cs) * 10000000ull;
  }
  // NavUnits: 0 projected metres, 3 lat/lon degrees; any other value says the position cannot be read.
  // Projected coordinates beyond 20,000 km (UTM northings stop at 10,000 km) are damaged fields.
  const bool finite = std::isfinite(o.sensor_y) && std::isfinite(o.sensor_x) && std::isfinite(o.heading_deg);
  if (fh.nav_units == 3)
    o.nav_valid = finite && std::fabs(o.sensor_y) <= 90.0 && std::fabs(o.sensor_x) <= 180.0 && !(o.sensor_y == 0.0 && o.sensor_x == 0.0);
  else if (fh.nav_units == 0)
    o.nav_valid = finite && std::fabs(o.sensor_y) <= kXtfMaxProjectedM && std::fabs(o.sensor_x) <= kXtfMaxProjectedM &&
                  !(o.sensor_y == 0.0 && o.sensor_x == 0.0);
  else
    o.nav_valid = false;

  // Channels.
  std::size_t off = kXtfPingHeaderBytes;
  std::uint32_t n_port = 0, n_stbd = 0;
  bool have_port = false, have_stbd = false;
  const std::uint16_t nch = ph->num_chans_to_follow;
  if (nch > 64) return Status(StatusCode::kCorrupt, "XTF ping declares more than 64 channels");
  for (std::uint16_t c = 0; c < nch; ++c) {
    if (end - off < kXtfPingChanHeaderBytes) return Status(StatusCode::kTruncated, "XTF ping channel header truncated");
    const std::uint8_t* q = p + off;
    XtfPingChannel ch;
    ch.channel_number = load_le_u16(q);
    ch.downsample_method = load_le_u16(q + 2);
    ch.slant_range_m = load_le_f32(q + 4);
    ch.ground_range_m = load_le_f32(q + 8);
    ch.time_delay_s = load_le_f32(q + 12);
    ch.time_duration_s = load_le_f32(q + 16);
    ch.seconds_per_ping = load_le_f32(q + 20);
    ch.processing_flags = load_le_u16(q + 24);
    ch.frequency = load_le_u16(q + 26);
    ch.num_samples = load_le_u32(q + 42);
    ch.weight = load_le_i16(q + 58);
    off += kXtfPingChanHeaderBytes;
    // Sample layout from the file header's channel info (by channel number), else 2 bytes unsigned.
    std::uint16_t bps = 2;
    std::uint8_t type = ch.channel_number == 0 ? 1 : (ch.channel_number == 1 ? 2 : 0);
    std::uint16_t unipolar = 1;
    std::uint8_t fmt = 0;
    if (ch.channel_number < fh.channels.size()) {
      const XtfChannelInfo& ci = fh.channels[ch.channel_number];
      bps = ci.bytes_per_sample;
      type = ci.type_of_channel;
      unipolar = ci.unipolar;
      fmt = ci.sample_format;
    }
    if (bps != 1 && bps != 2 && bps != 4) return Status(StatusCode::kUnsupported, "XTF bytes per sample is not 1, 2 or 4");
    if (ch.num_samples > (end - off) / bps) return Status(StatusCode::kTruncated, "XTF channel samples run past the packet");
    (void)o.channels.push_back(ch);
    const bool is_port = type == 1 && !have_port;
    const bool is_stbd = type == 2 && !have_stbd;
    if (is_port || is_stbd) {
      Span<float> dst = is_port ? port : stbd;
      if (ch.num_samples > dst.size()) return Status(StatusCode::kCapacityExceeded, "XTF ping has more samples than the buffer holds");
      if (!(std::isfinite(ch.slant_range_m) && ch.slant_range_m > 0.0f && ch.slant_range_m < 100000.0f))
        return Status(StatusCode::kCorrupt, "XTF channel slant range not finite or <= 0");
      const std::uint8_t* s = p + off;
      const std::uint32_t n = ch.num_samples;
      for (std::uint32_t i = 0; i < n; ++i) {
        float v;
        if (bps == 1) {
          v = unipolar ? static_cast<float>(s[i]) : static_cast<float>(static_cast<std::int8_t>(s[i]));
        } else if (bps == 2) {
          v = unipolar ? static_cast<float>(load_le_u16(s + 2 * i)) : static_cast<float>(load_le_i16(s + 2 * i));
        } else if (fmt == 5) {
          v = load_le_f32(s + 4 * i);
          if (!std::isfinite(v)) v = 0.0f;
        } else {
          v = unipolar ? static_cast<float>(load_le_u32(s + 4 * i)) : static_cast<float>(load_le_i32(s + 4 * i));
        }
        if (v < 0.0f) v = -v;  // bipolar samples: magnitude
        // Port is stored far range first: reverse so index 0 is the nearest sample.
        if (is_port)
          dst[n - 1 - i] = v;
        else
          dst[i] = v;
      }
      if (is_port) {
        have_port = true;
        n_port = n;
      } else {
        have_stbd = true;
        n_stbd = n;
      }
      o.slant_range_m = ch.slant_range_m;
    }
    off += static_cast<std::size_t>(ch.num_samples) * bps;
  }
  if (!have_port || !have_stbd) return Status(StatusCode::kUnsupported, "XTF ping without a port and a starboard channel");
  if (n_port != n_stbd) return Status(StatusCode::kUnsupported, "XTF port and starboard sample counts differ");
  if (n_port < 8) return Status(StatusCode::kCorrupt, "XTF ping with fewer than 8 samples per side");
  o.samples_per_side = n_port;
  return Status::ok();
}

Result<XtfAttitude> parse_xtf_attitude(Span<const std::uint8_t> b) noexcept {
  const Result<XtfPacketHeader> ph = parse_xtf_packet_header(b);
  if (!ph) return ph.status();
  if (ph->header_type != static_cast<std::uint8_t>(XtfPacketType::kAttitude)) return Status(StatusCode::kInvalidArgument, "not an attitude packet");
  if (b.size() < 64 || ph->num_bytes < 54) return Status(StatusCode::kTruncated, "XTF attitude packet truncated");
  const std::uint8_t* p = b.data();
  XtfAttitude a;
  a.pitch_deg = load_le_f32(p + 30);
  a.roll_deg = load_le_f32(p + 34);
  a.heave_m = load_le_f32(p + 38);
  a.yaw_deg = load_le_f32(p + 42);
  a.time_tag_ms = load_le_u32(p + 46);
  a.heading_deg = load_le_f32(p + 50);
  if (!std::isfinite(a.pitch_deg) || !std::isfinite(a.roll_deg) || !std::isfinite(a.heading_deg))
    return Status(StatusCode::kCorrupt, "XTF attitude not finite");
  return a;
}

Result<XtfNavigation> parse_xtf_navigation(Span<const std::uint8_t> b) noexcept {
  const Result<XtfPacketHeader> ph = parse_xtf_packet_header(b);
  if (!ph) return ph.status();
  if (ph->header_type != static_cast<std::uint8_t>(XtfPacketType::kNavigation)) return Status(StatusCode::kInvalidArgument, "not a navigation packet");
  if (b.size() < 64 || ph->num_bytes < 57) return Status(StatusCode::kTruncated, "XTF navigation packet truncated");
  const std::uint8_t* p = b.data();
  XtfNavigation n;
  n.time_tag_ms = load_le_u32(p + 29);
  n.raw_y = load_le_f64(p + 33);
  n.raw_x = load_le_f64(p + 41);
  n.raw_altitude_m = load_le_f32(p + 49);
  if (!std::isfinite(n.raw_y) || !std::isfinite(n.raw_x)) return Status(StatusCode::kCorrupt, "XTF navigation not finite");
  return n;
}

}  // namespace qnav::sidescan
