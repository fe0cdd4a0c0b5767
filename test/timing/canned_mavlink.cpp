// The canned inputs of the MAVLink codec's timing stages (canned.hpp: CannedMavlink): one message per
// call, encoded to a complete MAVLink 2 frame or parsed from one (Parser::feed byte stream + typed
// decode), for the messages qnavd sends (ODOMETRY, VISION_POSITION_DELTA, DISTANCE_SENSOR, HEARTBEAT,
// NAMED_VALUE_FLOAT) and the command it reads (COMMAND_LONG), plus signing (sign_frame) and a signed
// frame's verification. Field values are pseudo-random (a fixed LCG), so no payload is truncated more
// than a real one is. The counted call does the codec's work only: the result is hashed after the
// region (result()), since hashing a frame costs more than encoding it. Kept out of canned.cpp (the
// freestanding LEON3 workload does not link drivers/mavlink).
#include <cstring>

#include "drivers/mavlink/frame.hpp"
#include "drivers/mavlink/messages.hpp"
#include "drivers/mavlink/parser.hpp"
#include "test/timing/canned.hpp"

namespace qnav::timing {

namespace mav = drivers::mavlink;

namespace {

class Lcg {
 public:
  explicit Lcg(std::uint64_t seed) noexcept : s_(seed) {}
  std::uint32_t u32() noexcept {
    s_ = s_ * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<std::uint32_t>(s_ >> 32);
  }
  float f(float lo, float hi) noexcept { return lo + (hi - lo) * static_cast<float>(u32() >> 8) * (1.0f / 16777216.0f); }

 private:
  std::uint64_t s_;
};

mav::Odometry make_odometry(Lcg& r, int k) {
  mav::Odometry m;
  m.time_usec = 1000000ull * static_cast<std::uint64_t>(k + 1) + r.u32() % 1000;
  m.x = r.f(-500, 500);
  m.y = r.f(-500, 500);
  m.z = r.f(0, 100);
  for (float& q : m.q) q = r.f(-1, 1);
  m.vx = r.f(-2, 2);
  m.vy = r.f(-2, 2);
  m.vz = r.f(-1, 1);
  m.rollspeed = r.f(-0.5f, 0.5f);
  m.pitchspeed = r.f(-0.5f, 0.5f);
  m.yawspeed = r.f(-0.5f, 0.5f);
  for (float& c : m.pose_covariance) c = r.f(0, 4);
  for (float& c : m.velocity_covariance) c = r.f(0, 1);
  m.reset_counter = static_cast<std::uint8_t>(r.u32());
  m.estimator_type = mav::kMavEstimatorTypeVio;
  m.quality = static_cast<std::int8_t>(1 + r.u32() % 100);
  return m;
}

mav::VisionPositionDelta make_delta(Lcg& r, int k) {
  mav::VisionPositionDelta m;
  m.time_usec = 1000000ull * static_cast<std::uint64_t>(k + 1);
  m.time_delta_usec = 100000 + r.u32() % 1000;
  for (float& a : m.angle_delta) a = r.f(-0.1f, 0.1f);
  for (float& p : m.position_delta) p = r.f(-0.5f, 0.5f);
  m.confidence = r.f(1, 100);
  return m;
}

mav::DistanceSensor make_distance(Lcg& r, int k) {
  mav::DistanceSensor m;
  m.time_boot_ms = 1000u * static_cast<std::uint32_t>(k + 1);
  m.min_distance = 10;
  m.max_distance = 5000;
  m.current_distance = static_cast<std::uint16_t>(10 + r.u32() % 4990);
  m.type = 1;
  m.id = 0;
  m.orientation = 25;  // MAV_SENSOR_ROTATION_PITCH_270: down
  m.covariance = static_cast<std::uint8_t>(r.u32() % 250);
  m.horizontal_fov = r.f(0, 1);
  m.vertical_fov = r.f(0, 1);
  for (float& q : m.quaternion) q = r.f(-1, 1);
  m.signal_quality = static_cast<std::uint8_t>(1 + r.u32() % 100);
  return m;
}

mav::Heartbeat make_heartbeat(Lcg& r) {
  mav::Heartbeat m;
  m.custom_mode = r.u32() % 8;
  m.type = mav::kMavTypeOnboardController;
  m.autopilot = mav::kMavAutopilotInvalid;
  m.base_mode = 0;
  m.system_status = static_cast<std::uint8_t>(3 + r.u32() % 3);
  return m;
}

mav::NamedValueFloat make_named(Lcg& r, int k) {
  static const char* const kNames[] = {"xtrack_m", "sigma_m", "side", "node"};  // qnavd's route guidance
  mav::NamedValueFloat m;
  m.time_boot_ms = 1000u * static_cast<std::uint32_t>(k + 1);
  mav::set_string(m.name, kNames[k % 4]);
  m.value = r.f(-20, 20);
  return m;
}

mav::CommandLong make_command(Lcg& r) {
  mav::CommandLong m;
  m.target_system = 1;
  m.target_component = mav::kMavCompIdVisualInertialOdometry;
  m.command = 31000;  // MAV_CMD_USER_1 range: qnav's mode command
  m.confirmation = 0;
  m.param1 = static_cast<float>(r.u32() % 5);
  m.param2 = r.f(0, 1);
  m.param3 = r.f(0, 1);
  m.param4 = r.f(0, 1);
  m.param5 = r.f(0, 1);
  m.param6 = r.f(0, 1);
  m.param7 = r.f(0, 1);
  return m;
}

void hash_bytes(Hash& h, const std::uint8_t* p, std::size_t n) {
  h.add(static_cast<std::uint64_t>(n));
  for (std::size_t i = 0; i < n; ++i) h.add(static_cast<std::uint64_t>(p[i]));
}

void hash_floats(Hash& h, const float* v, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) h.add(static_cast<double>(v[i]));
}

}  // namespace

