#include "drivers/mavlink/messages.hpp"

#include <cstring>

#include "nav/core/byte_order.hpp"

namespace qnav::drivers::mavlink {
namespace {

// Sequential little-endian writer / reader over a full-length payload (wire order = call order).
class W {
 public:
  explicit W(std::uint8_t* p) noexcept : p_(p) {}
  W& u8(std::uint8_t v) noexcept { p_[o_++] = v; return *this; }
  W& i8(std::int8_t v) noexcept { return u8(static_cast<std::uint8_t>(v)); }
  W& u16(std::uint16_t v) noexcept { store_le_u16(p_ + o_, v); o_ += 2; return *this; }
  W& u32(std::uint32_t v) noexcept { store_le_u32(p_ + o_, v); o_ += 4; return *this; }
  W& i32(std::int32_t v) noexcept { return u32(static_cast<std::uint32_t>(v)); }
  W& u64(std::uint64_t v) noexcept { store_le_u64(p_ + o_, v); o_ += 8; return *this; }
  W& f32(float v) noexcept { store_le_f32(p_ + o_, v); o_ += 4; return *this; }
  W& f32s(const float* v, std::size_t n) noexcept { for (std::size_t i = 0; i < n; ++i) f32(v[i]); return *this; }
  W& chars(const char* s, std::size_t n) noexcept {  // n wire bytes, zero after the string's end
    std::size_t i = 0;
    for (; i < n && s[i] != '\0'; ++i) p_[o_ + i] = static_cast<std::uint8_t>(s[i]);
    for (; i < n; ++i) p_[o_ + i] = 0;
    o_ += n;
    return *this;
  }

 private:
  std::uint8_t* p_;
  std::size_t o_ = 0;
};

class R {
 public:
  explicit R(const std::uint8_t* p) noexcept : p_(p) {}
  std::uint8_t u8() noexcept { return p_[o_++]; }
  std::int8_t i8() noexcept { return static_cast<std::int8_t>(u8()); }
  std::uint16_t u16() noexcept { o_ += 2; return load_le_u16(p_ + o_ - 2); }
  std::uint32_t u32() noexcept { o_ += 4; return load_le_u32(p_ + o_ - 4); }
  std::int32_t i32() noexcept { return static_cast<std::int32_t>(u32()); }
  std::uint64_t u64() noexcept { o_ += 8; return load_le_u64(p_ + o_ - 8); }
  float f32() noexcept { o_ += 4; return load_le_f32(p_ + o_ - 4); }
  void f32s(float* v, std::size_t n) noexcept { for (std::size_t i = 0; i < n; ++i) v[i] = f32(); }
  void chars(char* s, std::size_t n) noexcept {  // s has n + 1 bytes
    for (std::size_t i = 0; i < n; ++i) s[i] = static_cast<char>(p_[o_ + i]);
    s[n] = '\0';
    o_ += n;
  }

