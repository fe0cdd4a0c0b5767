// qnav's side of the node-mavlink cross-check (mavlink_peer.mjs drives it):
//   mavlink_peer_tool gen COUNT SEED FRAMES.bin EXPECTED.jsonl [KEY_HEX]
//     COUNT messages of every typed kind with random values (random payload bytes decoded into the
//     typed struct: every bit pattern, NaN and infinities included; strings printable), encoded with
//     FrameEncoder (every 7th signed when KEY_HEX is given); their values as JSON lines.
//   mavlink_peer_tool decode FRAMES.bin OUT.jsonl [KEY_HEX]
//     FRAMES.bin through the Parser (in 1..97-byte pieces); every frame's values as JSON lines, then
//     one line with the parser's counters.
// JSON: {"msgid":N,"sysid":N,"compid":N,"seq":N,"signed":B,"verified":B,"fields":{XML name: value}};
// floats as %.9g (exact for a float) or "NaN"/"Infinity"/"-Infinity", uint64 as decimal strings.
// Test code: allocates and uses stdio freely.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "drivers/mavlink/frame.hpp"
#include "drivers/mavlink/messages.hpp"
#include "drivers/mavlink/parser.hpp"

using namespace qnav;
using namespace qnav::drivers::mavlink;

namespace {

class Json {
 public:
  void key(const char* k) {
    if (!first_) s_ += ',';
    first_ = false;
    s_ += '"';
    s_ += k;
    s_ += "\":";
  }
  void num(const char* k, long long v) {
    key(k);
    s_ += std::to_string(v);
  }
  void u64(const char* k, std::uint64_t v) {
    key(k);
    s_ += '"' + std::to_string(v) + '"';
  }
  static std::string f(float v) {
    if (std::isnan(v)) return "\"NaN\"";
    if (std::isinf(v)) return v > 0 ? "\"Infinity\"" : "\"-Infinity\"";
    char b[32];
    std::snprintf(b, sizeof b, "%.9g", static_cast<double>(v));
    return b;
  }
  void flt(const char* k, float v) {
    key(k);
    s_ += f(v);
  }
  void flts(const char* k, const float* v, std::size_t n) {
    key(k);
    s_ += '[';
    for (std::size_t i = 0; i < n; ++i) s_ += (i ? "," : "") + f(v[i]);
    s_ += ']';
  }
  void str(const char* k, const char* v) {
    key(k);
    s_ += '"';
    for (const char* p = v; *p; ++p) {
      if (*p == '"' || *p == '\\') s_ += '\\';
      s_ += *p;
    }
    s_ += '"';
  }
  std::string done() { return s_; }