struct CannedMavlink::Impl {
  // Inputs, per call.
  mav::Odometry odometry[kCalls];
  mav::VisionPositionDelta delta[kCalls];
  mav::DistanceSensor distance[kCalls];
  mav::Heartbeat heartbeat[kCalls];
  mav::NamedValueFloat named[kCalls];
  struct Wire {
    std::uint8_t bytes[mav::kMaxFrameBytes];
    std::size_t len = 0;
  };
  Wire wire[kKinds][kCalls];  // frames to parse (kSignedOdometry: signed; kSign: the unsigned frame to sign)
  mav::SigningKey key;
  // Codec state, as in a link.
  mav::FrameEncoder encoder{1, mav::kMavCompIdVisualInertialOdometry};
  mav::Parser parser;
  mav::Parser signed_parser;
  // The last call's output.
  std::uint8_t out[mav::kMaxFrameBytes];
  std::size_t out_len = 0;
  int kind = 0;
  bool frame_ok = false;
  mav::Odometry got_odometry;
  mav::VisionPositionDelta got_delta;
  mav::DistanceSensor got_distance;
  mav::Heartbeat got_heartbeat;
  mav::NamedValueFloat got_named;
  mav::CommandLong got_command;
};

CannedMavlink::CannedMavlink() : d_(new Impl) {}
CannedMavlink::~CannedMavlink() = default;

