// Typed MAVLink messages for an external navigation source (common.xml and ardupilotmega.xml), with
// their extension fields. Field names are the XML's (units in the comments, as the XML states them),
// so each struct reads against the definition. encode_payload() writes the message's full payload in
// wire order (fields by type size, largest first; extensions after, in definition order), little
// endian through nav/core/byte_order.hpp (correct on big-endian SPARC); decode_payload() reads a
// full-length payload (Parser restores truncated bytes as zeros). Strings (char[N]) are kept as the
// N wire bytes plus a terminating NUL the wire does not carry.
//   Odometry odo; ...;  Result<std::size_t> n = encode(encoder, odo, Span<std::uint8_t>(buf));
//   parser.feed(bytes, [&](const Frame& f) { Attitude a; if (decode(f, a)) { ... } });
// O(payload) time, no heap, no OS call.
#pragma once

#include <cstddef>
#include <cstdint>

#include "drivers/mavlink/frame.hpp"
#include "nav/core/span.hpp"
#include "nav/core/status.hpp"

namespace qnav::drivers::mavlink {

// Enum values qnav uses (common.xml).
constexpr std::uint8_t kMavTypeOnboardController = 18;
constexpr std::uint8_t kMavAutopilotInvalid = 8;
constexpr std::uint8_t kMavModeFlagSafetyArmed = 128;
constexpr std::uint8_t kMavFrameLocalNed = 1;
constexpr std::uint8_t kMavFrameBodyFrd = 12;
constexpr std::uint8_t kMavFrameLocalFrd = 20;
constexpr std::uint8_t kMavCompIdVisualInertialOdometry = 197;
constexpr std::uint8_t kMavEstimatorTypeVision = 2;
constexpr std::uint8_t kMavEstimatorTypeVio = 3;

struct Heartbeat {  // id 0
  static constexpr std::uint32_t kId = 0;
  std::uint32_t custom_mode = 0;
  std::uint8_t type = 0;          // MAV_TYPE
  std::uint8_t autopilot = 0;     // MAV_AUTOPILOT
  std::uint8_t base_mode = 0;     // MAV_MODE_FLAG bits
  std::uint8_t system_status = 0; // MAV_STATE
  std::uint8_t mavlink_version = 3;
};

struct SystemTime {  // id 2
  static constexpr std::uint32_t kId = 2;
  std::uint64_t time_unix_usec = 0;  // us since 1970
  std::uint32_t time_boot_ms = 0;
};

struct Attitude {  // id 30; rad, rad/s
  static constexpr std::uint32_t kId = 30;
  std::uint32_t time_boot_ms = 0;
  float roll = 0, pitch = 0, yaw = 0, rollspeed = 0, pitchspeed = 0, yawspeed = 0;
};

struct LocalPositionNed {  // id 32; m, m/s
  static constexpr std::uint32_t kId = 32;
  std::uint32_t time_boot_ms = 0;
  float x = 0, y = 0, z = 0, vx = 0, vy = 0, vz = 0;
};

struct SetGpsGlobalOrigin {  // id 48
  static constexpr std::uint32_t kId = 48;
  std::uint8_t target_system = 0;
  std::int32_t latitude = 0;   // degE7
  std::int32_t longitude = 0;  // degE7
  std::int32_t altitude = 0;   // mm (MSL)
  std::uint64_t time_usec = 0; // extension
};

struct GpsGlobalOrigin {  // id 49: the autopilot's EKF origin (its answer to SET_GPS_GLOBAL_ORIGIN)
  static constexpr std::uint32_t kId = 49;
  std::int32_t latitude = 0;   // degE7
  std::int32_t longitude = 0;  // degE7
  std::int32_t altitude = 0;   // mm (MSL)
  std::uint64_t time_usec = 0; // extension
};

struct CommandLong {  // id 76
  static constexpr std::uint32_t kId = 76;
  std::uint8_t target_system = 0, target_component = 0;
  std::uint16_t command = 0;  // MAV_CMD
  std::uint8_t confirmation = 0;
  float param1 = 0, param2 = 0, param3 = 0, param4 = 0, param5 = 0, param6 = 0, param7 = 0;
};

struct CommandAck {  // id 77
  static constexpr std::uint32_t kId = 77;
  std::uint16_t command = 0;
  std::uint8_t result = 0;          // MAV_RESULT
  std::uint8_t progress = 0;        // extension, %
  std::int32_t result_param2 = 0;   // extension
  std::uint8_t target_system = 0;   // extension
  std::uint8_t target_component = 0;// extension
};

struct SetPositionTargetLocalNed {  // id 84; m, m/s, m/s^2, rad, rad/s
  static constexpr std::uint32_t kId = 84;
  std::uint32_t time_boot_ms = 0;
  std::uint8_t target_system = 0, target_component = 0;
  std::uint8_t coordinate_frame = kMavFrameLocalNed;
  std::uint16_t type_mask = 0;  // POSITION_TARGET_TYPEMASK: bits set = ignore
  float x = 0, y = 0, z = 0, vx = 0, vy = 0, vz = 0, afx = 0, afy = 0, afz = 0, yaw = 0, yaw_rate = 0;
};

struct VisionPositionEstimate {  // id 102; us, m, rad
  static constexpr std::uint32_t kId = 102;
  std::uint64_t usec = 0;
  float x = 0, y = 0, z = 0, roll = 0, pitch = 0, yaw = 0;
  float covariance[21] = {};  // extension
  std::uint8_t reset_counter = 0;  // extension
};

struct VisionSpeedEstimate {  // id 103; us, m/s
  static constexpr std::uint32_t kId = 103;
  std::uint64_t usec = 0;
  float x = 0, y = 0, z = 0;
  float covariance[9] = {};        // extension
  std::uint8_t reset_counter = 0;  // extension
};

struct DistanceSensor {  // id 132
  static constexpr std::uint32_t kId = 132;
  std::uint32_t time_boot_ms = 0;
  std::uint16_t min_distance = 0, max_distance = 0, current_distance = 0;  // cm
  std::uint8_t type = 0, id = 0, orientation = 0, covariance = 0;  // covariance: cm^2
  float horizontal_fov = 0, vertical_fov = 0;  // extensions, rad
  float quaternion[4] = {};                    // extension
  std::uint8_t signal_quality = 0;             // extension, %
};

struct EkfStatusReport {  // id 193 (ardupilotmega)
  static constexpr std::uint32_t kId = 193;
  std::uint16_t flags = 0;  // EKF_STATUS_FLAGS
  float velocity_variance = 0, pos_horiz_variance = 0, pos_vert_variance = 0, compass_variance = 0,
        terrain_alt_variance = 0;
  float airspeed_variance = 0;  // extension
};

struct NamedValueFloat {  // id 251
  static constexpr std::uint32_t kId = 251;
  std::uint32_t time_boot_ms = 0;
  char name[11] = {};  // 10 wire bytes + NUL
  float value = 0;
};

struct StatusText {  // id 253
  static constexpr std::uint32_t kId = 253;
  std::uint8_t severity = 0;  // MAV_SEVERITY
  char text[51] = {};         // 50 wire bytes + NUL
  std::uint16_t id = 0;       // extension
  std::uint8_t chunk_seq = 0; // extension
};

struct Odometry {  // id 331; us, m, m/s, rad/s
  static constexpr std::uint32_t kId = 331;
  std::uint64_t time_usec = 0;
  std::uint8_t frame_id = kMavFrameLocalFrd, child_frame_id = kMavFrameBodyFrd;  // MAV_FRAME
  float x = 0, y = 0, z = 0;
  float q[4] = {1, 0, 0, 0};  // w, x, y, z
  float vx = 0, vy = 0, vz = 0, rollspeed = 0, pitchspeed = 0, yawspeed = 0;
  float pose_covariance[21] = {};
  float velocity_covariance[21] = {};
  std::uint8_t reset_counter = 0;   // extension
  std::uint8_t estimator_type = 0;  // extension, MAV_ESTIMATOR_TYPE
  std::int8_t quality = 0;          // extension: -1 failed, 0 unknown, 1..100
};

struct VisionPositionDelta {  // id 11011 (ardupilotmega); us, rad, m, %
  static constexpr std::uint32_t kId = 11011;
  std::uint64_t time_usec = 0, time_delta_usec = 0;
  float angle_delta[3] = {};
  float position_delta[3] = {};
  float confidence = 0;
};

// Full-length payloads (writes message_info(kId)->full_len bytes) and their decoding.
#define QNAV_MAVLINK_CODEC(T)                                                   \
  void encode_payload(const T& m, std::uint8_t* payload) noexcept;              \
  void decode_payload(const std::uint8_t* payload, T& m) noexcept;
QNAV_MAVLINK_CODEC(Heartbeat)
QNAV_MAVLINK_CODEC(SystemTime)
QNAV_MAVLINK_CODEC(Attitude)
QNAV_MAVLINK_CODEC(LocalPositionNed)
QNAV_MAVLINK_CODEC(SetGpsGlobalOrigin)
QNAV_MAVLINK_CODEC(GpsGlobalOrigin)
QNAV_MAVLINK_CODEC(CommandLong)
QNAV_MAVLINK_CODEC(CommandAck)
QNAV_MAVLINK_CODEC(SetPositionTargetLocalNed)
QNAV_MAVLINK_CODEC(VisionPositionEstimate)
QNAV_MAVLINK_CODEC(VisionSpeedEstimate)
QNAV_MAVLINK_CODEC(DistanceSensor)
QNAV_MAVLINK_CODEC(EkfStatusReport)
QNAV_MAVLINK_CODEC(NamedValueFloat)
QNAV_MAVLINK_CODEC(StatusText)
QNAV_MAVLINK_CODEC(Odometry)
QNAV_MAVLINK_CODEC(VisionPositionDelta)
#undef QNAV_MAVLINK_CODEC

// Copies a C string into a char[N+1] message field (cut at N bytes, rest zero).
template <std::size_t N>
void set_string(char (&field)[N], const char* s) noexcept {
  std::size_t i = 0;
  for (; s != nullptr && s[i] != '\0' && i + 1 < N; ++i) field[i] = s[i];
  for (; i < N; ++i) field[i] = '\0';
}

// One frame of message m from encoder's sender into out (see FrameEncoder::encode).
template <typename M>
Result<std::size_t> encode(FrameEncoder& encoder, const M& m, Span<std::uint8_t> out) noexcept {
  std::uint8_t payload[kMaxPayload];
  encode_payload(m, payload);
  const MessageInfo* info = message_info(M::kId);
  return encoder.encode(M::kId, payload, info != nullptr ? info->full_len : 0, out);
}

// True when f is an M (by id) and out now holds its fields.
template <typename M>
bool decode(const Frame& f, M& out) noexcept {
  if (f.msgid != M::kId) return false;
  decode_payload(f.payload, out);
  return true;
}

}  // namespace qnav::drivers::mavlink
