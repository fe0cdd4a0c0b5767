#include "drivers/dronecan/ahrs.hpp"

#include "drivers/dronecan/float16.hpp"
#include "nav/core/byte_order.hpp"

namespace qnav::drivers::dronecan {

namespace {
struct Reader {
  const std::uint8_t* p;
  std::size_t n;
  std::size_t i = 0;
  bool ok = true;
  bool need(std::size_t k) noexcept {
    if (!ok || n - i < k || i > n) ok = false;
    return ok;
  }
  std::uint64_t u56() noexcept {
    if (!need(7)) return 0;
    std::uint64_t v = 0;
    for (int k = 6; k >= 0; --k) v = (v << 8) | p[i + static_cast<std::size_t>(k)];
    i += 7;
    return v;
  }
  float f16() noexcept {
    if (!need(2)) return 0;
    const float v = half_to_float(load_le_u16(p + i));
    i += 2;
    return v;
  }
  float f32() noexcept {
    if (!need(4)) return 0;
    const float v = load_le_f32(p + i);
    i += 4;
    return v;
  }
  std::uint8_t u8() noexcept {
    if (!need(1)) return 0;
    return p[i++];
  }
};
struct Writer {
  std::uint8_t* p;
  std::size_t cap;
  std::size_t i = 0;
  bool ok = true;
  bool room(std::size_t k) noexcept {
    if (!ok || cap - i < k) ok = false;
    return ok;
  }
  void u56(std::uint64_t v) noexcept {
    if (!room(7)) return;
    for (int k = 0; k < 7; ++k) p[i++] = static_cast<std::uint8_t>(v >> (8 * k));
  }
  void f16(float v) noexcept {
    if (!room(2)) return;
    store_le_u16(p + i, float_to_half(v));
    i += 2;
  }
  void f32(float v) noexcept {
    if (!room(4)) return;
    store_le_f32(p + i, v);
    i += 4;
  }
  void u8(std::uint8_t v) noexcept {
    if (room(1)) p[i++] = v;
  }
};

// A `void4` + 4-bit length byte (length in the low nibble: the second field in MSB-first order).
bool read_len4(Reader& r, std::uint8_t& len, std::uint8_t max) noexcept {
  len = r.u8() & 0x0Fu;
  return len <= max;
}
// Tail array optimisation: the last array has no length prefix; its length is what is left.
bool read_tail_array(Reader& r, std::uint8_t max, std::uint8_t& len, float* dst) noexcept {
  const std::size_t rem = r.n - r.i;
  if (rem % 2 != 0 || rem / 2 > max) return false;
  len = static_cast<std::uint8_t>(rem / 2);
  for (std::uint8_t k = 0; k < len; ++k) dst[k] = r.f16();
  return true;
}
}  // namespace

Status decode_solution(const std::uint8_t* p, std::size_t n, bool tao, AhrsSolution& o) noexcept {
  if (p == nullptr) return Status(StatusCode::kInvalidArgument, "null payload");
  if (n > kSolutionMaxBytes) return Status(StatusCode::kCorrupt, "Solution payload longer than its DSDL maximum");
  Reader r{p, n};
  o.timestamp_us = r.u56();
  for (float& q : o.orientation_xyzw) q = r.f16();
  if (!read_len4(r, o.orientation_cov_len, 9)) return Status(StatusCode::kCorrupt, "orientation covariance length > 9");
  for (std::uint8_t k = 0; k < o.orientation_cov_len; ++k) o.orientation_cov[k] = r.f16();
  for (float& w : o.angular_velocity_radps) w = r.f16();
  if (!read_len4(r, o.angular_velocity_cov_len, 9)) return Status(StatusCode::kCorrupt, "rate covariance length > 9");
  for (std::uint8_t k = 0; k < o.angular_velocity_cov_len; ++k) o.angular_velocity_cov[k] = r.f16();
  for (float& a : o.linear_accel_mps2) a = r.f16();
  if (!r.ok) return Status(StatusCode::kTruncated, "Solution payload ends inside a field");
  if (!tao) return Status(StatusCode::kUnsupported, "Solution without TAO (CAN FD) is not supported");
  if (!read_tail_array(r, 9, o.linear_accel_cov_len, o.linear_accel_cov))
    return Status(StatusCode::kCorrupt, "acceleration covariance length > 9 or odd");
  if (!r.ok) return Status(StatusCode::kTruncated, "Solution payload ends inside a field");
  return Status::ok();
}

Status decode_raw_imu(const std::uint8_t* p, std::size_t n, bool tao, RawImu& o) noexcept {
  if (p == nullptr) return Status(StatusCode::kInvalidArgument, "null payload");
  if (n > kRawImuMaxBytes) return Status(StatusCode::kCorrupt, "RawIMU payload longer than its DSDL maximum");
  Reader r{p, n};
  o.timestamp_us = r.u56();
  o.integration_interval_s = r.f32();
  for (float& v : o.rate_gyro_latest_radps) v = r.f16();
  for (float& v : o.rate_gyro_integral_rad) v = r.f32();
  for (float& v : o.accel_latest_mps2) v = r.f16();
  for (float& v : o.accel_integral_mps) v = r.f32();
  if (!r.ok) return Status(StatusCode::kTruncated, "RawIMU payload ends inside a field");
  if (!tao) return Status(StatusCode::kUnsupported, "RawIMU without TAO (CAN FD) is not supported");
  if (!read_tail_array(r, 36, o.covariance_len, o.covariance))
    return Status(StatusCode::kCorrupt, "covariance length > 36 or odd");
  return Status::ok();
}

std::size_t encode_solution(const AhrsSolution& m, bool tao, std::uint8_t* out, std::size_t cap) noexcept {
  if (!tao || m.orientation_cov_len > 9 || m.angular_velocity_cov_len > 9 || m.linear_accel_cov_len > 9) return 0;
  Writer w{out, cap};
  w.u56(m.timestamp_us);
  for (float q : m.orientation_xyzw) w.f16(q);
  w.u8(m.orientation_cov_len);
  for (std::uint8_t k = 0; k < m.orientation_cov_len; ++k) w.f16(m.orientation_cov[k]);
  for (float v : m.angular_velocity_radps) w.f16(v);
  w.u8(m.angular_velocity_cov_len);
  for (std::uint8_t k = 0; k < m.angular_velocity_cov_len; ++k) w.f16(m.angular_velocity_cov[k]);
  for (float v : m.linear_accel_mps2) w.f16(v);
  for (std::uint8_t k = 0; k < m.linear_accel_cov_len; ++k) w.f16(m.linear_accel_cov[k]);
  return w.ok ? w.i : 0;
}

std::size_t encode_raw_imu(const RawImu& m, bool tao, std::uint8_t* out, std::size_t cap) noexcept {
  if (!tao || m.covariance_len > 36) return 0;
  Writer w{out, cap};
  w.u56(m.timestamp_us);
  w.f32(m.integration_interval_s);
  for (float v : m.rate_gyro_latest_radps) w.f16(v);
  for (float v : m.rate_gyro_integral_rad) w.f32(v);
  for (float v : m.accel_latest_mps2) w.f16(v);
  for (float v : m.accel_integral_mps) w.f32(v);
  for (std::uint8_t k = 0; k < m.covariance_len; ++k) w.f16(m.covariance[k]);
  return w.ok ? w.i : 0;
}

}  // namespace qnav::drivers::dronecan