Status CannedMavlink::init() {
  Impl& d = *d_;
  Lcg r(0x5eed0331u);
  for (std::uint8_t i = 0; i < 32; ++i) d.key.secret[i] = static_cast<std::uint8_t>(r.u32());
  d.key.link_id = 1;
  d.signed_parser.set_signing_key(d.key);
  mav::FrameEncoder autopilot(1, 1);  // the frames qnav parses come from the autopilot (1, 1)
  for (int k = 0; k < kCalls; ++k) {
    d.odometry[k] = make_odometry(r, k);
    d.delta[k] = make_delta(r, k);
    d.distance[k] = make_distance(r, k);
    d.heartbeat[k] = make_heartbeat(r);
    d.named[k] = make_named(r, k);
    const mav::CommandLong command = make_command(r);
    Result<std::size_t> n[kKinds] = {
        mav::encode(autopilot, d.odometry[k], Span<std::uint8_t>(d.wire[kOdometry][k].bytes)),
        mav::encode(autopilot, d.delta[k], Span<std::uint8_t>(d.wire[kDelta][k].bytes)),
        mav::encode(autopilot, d.distance[k], Span<std::uint8_t>(d.wire[kDistance][k].bytes)),
        mav::encode(autopilot, d.heartbeat[k], Span<std::uint8_t>(d.wire[kHeartbeat][k].bytes)),
        mav::encode(autopilot, d.named[k], Span<std::uint8_t>(d.wire[kNamed][k].bytes)),
        mav::encode(autopilot, command, Span<std::uint8_t>(d.wire[kCommand][k].bytes)),
        mav::encode(autopilot, d.odometry[k], Span<std::uint8_t>(d.wire[kSignedOdometry][k].bytes)),
        mav::encode(d.encoder, d.odometry[k], Span<std::uint8_t>(d.wire[kSign][k].bytes)),
    };
    for (int kind = 0; kind < kKinds; ++kind) {
      if (!n[kind]) return n[kind].status();
      d.wire[kind][k].len = n[kind].value();
    }
    Impl::Wire& s = d.wire[kSignedOdometry][k];
    Result<std::size_t> sl = mav::sign_frame(s.bytes, s.len, sizeof s.bytes, d.key, 1000000ull + 100ull * static_cast<std::uint64_t>(k));
    if (!sl) return sl.status();
    s.len = sl.value();
  }
  return Status::ok();
}

std::uint64_t CannedMavlink::encode(int kind, int k) {
  Impl& d = *d_;
  if (k < 0 || k >= kCalls) return 0;
  d.kind = kind;
  const Span<std::uint8_t> out(d.out);
  Result<std::size_t> n = Status(StatusCode::kInvalidArgument, "not an encode kind");
  switch (kind) {
    case kOdometry: n = mav::encode(d.encoder, d.odometry[k], out); break;
    case kDelta: n = mav::encode(d.encoder, d.delta[k], out); break;
    case kDistance: n = mav::encode(d.encoder, d.distance[k], out); break;
    case kHeartbeat: n = mav::encode(d.encoder, d.heartbeat[k], out); break;
    case kNamed: n = mav::encode(d.encoder, d.named[k], out); break;
    default: break;
  }
  d.out_len = n ? n.value() : 0;
  return d.out_len;
}

std::uint64_t CannedMavlink::sign(int k) {
  Impl& d = *d_;
  if (k < 0 || k >= kCalls) return 0;
  d.kind = kSign;
  const Impl::Wire& w = d.wire[kSign][k];
  std::memcpy(d.out, w.bytes, w.len);  // the frame as the encoder wrote it (a copy, not counted as signing)
  Result<std::size_t> n = mav::sign_frame(d.out, w.len, sizeof d.out, d.key, 2000000ull + 100ull * static_cast<std::uint64_t>(k));
  d.out_len = n ? n.value() : 0;
  return d.out_len;
}

std::uint64_t CannedMavlink::parse(int kind, int k) {
  Impl& d = *d_;
  if (k < 0 || k >= kCalls || kind < 0 || kind >= kSign) return 0;
  d.kind = kind;
  d.frame_ok = false;
  const Impl::Wire& w = d.wire[kind][k];
  mav::Parser& parser = kind == kSignedOdometry ? d.signed_parser : d.parser;
  parser.feed(Span<const std::uint8_t>(w.bytes, w.len), [&](const mav::Frame& f) {
    switch (kind) {
      case kOdometry: d.frame_ok = mav::decode(f, d.got_odometry); break;
      case kDelta: d.frame_ok = mav::decode(f, d.got_delta); break;
      case kDistance: d.frame_ok = mav::decode(f, d.got_distance); break;
      case kHeartbeat: d.frame_ok = mav::decode(f, d.got_heartbeat); break;
      case kNamed: d.frame_ok = mav::decode(f, d.got_named); break;
      case kCommand: d.frame_ok = mav::decode(f, d.got_command); break;
      case kSignedOdometry: d.frame_ok = f.signature_verified && mav::decode(f, d.got_odometry); break;
      default: break;
    }
  });
  return d.frame_ok ? 1 : 0;
}