 private:
  std::string s_;
  bool first_ = true;
};

std::string fields(const Heartbeat& m) {
  Json j;
  j.num("type", m.type); j.num("autopilot", m.autopilot); j.num("base_mode", m.base_mode);
  j.num("custom_mode", m.custom_mode); j.num("system_status", m.system_status); j.num("mavlink_version", m.mavlink_version);
  return j.done();
}
std::string fields(const SystemTime& m) {
  Json j;
  j.u64("time_unix_usec", m.time_unix_usec); j.num("time_boot_ms", m.time_boot_ms);
  return j.done();
}
std::string fields(const Attitude& m) {
  Json j;
  j.num("time_boot_ms", m.time_boot_ms); j.flt("roll", m.roll); j.flt("pitch", m.pitch); j.flt("yaw", m.yaw);
  j.flt("rollspeed", m.rollspeed); j.flt("pitchspeed", m.pitchspeed); j.flt("yawspeed", m.yawspeed);
  return j.done();
}
std::string fields(const LocalPositionNed& m) {
  Json j;
  j.num("time_boot_ms", m.time_boot_ms); j.flt("x", m.x); j.flt("y", m.y); j.flt("z", m.z);
  j.flt("vx", m.vx); j.flt("vy", m.vy); j.flt("vz", m.vz);
  return j.done();
}
std::string fields(const SetGpsGlobalOrigin& m) {
  Json j;
  j.num("target_system", m.target_system); j.num("latitude", m.latitude); j.num("longitude", m.longitude);
  j.num("altitude", m.altitude); j.u64("time_usec", m.time_usec);
  return j.done();
}
std::string fields(const GpsGlobalOrigin& m) {
  Json j;
  j.num("latitude", m.latitude); j.num("longitude", m.longitude); j.num("altitude", m.altitude); j.u64("time_usec", m.time_usec);
  return j.done();
}
std::string fields(const CommandLong& m) {
  Json j;
  j.num("target_system", m.target_system); j.num("target_component", m.target_component); j.num("command", m.command);
  j.num("confirmation", m.confirmation); j.flt("param1", m.param1); j.flt("param2", m.param2); j.flt("param3", m.param3);
  j.flt("param4", m.param4); j.flt("param5", m.param5); j.flt("param6", m.param6); j.flt("param7", m.param7);
  return j.done();
}
std::string fields(const CommandAck& m) {
  Json j;
  j.num("command", m.command); j.num("result", m.result); j.num("progress", m.progress);
  j.num("result_param2", m.result_param2); j.num("target_system", m.target_system); j.num("target_component", m.target_component);
  return j.done();
}
std::string fields(const SetPositionTargetLocalNed& m) {
  Json j;
  j.num("time_boot_ms", m.time_boot_ms); j.num("target_system", m.target_system); j.num("target_component", m.target_component);
  j.num("coordinate_frame", m.coordinate_frame); j.num("type_mask", m.type_mask); j.flt("x", m.x); j.flt("y", m.y);
  j.flt("z", m.z); j.flt("vx", m.vx); j.flt("vy", m.vy); j.flt("vz", m.vz); j.flt("afx", m.afx); j.flt("afy", m.afy);
  j.flt("afz", m.afz); j.flt("yaw", m.yaw); j.flt("yaw_rate", m.yaw_rate);
  return j.done();
}
std::string fields(const VisionPositionEstimate& m) {
  Json j;
  j.u64("usec", m.usec); j.flt("x", m.x); j.flt("y", m.y); j.flt("z", m.z); j.flt("roll", m.roll);
  j.flt("pitch", m.pitch); j.flt("yaw", m.yaw); j.flts("covariance", m.covariance, 21); j.num("reset_counter", m.reset_counter);
  return j.done();
}
std::string fields(const VisionSpeedEstimate& m) {
  Json j;
  j.u64("usec", m.usec); j.flt("x", m.x); j.flt("y", m.y); j.flt("z", m.z); j.flts("covariance", m.covariance, 9);
  j.num("reset_counter", m.reset_counter);
  return j.done();
}
std::string fields(const DistanceSensor& m) {
  Json j;
  j.num("time_boot_ms", m.time_boot_ms); j.num("min_distance", m.min_distance); j.num("max_distance", m.max_distance);
  j.num("current_distance", m.current_distance); j.num("type", m.type); j.num("id", m.id); j.num("orientation", m.orientation);
  j.num("covariance", m.covariance); j.flt("horizontal_fov", m.horizontal_fov); j.flt("vertical_fov", m.vertical_fov);
  j.flts("quaternion", m.quaternion, 4); j.num("signal_quality", m.signal_quality);
  return j.done();
}
std::string fields(const EkfStatusReport& m) {
  Json j;
  j.num("flags", m.flags); j.flt("velocity_variance", m.velocity_variance); j.flt("pos_horiz_variance", m.pos_horiz_variance);
  j.flt("pos_vert_variance", m.pos_vert_variance); j.flt("compass_variance", m.compass_variance);
  j.flt("terrain_alt_variance", m.terrain_alt_variance); j.flt("airspeed_variance", m.airspeed_variance);
  return j.done();
}
std::string fields(const NamedValueFloat& m) {
  Json j;
  j.num("time_boot_ms", m.time_boot_ms); j.str("name", m.name); j.flt("value", m.value);
  return j.done();
}
std::string fields(const StatusText& m) {
  Json j;
  j.num("severity", m.severity); j.str("text", m.text); j.num("id", m.id); j.num("chunk_seq", m.chunk_seq);
  return j.done();
}
std::string fields(const Odometry& m) {
  Json j;
  j.u64("time_usec", m.time_usec); j.num("frame_id", m.frame_id); j.num("child_frame_id", m.child_frame_id);
  j.flt("x", m.x); j.flt("y", m.y); j.flt("z", m.z); j.flts("q", m.q, 4); j.flt("vx", m.vx); j.flt("vy", m.vy);
  j.flt("vz", m.vz); j.flt("rollspeed", m.rollspeed); j.flt("pitchspeed", m.pitchspeed); j.flt("yawspeed", m.yawspeed);
  j.flts("pose_covariance", m.pose_covariance, 21); j.flts("velocity_covariance", m.velocity_covariance, 21);
  j.num("reset_counter", m.reset_counter); j.num("estimator_type", m.estimator_type); j.num("quality", m.quality);
  return j.done();
}
std::string fields(const VisionPositionDelta& m) {
  Json j;
  j.u64("time_usec", m.time_usec); j.u64("time_delta_usec", m.time_delta_usec); j.flts("angle_delta", m.angle_delta, 3);
  j.flts("position_delta", m.position_delta, 3); j.flt("confidence", m.confidence);
  return j.done();
}

// Typed dispatch: decode a full payload and call fn(typed message).
template <typename Fn>
bool with_typed(std::uint32_t msgid, const std::uint8_t* payload, Fn&& fn) {
  switch (msgid) {
#define QNAV_CASE(T) case T::kId: { T m; decode_payload(payload, m); fn(m); return true; }
    QNAV_CASE(Heartbeat) QNAV_CASE(SystemTime) QNAV_CASE(Attitude) QNAV_CASE(LocalPositionNed)
    QNAV_CASE(SetGpsGlobalOrigin) QNAV_CASE(GpsGlobalOrigin) QNAV_CASE(CommandLong) QNAV_CASE(CommandAck) QNAV_CASE(SetPositionTargetLocalNed)
    QNAV_CASE(VisionPositionEstimate) QNAV_CASE(VisionSpeedEstimate) QNAV_CASE(DistanceSensor)
    QNAV_CASE(EkfStatusReport) QNAV_CASE(NamedValueFloat) QNAV_CASE(StatusText) QNAV_CASE(Odometry)
    QNAV_CASE(VisionPositionDelta)
#undef QNAV_CASE
    default: return false;
  }
}

std::string line(const Frame& f, const std::string& flds) {
  char head[160];
  std::snprintf(head, sizeof head, "{\"msgid\":%u,\"sysid\":%u,\"compid\":%u,\"seq\":%u,\"version\":%u,\"signed\":%s,\"verified\":%s,\"fields\":{",
                static_cast<unsigned>(f.msgid), f.sysid, f.compid, f.seq, f.version, f.is_signed ? "true" : "false",
                f.signature_verified ? "true" : "false");
  return std::string(head) + flds + "}}\n";
}

bool parse_key(const char* hex, SigningKey& key) {
  if (hex == nullptr || std::strlen(hex) != 64) return false;
  for (int i = 0; i < 32; ++i) {
    char b[3] = {hex[2 * i], hex[2 * i + 1], 0};
    key.secret[i] = static_cast<std::uint8_t>(std::strtoul(b, nullptr, 16));
  }
  return true;
}

struct Lcg {
  std::uint64_t s;
  std::uint32_t next() {
    s = s * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<std::uint32_t>(s >> 33);
  }
};

int gen(int count, std::uint64_t seed, const char* frames_path, const char* json_path, const char* key_hex) {
  SigningKey key;
  const bool sign = key_hex != nullptr && parse_key(key_hex, key);
  if (key_hex != nullptr && !sign) return std::fprintf(stderr, "bad key\n"), 2;
  key.link_id = 7;
  FILE* fb = std::fopen(frames_path, "wb");
  FILE* fj = std::fopen(json_path, "w");
  if (fb == nullptr || fj == nullptr) return std::fprintf(stderr, "cannot write outputs\n"), 2;
  Lcg rng{seed};
  const Span<const MessageInfo> known = known_messages();
  std::uint64_t ts = 100000;
  for (int i = 0; i < count; ++i) {
    const MessageInfo& info = known[rng.next() % known.size()];
    FrameEncoder enc(static_cast<std::uint8_t>(1 + rng.next() % 254), static_cast<std::uint8_t>(rng.next() % 256));
    for (std::uint32_t k = rng.next() % 256; k > 0; --k) {  // a random sequence number
      std::uint8_t scratch[kMaxFrameBytes];
      (void)encode(enc, Heartbeat{}, Span<std::uint8_t>(scratch));
    }
    std::uint8_t payload[kMaxPayload] = {};
    for (std::size_t b = 0; b < info.full_len; ++b) payload[b] = static_cast<std::uint8_t>(rng.next());
    if (rng.next() % 4 == 0) {  // trailing zeros: truncation
      for (std::size_t b = rng.next() % info.full_len; b < info.full_len; ++b) payload[b] = 0;
    }
    std::size_t from = 0, n = 0;
    if (info.id == NamedValueFloat::kId) from = 8, n = 10;
    if (info.id == StatusText::kId) from = 1, n = 50;
    const std::size_t slen = n ? rng.next() % (n + 1) : 0;
    for (std::size_t b = 0; b < n; ++b) payload[from + b] = b < slen ? static_cast<std::uint8_t>(0x20 + rng.next() % 95) : 0;
    std::uint8_t frame[kMaxFrameBytes];
    std::size_t frame_len = 0;
    std::string flds;
    with_typed(info.id, payload, [&](const auto& m) {
      flds = fields(m);
      auto r = encode(enc, m, Span<std::uint8_t>(frame));
      frame_len = r.is_ok() ? r.value() : 0;
    });
    if (frame_len == 0) return std::fprintf(stderr, "encode failed\n"), 1;
    Frame meta;
    meta.msgid = info.id;
    meta.sysid = frame[5];
    meta.compid = frame[6];
    meta.seq = frame[4];
    if (sign && i % 7 == 3) {
      auto s = sign_frame(frame, frame_len, sizeof frame, key, ts++);
      if (!s.is_ok()) return std::fprintf(stderr, "sign failed\n"), 1;
      frame_len = s.value();
      meta.is_signed = meta.signature_verified = true;
    }
    std::fwrite(frame, 1, frame_len, fb);
    const std::string l = line(meta, flds);
    std::fwrite(l.data(), 1, l.size(), fj);
  }
  std::fclose(fb);
  std::fclose(fj);
  return 0;
}

int decode_file(const char* frames_path, const char* json_path, const char* key_hex) {
  FILE* fb = std::fopen(frames_path, "rb");
  FILE* fj = std::fopen(json_path, "w");
  if (fb == nullptr || fj == nullptr) return std::fprintf(stderr, "cannot open files\n"), 2;
  std::vector<std::uint8_t> bytes;
  std::uint8_t chunk[4096];
  for (std::size_t n; (n = std::fread(chunk, 1, sizeof chunk, fb)) > 0;) bytes.insert(bytes.end(), chunk, chunk + n);
  std::fclose(fb);
  Parser parser;
  SigningKey key;
  if (key_hex != nullptr) {
    if (!parse_key(key_hex, key)) return std::fprintf(stderr, "bad key\n"), 2;
    parser.set_signing_key(key);
  }
  std::size_t at = 0, step = 1;
  while (at < bytes.size()) {
    std::size_t n = step;
    step = step % 97 + 1;
    if (n > bytes.size() - at) n = bytes.size() - at;
    parser.feed(Span<const std::uint8_t>(bytes.data() + at, n), [&](const Frame& f) {
      with_typed(f.msgid, f.payload, [&](const auto& m) {
        const std::string l = line(f, fields(m));
        std::fwrite(l.data(), 1, l.size(), fj);
      });
    });
    at += n;
  }
  std::string c = "{\"counters\":{";
  for (std::size_t i = 0; i < parser.counters().size(); ++i) {
    c += (i ? ",\"" : "\"") + std::string(parser.counters().name_at(i)) + "\":" + std::to_string(parser.counters().count_at(i));
  }
  c += "},\"buffered\":" + std::to_string(parser.buffered_bytes()) + "}\n";
  std::fwrite(c.data(), 1, c.size(), fj);
  std::fclose(fj);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc >= 6 && std::strcmp(argv[1], "gen") == 0)
    return gen(std::atoi(argv[2]), std::strtoull(argv[3], nullptr, 10), argv[4], argv[5], argc > 6 ? argv[6] : nullptr);
  if (argc >= 4 && std::strcmp(argv[1], "decode") == 0) return decode_file(argv[2], argv[3], argc > 4 ? argv[4] : nullptr);
  std::fprintf(stderr, "usage: mavlink_peer_tool gen COUNT SEED FRAMES JSONL [KEY_HEX] | decode FRAMES JSONL [KEY_HEX]\n");
  return 2;
}
