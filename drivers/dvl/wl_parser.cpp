#include "drivers/dvl/wl_parser.hpp"

#include <cmath>
#include <cstdio>
#include <cstring>

#include "drivers/dvl/text_fields.hpp"

namespace qnav::drivers::dvl {

std::uint8_t crc8_07(const std::uint8_t* data, std::size_t n) noexcept {
  std::uint8_t c = 0;
  for (std::size_t i = 0; i < n; ++i) {
    c = static_cast<std::uint8_t>(c ^ data[i]);
    for (int k = 0; k < 8; ++k) c = static_cast<std::uint8_t>((c & 0x80u) ? ((c << 1) ^ 0x07u) : (c << 1));
  }
  return c;
}

namespace {
int hexval(char c) noexcept {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}
}  // namespace

std::size_t wl_velocity_report(double vx_mps, double vy_mps, double vz_mps, double altitude_m, long long tov_us, long long tot_us, char* out,
                               std::size_t cap) noexcept {
  char body[224];
  const int n = std::snprintf(body, sizeof body, "wrz,%.4f,%.4f,%.3f,y,%.2f,0.002,1e-05;0;0;0;1e-05;0;0;0;1e-05,%lld,%lld,125.00,0", vx_mps, vy_mps,
                              vz_mps, altitude_m, tov_us, tot_us);
  if (n < 0 || static_cast<std::size_t>(n) >= sizeof body) return 0;
  return wl_with_checksum(body, out, cap);
}

std::size_t wl_with_checksum(const char* body, char* out, std::size_t cap) noexcept {
  static constexpr char kHex[] = "0123456789abcdef";
  const std::size_t n = std::strlen(body);
  if (n + 5 > cap) return 0;
  std::memcpy(out, body, n);
  const std::uint8_t c = crc8_07(reinterpret_cast<const std::uint8_t*>(body), n);
  out[n] = '*';
  out[n + 1] = kHex[c >> 4];
  out[n + 2] = kHex[c & 0xF];
  out[n + 3] = '\n';
  out[n + 4] = '\0';
  return n + 4;
}

Status WlParser::parse_line(const char* line, std::size_t n, std::int64_t arrival_ns, WlMessage& out) noexcept {
  if (line == nullptr) return Status(StatusCode::kInvalidArgument, "null line");
  while (n > 0 && (line[n - 1] == '\n' || line[n - 1] == '\r')) --n;
  if (n > kMaxWlLine) return reject(DvlCounter::kLength, StatusCode::kTruncated, "line longer than the protocol allows");
  if (n < 6 || line[n - 3] != '*') return reject(DvlCounter::kChecksum, StatusCode::kCorrupt, "no *xx checksum");
  const int hi = hexval(line[n - 2]);
  const int lo = hexval(line[n - 1]);
  if (hi < 0 || lo < 0) return reject(DvlCounter::kChecksum, StatusCode::kCorrupt, "bad checksum digits");
  const std::size_t body = n - 3;
  if (crc8_07(reinterpret_cast<const std::uint8_t*>(line), body) != static_cast<std::uint8_t>((hi << 4) | lo))
    return reject(DvlCounter::kChecksum, StatusCode::kCorrupt, "checksum mismatch");
  if (line[0] != 'w' || line[1] != 'r') return reject(DvlCounter::kFormat, StatusCode::kCorrupt, "not a wr* sentence");
  out = WlMessage{};
  out.type = line[2];
  Field f[16];
  const std::size_t nf = split_fields(line, body, ',', f, 16);
  if (nf > 16) return reject(DvlCounter::kFormat, StatusCode::kCorrupt, "too many fields");
  if (out.type == 'z') {
    if (nf != 12 || f[0].n != 3) return reject(DvlCounter::kFormat, StatusCode::kCorrupt, "wrz needs 11 fields");
    DvlVelocity& v = out.velocity;
    v.source = DvlSource::kWaterLinked;
    long long tov = 0, tot = 0, status = 0;
    const Field valid = trim(f[4]);
    if (!parse_double(f[1], v.vx_mps) || !parse_double(f[2], v.vy_mps) || !parse_double(f[3], v.vz_mps) ||
        valid.n != 1 || (valid.p[0] != 'y' && valid.p[0] != 'n') || !parse_double(f[5], v.altitude_m) ||
        !parse_double(f[6], v.fom_mps) || !parse_int(f[8], tov) || !parse_int(f[9], tot) ||
        !parse_double(f[10], out.time_since_last_ms) || !parse_int(f[11], status))
      return reject(DvlCounter::kFormat, StatusCode::kCorrupt, "wrz field does not parse");
    Field cov[10];
    if (split_fields(f[7].p, f[7].n, ';', cov, 10) != 9) return reject(DvlCounter::kFormat, StatusCode::kCorrupt, "covariance needs 9 values");
    for (int i = 0; i < 9; ++i)
      if (!parse_double(cov[i], out.covariance[i])) return reject(DvlCounter::kFormat, StatusCode::kCorrupt, "covariance value");
    v.bottom_lock = valid.p[0] == 'y';
    if (std::fabs(v.vx_mps) > 10 || std::fabs(v.vy_mps) > 10 || std::fabs(v.vz_mps) > 10 || v.fom_mps < 0 ||
        (v.bottom_lock && v.altitude_m < 0) || v.altitude_m > kMaxDvlAltitudeM)
      return reject(DvlCounter::kRange, StatusCode::kOutOfRange, "wrz value out of range");
    // A covariance's diagonal is a variance: never negative.
    if (out.covariance[0] < 0 || out.covariance[4] < 0 || out.covariance[8] < 0)
      return reject(DvlCounter::kRange, StatusCode::kOutOfRange, "wrz covariance has a negative variance");
    if (tov < 0 || tot < 0 || tov > kMaxDvlDeviceTimeUs || tot > kMaxDvlDeviceTimeUs)
      return reject(DvlCounter::kRange, StatusCode::kOutOfRange, "wrz time outside 0..127 years");
    const long long latency_us = tot - tov;
    if (latency_us < 0 || latency_us > 1000000) return reject(DvlCounter::kRange, StatusCode::kOutOfRange, "DVL latency outside 0..1 s");
    if (have_last_ && tov <= last_validity_us_) return reject(DvlCounter::kStale, StatusCode::kInvalidArgument, "time_of_validity not advancing");
    have_last_ = true;
    last_validity_us_ = tov;
    v.device_time_us = tov;
    v.stamp.arrival_ns = arrival_ns;
    v.stamp.sample_ns = arrival_ns - latency_us * 1000;
    out.time_of_transmission_us = tot;
    out.status = static_cast<int>(status);
    out.kind = WlKind::kVelocity;
    if (!v.bottom_lock) counters_.increment(DvlCounter::kNoLock);
    return Status::ok();
  }
  if (out.type == 'u') {
    if (nf != 6 || f[0].n != 3) return reject(DvlCounter::kFormat, StatusCode::kCorrupt, "wru needs 5 fields");
    long long id = 0;
    WlTransducer& t = out.transducer;
    if (!parse_int(f[1], id) || !parse_double(f[2], t.velocity_mps) || !parse_double(f[3], t.distance_m) ||
        !parse_double(f[4], t.rssi_dbm) || !parse_double(f[5], t.nsd_dbm))
      return reject(DvlCounter::kFormat, StatusCode::kCorrupt, "wru field does not parse");
    if (id < 0 || id > 3 || std::fabs(t.velocity_mps) > 10) return reject(DvlCounter::kRange, StatusCode::kOutOfRange, "wru value out of range");
    t.id = static_cast<int>(id);
    t.locked = t.distance_m >= 0;
    out.kind = WlKind::kTransducer;
    return Status::ok();
  }
  if (out.type == 'p') {
    if (nf != 10 || f[0].n != 3) return reject(DvlCounter::kFormat, StatusCode::kCorrupt, "wrp needs 9 fields");
    WlDeadReckoning& d = out.dead_reckoning;
    long long st = 0;
    if (!parse_double(f[1], d.time_s) || !parse_double(f[2], d.x_m) || !parse_double(f[3], d.y_m) ||
        !parse_double(f[4], d.z_m) || !parse_double(f[5], d.pos_std_m) || !parse_double(f[6], d.roll_deg) ||
        !parse_double(f[7], d.pitch_deg) || !parse_double(f[8], d.yaw_deg) || !parse_int(f[9], st))
      return reject(DvlCounter::kFormat, StatusCode::kCorrupt, "wrp field does not parse");
    if (d.pos_std_m < 0 || std::fabs(d.roll_deg) > 360 || std::fabs(d.pitch_deg) > 360 || std::fabs(d.yaw_deg) > 360)
      return reject(DvlCounter::kRange, StatusCode::kOutOfRange, "wrp value out of range");
    d.status = static_cast<int>(st);
    out.kind = WlKind::kDeadReckoning;
    return Status::ok();
  }
  out.kind = WlKind::kOther;
  return Status::ok();
}

}  // namespace qnav::drivers::dvl