std::uint64_t CannedMavlink::result(bool parsed) const {
  const Impl& d = *d_;
  Hash h;
  if (!parsed) {
    if (d.out_len == 0) return 0;
    hash_bytes(h, d.out, d.out_len);
    return h.value();
  }
  if (!d.frame_ok) return 0;
  switch (d.kind) {
    case kOdometry:
    case kSignedOdometry: {
      const mav::Odometry& m = d.got_odometry;
      h.add(m.time_usec);
      const float head[] = {m.x, m.y, m.z, m.q[0], m.q[1], m.q[2], m.q[3], m.vx, m.vy, m.vz, m.rollspeed, m.pitchspeed, m.yawspeed};
      hash_floats(h, head, sizeof head / sizeof head[0]);
      hash_floats(h, m.pose_covariance, 21);
      hash_floats(h, m.velocity_covariance, 21);
      h.add(static_cast<std::uint64_t>(m.reset_counter) << 16 | static_cast<std::uint64_t>(m.estimator_type) << 8 |
            static_cast<std::uint8_t>(m.quality));
      break;
    }
    case kDelta: {
      const mav::VisionPositionDelta& m = d.got_delta;
      h.add(m.time_usec);
      h.add(m.time_delta_usec);
      hash_floats(h, m.angle_delta, 3);
      hash_floats(h, m.position_delta, 3);
      h.add(static_cast<double>(m.confidence));
      break;
    }
    case kDistance: {
      const mav::DistanceSensor& m = d.got_distance;
      h.add(static_cast<std::uint64_t>(m.time_boot_ms));
      h.add(static_cast<std::uint64_t>(m.min_distance) << 32 | static_cast<std::uint64_t>(m.max_distance) << 16 | m.current_distance);
      h.add(static_cast<std::uint64_t>(m.type) << 24 | static_cast<std::uint64_t>(m.id) << 16 |
            static_cast<std::uint64_t>(m.orientation) << 8 | m.covariance);
      const float f[] = {m.horizontal_fov, m.vertical_fov, m.quaternion[0], m.quaternion[1], m.quaternion[2], m.quaternion[3]};
      hash_floats(h, f, 6);
      h.add(static_cast<std::uint64_t>(m.signal_quality));
      break;
    }
    case kHeartbeat: {
      const mav::Heartbeat& m = d.got_heartbeat;
      h.add(static_cast<std::uint64_t>(m.custom_mode));
      h.add(static_cast<std::uint64_t>(m.type) << 32 | static_cast<std::uint64_t>(m.autopilot) << 24 |
            static_cast<std::uint64_t>(m.base_mode) << 16 | static_cast<std::uint64_t>(m.system_status) << 8 | m.mavlink_version);
      break;
    }
    case kNamed: {
      const mav::NamedValueFloat& m = d.got_named;
      h.add(static_cast<std::uint64_t>(m.time_boot_ms));
      hash_bytes(h, reinterpret_cast<const std::uint8_t*>(m.name), 10);
      h.add(static_cast<double>(m.value));
      break;
    }
    case kCommand: {
      const mav::CommandLong& m = d.got_command;
      h.add(static_cast<std::uint64_t>(m.target_system) << 32 | static_cast<std::uint64_t>(m.target_component) << 24 |
            static_cast<std::uint64_t>(m.command) << 8 | m.confirmation);
      const float f[] = {m.param1, m.param2, m.param3, m.param4, m.param5, m.param6, m.param7};
      hash_floats(h, f, 7);
      break;
    }
    default: return 0;
  }
  return h.value();
}

}  // namespace qnav::timing
