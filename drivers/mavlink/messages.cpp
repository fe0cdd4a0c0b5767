#include "drivers/mavlink/messages.hpp"

#include <cstring>

#include "nav/core/byte_order.hpp"

namespace qnav::drivers::mavlink {
namespace {

// Each message's fields are listed once, in wire order (MAVLink sorts them by size, largest first,
// then extensions), by QNAV_MAV_MESSAGE below; the writer W and the reader R walk that one list.
// Little-endian on every host (nav/core/byte_order.hpp: SPARC is big-endian). A char array of N
// bytes is N - 1 wire bytes (zero after the string's end) and a NUL; a float array is its elements.
class W {
 public:
  explicit W(std::uint8_t* p) noexcept : p_(p) {}
  W& operator()(std::uint8_t v) noexcept { p_[o_++] = v; return *this; }
  W& operator()(std::int8_t v) noexcept { return (*this)(static_cast<std::uint8_t>(v)); }
  W& operator()(std::uint16_t v) noexcept { store_le_u16(p_ + o_, v); o_ += 2; return *this; }
  W& operator()(std::uint32_t v) noexcept { store_le_u32(p_ + o_, v); o_ += 4; return *this; }
  W& operator()(std::int32_t v) noexcept { return (*this)(static_cast<std::uint32_t>(v)); }
  W& operator()(std::uint64_t v) noexcept { store_le_u64(p_ + o_, v); o_ += 8; return *this; }
  W& operator()(float v) noexcept { store_le_f32(p_ + o_, v); o_ += 4; return *this; }
  template <std::size_t N>
  W& operator()(const float (&v)[N]) noexcept {
    for (std::size_t i = 0; i < N; ++i) (*this)(v[i]);
    return *this;
  }
  template <std::size_t N>
  W& operator()(const char (&s)[N]) noexcept {
    std::size_t i = 0;
    for (; i < N - 1 && s[i] != '\0'; ++i) p_[o_ + i] = static_cast<std::uint8_t>(s[i]);
    for (; i < N - 1; ++i) p_[o_ + i] = 0;
    o_ += N - 1;
    return *this;
  }

 private:
  std::uint8_t* p_;
  std::size_t o_ = 0;
};

class R {
 public:
  explicit R(const std::uint8_t* p) noexcept : p_(p) {}
  R& operator()(std::uint8_t& v) noexcept { v = p_[o_++]; return *this; }
  R& operator()(std::int8_t& v) noexcept { v = static_cast<std::int8_t>(p_[o_++]); return *this; }
  R& operator()(std::uint16_t& v) noexcept { v = load_le_u16(p_ + o_); o_ += 2; return *this; }
  R& operator()(std::uint32_t& v) noexcept { v = load_le_u32(p_ + o_); o_ += 4; return *this; }
  R& operator()(std::int32_t& v) noexcept { v = static_cast<std::int32_t>(load_le_u32(p_ + o_)); o_ += 4; return *this; }
  R& operator()(std::uint64_t& v) noexcept { v = load_le_u64(p_ + o_); o_ += 8; return *this; }
  R& operator()(float& v) noexcept { v = load_le_f32(p_ + o_); o_ += 4; return *this; }
  template <std::size_t N>
  R& operator()(float (&v)[N]) noexcept {
    for (std::size_t i = 0; i < N; ++i) (*this)(v[i]);
    return *this;
  }
  template <std::size_t N>
  R& operator()(char (&s)[N]) noexcept {
    for (std::size_t i = 0; i < N - 1; ++i) s[i] = static_cast<char>(p_[o_ + i]);
    s[N - 1] = '\0';
    o_ += N - 1;
    return *this;
  }