 private:
  const std::uint8_t* p_;
  std::size_t o_ = 0;
};

}  // namespace

void encode_payload(const Heartbeat& m, std::uint8_t* p) noexcept {
  W(p).u32(m.custom_mode).u8(m.type).u8(m.autopilot).u8(m.base_mode).u8(m.system_status).u8(m.mavlink_version);
}
void decode_payload(const std::uint8_t* p, Heartbeat& m) noexcept {
  R r(p);
  m.custom_mode = r.u32();
  m.type = r.u8();
  m.autopilot = r.u8();
  m.base_mode = r.u8();
  m.system_status = r.u8();
  m.mavlink_version = r.u8();
}

void encode_payload(const SystemTime& m, std::uint8_t* p) noexcept { W(p).u64(m.time_unix_usec).u32(m.time_boot_ms); }
void decode_payload(const std::uint8_t* p, SystemTime& m) noexcept {
  R r(p);
  m.time_unix_usec = r.u64();
  m.time_boot_ms = r.u32();
}

void encode_payload(const Attitude& m, std::uint8_t* p) noexcept {
  W(p).u32(m.time_boot_ms).f32(m.roll).f32(m.pitch).f32(m.yaw).f32(m.rollspeed).f32(m.pitchspeed).f32(m.yawspeed);
}
void decode_payload(const std::uint8_t* p, Attitude& m) noexcept {
  R r(p);
  m.time_boot_ms = r.u32();
  m.roll = r.f32();
  m.pitch = r.f32();
  m.yaw = r.f32();
  m.rollspeed = r.f32();
  m.pitchspeed = r.f32();
  m.yawspeed = r.f32();
}

void encode_payload(const LocalPositionNed& m, std::uint8_t* p) noexcept {
  W(p).u32(m.time_boot_ms).f32(m.x).f32(m.y).f32(m.z).f32(m.vx).f32(m.vy).f32(m.vz);
}
void decode_payload(const std::uint8_t* p, LocalPositionNed& m) noexcept {
  R r(p);
  m.time_boot_ms = r.u32();
  m.x = r.f32();
  m.y = r.f32();
  m.z = r.f32();
  m.vx = r.f32();
  m.vy = r.f32();
  m.vz = r.f32();
}

void encode_payload(const SetGpsGlobalOrigin& m, std::uint8_t* p) noexcept {
  W(p).i32(m.latitude).i32(m.longitude).i32(m.altitude).u8(m.target_system).u64(m.time_usec);
}
void decode_payload(const std::uint8_t* p, SetGpsGlobalOrigin& m) noexcept {
  R r(p);
  m.latitude = r.i32();
  m.longitude = r.i32();
  m.altitude = r.i32();
  m.target_system = r.u8();
  m.time_usec = r.u64();
}

void encode_payload(const GpsGlobalOrigin& m, std::uint8_t* p) noexcept {
  W(p).i32(m.latitude).i32(m.longitude).i32(m.altitude).u64(m.time_usec);
}
void decode_payload(const std::uint8_t* p, GpsGlobalOrigin& m) noexcept {
  R r(p);
  m.latitude = r.i32();
  m.longitude = r.i32();
  m.altitude = r.i32();
  m.time_usec = r.u64();
}

void encode_payload(const CommandLong& m, std::uint8_t* p) noexcept {
  W(p).f32(m.param1).f32(m.param2).f32(m.param3).f32(m.param4).f32(m.param5).f32(m.param6).f32(m.param7)
      .u16(m.command).u8(m.target_system).u8(m.target_component).u8(m.confirmation);
}
void decode_payload(const std::uint8_t* p, CommandLong& m) noexcept {
  R r(p);
  m.param1 = r.f32();
  m.param2 = r.f32();
  m.param3 = r.f32();
  m.param4 = r.f32();
  m.param5 = r.f32();
  m.param6 = r.f32();
  m.param7 = r.f32();
  m.command = r.u16();
  m.target_system = r.u8();
  m.target_component = r.u8();
  m.confirmation = r.u8();
}

void encode_payload(const CommandAck& m, std::uint8_t* p) noexcept {
  W(p).u16(m.command).u8(m.result).u8(m.progress).i32(m.result_param2).u8(m.target_system).u8(m.target_component);
}
void decode_payload(const std::uint8_t* p, CommandAck& m) noexcept {
  R r(p);
  m.command = r.u16();
  m.result = r.u8();
  m.progress = r.u8();
  m.result_param2 = r.i32();
  m.target_system = r.u8();
  m.target_component = r.u8();
}

void encode_payload(const SetPositionTargetLocalNed& m, std::uint8_t* p) noexcept {
  W(p).u32(m.time_boot_ms).f32(m.x).f32(m.y).f32(m.z).f32(m.vx).f32(m.vy).f32(m.vz).f32(m.afx).f32(m.afy).f32(m.afz)
      .f32(m.yaw).f32(m.yaw_rate).u16(m.type_mask).u8(m.target_system).u8(m.target_component).u8(m.coordinate_frame);
}
void decode_payload(const std::uint8_t* p, SetPositionTargetLocalNed& m) noexcept {
  R r(p);
  m.time_boot_ms = r.u32();
  m.x = r.f32();
  m.y = r.f32();
  m.z = r.f32();
  m.vx = r.f32();
  m.vy = r.f32();
  m.vz = r.f32();
  m.afx = r.f32();
  m.afy = r.f32();
  m.afz = r.f32();
  m.yaw = r.f32();
  m.yaw_rate = r.f32();
  m.type_mask = r.u16();
  m.target_system = r.u8();
  m.target_component = r.u8();
  m.coordinate_frame = r.u8();
}

void encode_payload(const VisionPositionEstimate& m, std::uint8_t* p) noexcept {
  W(p).u64(m.usec).f32(m.x).f32(m.y).f32(m.z).f32(m.roll).f32(m.pitch).f32(m.yaw).f32s(m.covariance, 21).u8(m.reset_counter);
}
void decode_payload(const std::uint8_t* p, VisionPositionEstimate& m) noexcept {
  R r(p);
  m.usec = r.u64();
  m.x = r.f32();
  m.y = r.f32();
  m.z = r.f32();
  m.roll = r.f32();
  m.pitch = r.f32();
  m.yaw = r.f32();
  r.f32s(m.covariance, 21);
  m.reset_counter = r.u8();
}

void encode_payload(const VisionSpeedEstimate& m, std::uint8_t* p) noexcept {
  W(p).u64(m.usec).f32(m.x).f32(m.y).f32(m.z).f32s(m.covariance, 9).u8(m.reset_counter);
}
void decode_payload(const std::uint8_t* p, VisionSpeedEstimate& m) noexcept {
  R r(p);
  m.usec = r.u64();
  m.x = r.f32();
  m.y = r.f32();
  m.z = r.f32();
  r.f32s(m.covariance, 9);
  m.reset_counter = r.u8();
}

void encode_payload(const DistanceSensor& m, std::uint8_t* p) noexcept {
  W(p).u32(m.time_boot_ms).u16(m.min_distance).u16(m.max_distance).u16(m.current_distance).u8(m.type).u8(m.id)
      .u8(m.orientation).u8(m.covariance).f32(m.horizontal_fov).f32(m.vertical_fov).f32s(m.quaternion, 4)
      .u8(m.signal_quality);
}
void decode_payload(const std::uint8_t* p, DistanceSensor& m) noexcept {
  R r(p);
  m.time_boot_ms = r.u32();
  m.min_distance = r.u16();
  m.max_distance = r.u16();
  m.current_distance = r.u16();
  m.type = r.u8();
  m.id = r.u8();
  m.orientation = r.u8();
  m.covariance = r.u8();
  m.horizontal_fov = r.f32();
  m.vertical_fov = r.f32();
  r.f32s(m.quaternion, 4);
  m.signal_quality = r.u8();
}

void encode_payload(const EkfStatusReport& m, std::uint8_t* p) noexcept {
  W(p).f32(m.velocity_variance).f32(m.pos_horiz_variance).f32(m.pos_vert_variance).f32(m.compass_variance)
      .f32(m.terrain_alt_variance).u16(m.flags).f32(m.airspeed_variance);
}
void decode_payload(const std::uint8_t* p, EkfStatusReport& m) noexcept {
  R r(p);
  m.velocity_variance = r.f32();
  m.pos_horiz_variance = r.f32();
  m.pos_vert_variance = r.f32();
  m.compass_variance = r.f32();
  m.terrain_alt_variance = r.f32();
  m.flags = r.u16();
  m.airspeed_variance = r.f32();
}

void encode_payload(const NamedValueFloat& m, std::uint8_t* p) noexcept {
  W(p).u32(m.time_boot_ms).f32(m.value).chars(m.name, 10);
}
void decode_payload(const std::uint8_t* p, NamedValueFloat& m) noexcept {
  R r(p);
  m.time_boot_ms = r.u32();
  m.value = r.f32();
  r.chars(m.name, 10);
}

void encode_payload(const StatusText& m, std::uint8_t* p) noexcept {
  W(p).u8(m.severity).chars(m.text, 50).u16(m.id).u8(m.chunk_seq);
}
void decode_payload(const std::uint8_t* p, StatusText& m) noexcept {
  R r(p);
  m.severity = r.u8();
  r.chars(m.text, 50);
  m.id = r.u16();
  m.chunk_seq = r.u8();
}

void encode_payload(const Odometry& m, std::uint8_t* p) noexcept {
  W(p).u64(m.time_usec).f32(m.x).f32(m.y).f32(m.z).f32s(m.q, 4).f32(m.vx).f32(m.vy).f32(m.vz).f32(m.rollspeed)
      .f32(m.pitchspeed).f32(m.yawspeed).f32s(m.pose_covariance, 21).f32s(m.velocity_covariance, 21).u8(m.frame_id)
      .u8(m.child_frame_id).u8(m.reset_counter).u8(m.estimator_type).i8(m.quality);
}
void decode_payload(const std::uint8_t* p, Odometry& m) noexcept {
  R r(p);
  m.time_usec = r.u64();
  m.x = r.f32();
  m.y = r.f32();
  m.z = r.f32();
  r.f32s(m.q, 4);
  m.vx = r.f32();
  m.vy = r.f32();
  m.vz = r.f32();
  m.rollspeed = r.f32();
  m.pitchspeed = r.f32();
  m.yawspeed = r.f32();
  r.f32s(m.pose_covariance, 21);
  r.f32s(m.velocity_covariance, 21);
  m.frame_id = r.u8();
  m.child_frame_id = r.u8();
  m.reset_counter = r.u8();
  m.estimator_type = r.u8();
  m.quality = r.i8();
}

void encode_payload(const VisionPositionDelta& m, std::uint8_t* p) noexcept {
  W(p).u64(m.time_usec).u64(m.time_delta_usec).f32s(m.angle_delta, 3).f32s(m.position_delta, 3).f32(m.confidence);
}
void decode_payload(const std::uint8_t* p, VisionPositionDelta& m) noexcept {
  R r(p);
  m.time_usec = r.u64();
  m.time_delta_usec = r.u64();
  r.f32s(m.angle_delta, 3);
  r.f32s(m.position_delta, 3);
  m.confidence = r.f32();
}

}  // namespace qnav::drivers::mavlink
