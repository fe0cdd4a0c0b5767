#include "drivers/sidescan/xtf_writer.hpp"

#include <cmath>
#include <cstring>

#include "drivers/sidescan/xtf_parser.hpp"
#include "nav/core/byte_order.hpp"

namespace qnav::sidescan {

namespace {
void put_text(std::uint8_t* p, const char* s, std::size_t n) noexcept {
  for (std::size_t i = 0; i < n && s != nullptr && s[i] != '\0'; ++i) p[i] = static_cast<std::uint8_t>(s[i]);
}
void civil_from_days(std::int64_t z, int& y, unsigned& m, unsigned& d) noexcept {
  z += 719468;
  const std::int64_t era = (z >= 0 ? z : z - 146096) / 146097;
  const unsigned doe = static_cast<unsigned>(z - era * 146097);
  const unsigned yoe = (doe - doe / 1460 + doe / 36524 - doe / 146096) / 365;
  const unsigned doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
  const unsigned mp = (5 * doy + 2) / 153;
  d = doy - (153 * mp + 2) / 5 + 1;
  m = mp < 10 ? mp + 3 : mp - 9;
  y = static_cast<int>(static_cast<std::int64_t>(yoe) + era * 400 + (m <= 2 ? 1 : 0));
}
}  // namespace

Status encode_xtf_file_header(Span<std::uint8_t> out, std::uint16_t nav_units, const char* sonar_name) noexcept {
  if (out.size() < kXtfFileHeaderBytes) return Status(StatusCode::kCapacityExceeded, "XTF header needs 1024 bytes");
  std::uint8_t* p = out.data();
  std::memset(p, 0, kXtfFileHeaderBytes);
  p[0] = kXtfFileFormat;
  p[1] = 1;
  put_text(p + 2, "QNAV", 8);
  put_text(p + 10, "223", 8);
  put_text(p + 18, sonar_name, 16);
  put_text(p + 36, "written by qnav (drivers/sidescan/xtf_writer)", 64);
  store_le_u16(p + 164, nav_units);
  store_le_u16(p + 166, 2);
  for (int c = 0; c < 2; ++c) {
    std::uint8_t* ci = p + 256 + 128 * c;
    ci[0] = static_cast<std::uint8_t>(c == 0 ? 1 : 2);
    ci[1] = static_cast<std::uint8_t>(c);
    store_le_u16(ci + 2, 1);
    store_le_u16(ci + 4, 1);
    store_le_u16(ci + 6, 2);
    put_text(ci + 12, c == 0 ? "PORT" : "STARBOARD", 16);
    store_le_f32(ci + 28, 5.0f);
    ci[74] = 0;
  }
  return Status::ok();
}

std::size_t xtf_ping_bytes(std::size_t n) noexcept {
  const std::size_t raw = kXtfPingHeaderBytes + 2 * (kXtfPingChanHeaderBytes + 2 * n);
  return (raw + 63) / 64 * 64;
}

Result<std::size_t> encode_xtf_ping(Span<std::uint8_t> out, const XtfWritePing& w) noexcept {
  const std::size_t n = w.port.size();
  if (n == 0 || n != w.stbd.size() || n > 1000000) return Status(StatusCode::kInvalidArgument, "port/stbd sample counts differ or are zero");
  const std::size_t bytes = xtf_ping_bytes(n);
  if (out.size() < bytes) return Status(StatusCode::kCapacityExceeded, "buffer too small for the XTF ping");
  std::uint8_t* p = out.data();
  std::memset(p, 0, bytes);
  store_le_u16(p, kXtfMagic);
  p[2] = 0;
  store_le_u16(p + 4, 2);
  store_le_u32(p + 10, static_cast<std::uint32_t>(bytes));
  const std::int64_t cs = static_cast<std::int64_t>(w.stamp_ns / 10000000ull);
  const std::int64_t days = cs / 8640000;
  std::int64_t rem = cs % 8640000;
  int y;
  unsigned mo, d;
  civil_from_days(days, y, mo, d);
  store_le_u16(p + 14, static_cast<std::uint16_t>(y));
  p[16] = static_cast<std::uint8_t>(mo);
  p[17] = static_cast<std::uint8_t>(d);
  p[18] = static_cast<std::uint8_t>(rem / 360000);
  rem %= 360000;
  p[19] = static_cast<std::uint8_t>(rem / 6000);
  rem %= 6000;
  p[20] = static_cast<std::uint8_t>(rem / 100);
  p[21] = static_cast<std::uint8_t>(rem % 100);
  store_le_u32(p + 28, w.ping_number);
  store_le_f32(p + 32, w.sound_velocity_mps);
  store_le_f64(p + 128, w.sensor_y);
  store_le_f64(p + 136, w.sensor_x);
  store_le_f32(p + 152, w.speed_knots);
  store_le_f64(p + 160, w.sensor_y);
  store_le_f64(p + 168, w.sensor_x);
  store_le_f32(p + 192, w.depth_m);
  store_le_f32(p + 196, w.altitude_m);
  store_le_f32(p + 204, w.pitch_deg);
  store_le_f32(p + 208, w.roll_deg);
  store_le_f32(p + 212, w.heading_deg);
  std::size_t off = kXtfPingHeaderBytes;
  for (int c = 0; c < 2; ++c) {
    std::uint8_t* q = p + off;
    store_le_u16(q, static_cast<std::uint16_t>(c));
    store_le_f32(q + 4, w.slant_range_m);
    store_le_f32(q + 16, 2.0f * w.slant_range_m / (2.0f * w.sound_velocity_mps));
    store_le_u32(q + 42, static_cast<std::uint32_t>(n));
    off += kXtfPingChanHeaderBytes;
    const Span<const float> src = c == 0 ? w.port : w.stbd;
    for (std::size_t i = 0; i < n; ++i) {
      const float v = c == 0 ? src[n - 1 - i] : src[i];  // port far range first
      float s = std::isfinite(v) ? std::round(v * w.sample_scale) : 0.0f;
      s = s < 0.0f ? 0.0f : (s > 65535.0f ? 65535.0f : s);
      store_le_u16(p + off + 2 * i, static_cast<std::uint16_t>(s));
    }
    off += 2 * n;
  }
  return bytes;
}

}  // namespace qnav::sidescan