 private:
  const std::uint8_t* p_;
  std::size_t o_ = 0;
};

template <class T>
struct Fields;

}  // namespace

// One message: its fields in wire order, and its encode_payload / decode_payload over them.
#define QNAV_MAV_MESSAGE(T, FIELDS)                                                          \
  namespace {                                                                                \
  template <>                                                                                \
  struct Fields<T> {                                                                         \
    template <class M, class IO>                                                             \
    static void visit(M& m, IO& io) noexcept {                                               \
      io FIELDS;                                                                             \
    }                                                                                        \
  };                                                                                         \
  }                                                                                          \
  void encode_payload(const T& m, std::uint8_t* p) noexcept {                                \
    W w(p);                                                                                  \
    Fields<T>::visit(m, w);                                                                  \
  }                                                                                          \
  void decode_payload(const std::uint8_t* p, T& m) noexcept {                                \
    R r(p);                                                                                  \
    Fields<T>::visit(m, r);                                                                  \
  }

QNAV_MAV_MESSAGE(Heartbeat, (m.custom_mode)(m.type)(m.autopilot)(m.base_mode)(m.system_status)(m.mavlink_version))
QNAV_MAV_MESSAGE(SystemTime, (m.time_unix_usec)(m.time_boot_ms))
QNAV_MAV_MESSAGE(Attitude, (m.time_boot_ms)(m.roll)(m.pitch)(m.yaw)(m.rollspeed)(m.pitchspeed)(m.yawspeed))
QNAV_MAV_MESSAGE(LocalPositionNed, (m.time_boot_ms)(m.x)(m.y)(m.z)(m.vx)(m.vy)(m.vz))
QNAV_MAV_MESSAGE(SetGpsGlobalOrigin, (m.latitude)(m.longitude)(m.altitude)(m.target_system)(m.time_usec))
QNAV_MAV_MESSAGE(GpsGlobalOrigin, (m.latitude)(m.longitude)(m.altitude)(m.time_usec))
QNAV_MAV_MESSAGE(CommandLong, (m.param1)(m.param2)(m.param3)(m.param4)(m.param5)(m.param6)(m.param7)(m.command)(m.target_system)(m.target_component)(m.confirmation))
QNAV_MAV_MESSAGE(CommandAck, (m.command)(m.result)(m.progress)(m.result_param2)(m.target_system)(m.target_component))
QNAV_MAV_MESSAGE(SetPositionTargetLocalNed, (m.time_boot_ms)(m.x)(m.y)(m.z)(m.vx)(m.vy)(m.vz)(m.afx)(m.afy)(m.afz)(m.yaw)(m.yaw_rate)(m.type_mask)(m.target_system)(m.target_component)(m.coordinate_frame))
QNAV_MAV_MESSAGE(VisionPositionEstimate, (m.usec)(m.x)(m.y)(m.z)(m.roll)(m.pitch)(m.yaw)(m.covariance)(m.reset_counter))
QNAV_MAV_MESSAGE(VisionSpeedEstimate, (m.usec)(m.x)(m.y)(m.z)(m.covariance)(m.reset_counter))
QNAV_MAV_MESSAGE(DistanceSensor, (m.time_boot_ms)(m.min_distance)(m.max_distance)(m.current_distance)(m.type)(m.id)(m.orientation)(m.covariance)(m.horizontal_fov)(m.vertical_fov)(m.quaternion)(m.signal_quality))
QNAV_MAV_MESSAGE(EkfStatusReport, (m.velocity_variance)(m.pos_horiz_variance)(m.pos_vert_variance)(m.compass_variance)(m.terrain_alt_variance)(m.flags)(m.airspeed_variance))
QNAV_MAV_MESSAGE(NamedValueFloat, (m.time_boot_ms)(m.value)(m.name))
QNAV_MAV_MESSAGE(StatusText, (m.severity)(m.text)(m.id)(m.chunk_seq))
QNAV_MAV_MESSAGE(Odometry, (m.time_usec)(m.x)(m.y)(m.z)(m.q)(m.vx)(m.vy)(m.vz)(m.rollspeed)(m.pitchspeed)(m.yawspeed)(m.pose_covariance)(m.velocity_covariance)(m.frame_id)(m.child_frame_id)(m.reset_counter)(m.estimator_type)(m.quality))
QNAV_MAV_MESSAGE(VisionPositionDelta, (m.time_usec)(m.time_delta_usec)(m.angle_delta)(m.position_delta)(m.confidence))

#undef QNAV_MAV_MESSAGE

}  // namespace qnav::drivers::mavlink
