#include "drivers/sidescan/jsf_parser.hpp"

#include <cmath>
#include <cstring>

#include "nav/core/byte_order.hpp"

namespace qnav::sidescan {

namespace {
std::size_t jsf_bytes_per_sample(std::int16_t data_format) noexcept {
  switch (data_format) {
    case 0: return 2;  // envelope
    case 1: return 4;  // analytic (I, Q)
    case 2: return 2;  // raw
    default: return 0;
  }
}
}  // namespace


Result<JsfMessageHeader> parse_jsf_message_header(Span<const std::uint8_t> b) noexcept {
  if (b.size() < kJsfHeaderBytes) return Status(StatusCode::kTruncated, "JSF message header truncated");
  const std::uint8_t* p = b.data();
  if (load_le_u16(p) != kJsfSync) return Status(StatusCode::kCorrupt, "JSF sync is not 0x1601");
  JsfMessageHeader h;
  h.protocol_version = p[2];
  h.session = p[3];
  h.message_type = load_le_u16(p + 4);
  h.command_type = p[6];
  h.subsystem = p[7];
  h.channel = p[8];
  h.sequence = p[9];
  h.body_bytes = load_le_i32(p + 12);
  if (h.body_bytes < 0 || h.body_bytes > kJsfMaxBodyBytes) return Status(StatusCode::kCorrupt, "JSF body size negative or above 16 MiB");
  return h;
}

Status parse_jsf_sonar_data(const JsfMessageHeader& h, Span<const std::uint8_t> b, JsfSonarData& o, Span<float> samples) noexcept {
  if (h.message_type != kJsfSonarDataType) return Status(StatusCode::kInvalidArgument, "not a JSF sonar data message");
  if (h.body_bytes < 0 || static_cast<std::size_t>(h.body_bytes) > b.size()) return Status(StatusCode::kTruncated, "JSF body shorter than its size field");
  if (static_cast<std::size_t>(h.body_bytes) < kJsfSonarHeaderBytes) return Status(StatusCode::kCorrupt, "JSF sonar body shorter than its 240-byte header");
  const std::uint8_t* p = b.data();
  o = JsfSonarData{};
  o.subsystem = h.subsystem;
  o.channel = h.channel;
  const std::int32_t t1970 = load_le_i32(p);
  o.ping_number = load_le_u32(p + 8);
  const std::uint16_t msbs = load_le_u16(p + 16);
  o.validity = load_le_u16(p + 30);
  o.data_format = load_le_i16(p + 34);
  o.coordinate_units = load_le_i16(p + 88);
  const std::int32_t lon = load_le_i32(p + 80), lat = load_le_i32(p + 84);
  o.samples = static_cast<std::uint32_t>(load_le_u16(p + 114)) | (static_cast<std::uint32_t>((msbs >> 8) & 0xF) << 16);
  o.sample_interval_ns = load_le_u32(p + 116);
  const std::int32_t alt_mm = load_le_i32(p + 144);
  o.sound_speed_mps = load_le_f32(p + 148);
  o.weighting_factor = load_le_i16(p + 168);
  // Heading in 1/100 degree, 0..35999: anything else is a damaged field, not a direction.
  const std::uint16_t heading_cdeg = load_le_u16(p + 172);
  o.heading_deg = heading_cdeg < 36000 ? static_cast<float>(heading_cdeg) * 0.01f : std::nanf("");
  o.pitch_deg = static_cast<float>(load_le_i16(p + 174)) * (180.0f / 32768.0f);
  o.roll_deg = static_cast<float>(load_le_i16(p + 176)) * (180.0f / 32768.0f);
  o.speed_knots = static_cast<float>(load_le_i16(p + 194)) * 0.1f;
  const std::uint32_t ms_today = load_le_u32(p + 200);
  if (t1970 > 0) o.stamp_ns = static_cast<std::uint64_t>(t1970) * 1000000000ull + static_cast<std::uint64_t>(ms_today % 1000u) * 1000000ull;
  if (!(std::isfinite(o.sound_speed_mps) && o.sound_speed_mps > 1000.0f && o.sound_speed_mps < 2000.0f)) o.sound_speed_mps = 1500.0f;
  o.altitude_m = (o.validity & (1u << 6)) ? static_cast<float>(alt_mm) * 0.001f : -1.0f;
  if (o.coordinate_units == 2) {
    o.y = lat / 600000.0;
    o.x = lon / 600000.0;
    o.position_valid = (o.validity & 1u) && std::fabs(o.y) <= 90.0 && std::fabs(o.x) <= 180.0 && !(lat == 0 && lon == 0);
  } else {
    const double s = o.coordinate_units == 3 ? 0.1 : 0.001;
    o.y = lat * s;
    o.x = lon * s;
    o.position_valid = (o.validity & 1u) != 0;
  }
  const std::size_t bps = jsf_bytes_per_sample(o.data_format);
  if (bps == 0) return Status(StatusCode::kUnsupported, "JSF sample format not envelope, analytic or raw");
  // The body is exactly the sonar header and its samples: a size field that disagrees is damaged.
  if (static_cast<std::size_t>(h.body_bytes) != kJsfSonarHeaderBytes + o.samples * bps)
    return Status(StatusCode::kCorrupt, "JSF body size disagrees with its sample count");
  if (o.samples > samples.size()) return Status(StatusCode::kCapacityExceeded, "JSF message has more samples than the buffer holds");
  if (o.samples < 8) return Status(StatusCode::kCorrupt, "JSF message with fewer than 8 samples");
  if (o.sample_interval_ns == 0 || o.sample_interval_ns > 100000000u) return Status(StatusCode::kCorrupt, "JSF sample interval zero or absurd");
  if (o.weighting_factor < -30 || o.weighting_factor > 30) return Status(StatusCode::kCorrupt, "JSF weighting factor outside [-30, 30]");
  const float scale = std::ldexp(1.0f, -o.weighting_factor);
  const std::uint8_t* s = p + kJsfSonarHeaderBytes;
  for (std::uint32_t i = 0; i < o.samples; ++i) {
    float v;
    if (o.data_format == 0) {
      v = static_cast<float>(load_le_u16(s + 2 * i));
    } else if (o.data_format == 1) {
      const float re = static_cast<float>(load_le_i16(s + 4 * i)), im = static_cast<float>(load_le_i16(s + 4 * i + 2));
      v = std::sqrt(re * re + im * im);
    } else {
      v = std::fabs(static_cast<float>(load_le_i16(s + 2 * i)));
    }
    samples[i] = v * scale;
  }
  o.slant_range_m = static_cast<float>(static_cast<double>(o.samples) * o.sample_interval_ns * 1e-9 *
                                       static_cast<double>(o.sound_speed_mps) * 0.5);
  return Status::ok();
}

Result<std::size_t> jsf_sonar_body_bytes(Span<const std::uint8_t> b) noexcept {
  if (b.size() < kJsfSonarHeaderBytes) return Status(StatusCode::kTruncated, "JSF sonar header truncated");
  const std::uint8_t* p = b.data();
  const std::uint16_t msbs = load_le_u16(p + 16);
  const std::size_t samples = static_cast<std::size_t>(load_le_u16(p + 114)) | (static_cast<std::size_t>((msbs >> 8) & 0xF) << 16);
  const std::size_t bps = jsf_bytes_per_sample(load_le_i16(p + 34));
  if (bps == 0) return Status(StatusCode::kUnsupported, "JSF sample format not envelope, analytic or raw");
  return kJsfSonarHeaderBytes + samples * bps;
}

std::size_t jsf_sonar_message_bytes(std::size_t n) noexcept { return kJsfHeaderBytes + kJsfSonarHeaderBytes + 2 * n; }

Result<std::size_t> encode_jsf_sonar_message(Span<std::uint8_t> out, const JsfWriteSonar& w) noexcept {
  const std::size_t n = w.samples.size();
  if (n == 0 || n > 0xFFFFF) return Status(StatusCode::kInvalidArgument, "JSF sample count 0 or above 20 bits");
  const std::size_t bytes = jsf_sonar_message_bytes(n);
  if (out.size() < bytes) return Status(StatusCode::kCapacityExceeded, "buffer too small for the JSF message");
  std::uint8_t* p = out.data();
  std::memset(p, 0, bytes);
  store_le_u16(p, kJsfSync);
  p[2] = 0x0D;
  store_le_u16(p + 4, kJsfSonarDataType);
  p[6] = 2;
  p[7] = w.subsystem;
  p[8] = w.channel;
  p[9] = static_cast<std::uint8_t>(w.ping_number);
  store_le_u32(p + 12, static_cast<std::uint32_t>(kJsfSonarHeaderBytes + 2 * n));
  std::uint8_t* b = p + kJsfHeaderBytes;
  const std::uint64_t s = w.stamp_ns / 1000000000ull;
  store_le_u32(b, static_cast<std::uint32_t>(s));
  store_le_u32(b + 8, w.ping_number);
  store_le_u16(b + 16, static_cast<std::uint16_t>(((n >> 16) & 0xF) << 8));
  store_le_u16(b + 28, 1);
  store_le_u16(b + 30, static_cast<std::uint16_t>(1u | (1u << 3) | (w.altitude_m > 0.0f ? (1u << 6) : 0u)));
  if (w.coordinate_units == 1) {
    if (!(std::fabs(w.x_m) < 2.1e6 && std::fabs(w.y_m) < 2.1e6)) return Status(StatusCode::kOutOfRange, "JSF mm coordinates beyond +-2100 km");
    store_le_u32(b + 80, static_cast<std::uint32_t>(static_cast<std::int32_t>(std::lround(w.x_m * 1000.0))));
    store_le_u32(b + 84, static_cast<std::uint32_t>(static_cast<std::int32_t>(std::lround(w.y_m * 1000.0))));
    store_le_u16(b + 88, 1);
  } else {
    store_le_u32(b + 80, static_cast<std::uint32_t>(static_cast<std::int32_t>(std::lround(w.lon_deg * 600000.0))));
    store_le_u32(b + 84, static_cast<std::uint32_t>(static_cast<std::int32_t>(std::lround(w.lat_deg * 600000.0))));
    store_le_u16(b + 88, 2);
  }
  store_le_u16(b + 114, static_cast<std::uint16_t>(n & 0xFFFF));
  store_le_u32(b + 116, w.sample_interval_ns);
  store_le_u32(b + 144, static_cast<std::uint32_t>(static_cast<std::int32_t>(std::lround(static_cast<double>(w.altitude_m) * 1000.0))));
  store_le_f32(b + 148, w.sound_speed_mps);
  store_le_u16(b + 168, static_cast<std::uint16_t>(w.weighting_factor));
  double hd = std::fmod(static_cast<double>(w.heading_deg), 360.0);
  if (hd < 0.0) hd += 360.0;
  store_le_u16(b + 172, static_cast<std::uint16_t>(std::lround(hd * 100.0) % 36000));
  store_le_u32(b + 200, static_cast<std::uint32_t>((w.stamp_ns / 1000000ull) % 86400000ull));
  const float scale = std::ldexp(1.0f, w.weighting_factor);
  for (std::size_t i = 0; i < n; ++i) {
    float v = std::isfinite(w.samples[i]) ? std::round(w.samples[i] * scale) : 0.0f;
    v = v < 0.0f ? 0.0f : (v > 65535.0f ? 65535.0f : v);
    store_le_u16(b + kJsfSonarHeaderBytes + 2 * i, static_cast<std::uint16_t>(v));
  }
  return bytes;
}

}  // namespace qnav::sidescan
