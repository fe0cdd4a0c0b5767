#include "firmware/qnavd/mavlink_endpoint.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace qnav::daemon {

namespace mav = drivers::mavlink;
namespace qc = drivers::qnavcan;

namespace {
constexpr std::uint8_t kMavResultAccepted = 0, kMavResultDenied = 2, kMavResultUnsupported = 3, kMavResultFailed = 4;
constexpr std::uint8_t kSeverityWarning = 4;
}  // namespace

MavlinkEndpoint::MavlinkEndpoint(const DaemonConfig& c, FILE* log, const hal::Clock* utc) noexcept
    : cfg_(c), log_(log), wire_(c, utc), streams_(c, wire_) {}

mav::SetGpsGlobalOrigin MavlinkEndpoint::origin_message(const DaemonConfig& c) noexcept {
  mav::SetGpsGlobalOrigin o;
  o.target_system = static_cast<std::uint8_t>(c.mavlink_autopilot_system_id);
  o.latitude = static_cast<std::int32_t>(std::lround(c.mavlink_origin_lat_deg * 1e7));
  o.longitude = static_cast<std::int32_t>(std::lround(c.mavlink_origin_lon_deg * 1e7));
  o.altitude = static_cast<std::int32_t>(std::lround(c.mavlink_origin_alt_m * 1000.0));
  return o;
}

std::uint32_t MavlinkEndpoint::rejected() const noexcept {
  return parser_rejects() + wire_.counters().get(MavCounter::kCmdWrongSender) + wire_.counters().get(MavCounter::kCmdBadParam) +
         wire_.counters().get(MavCounter::kBadAttitude) + wire_.counters().get(MavCounter::kCmdUnsigned);
}

MavInputs MavlinkEndpoint::drain(SpscRing<MavBytes>& rx) noexcept {
  MavInputs in;
  if (has_next_cmd_) {  // the second command of the item drained before
    has_next_cmd_ = false;
    in.mode_cmd = true;
    in.cmd = next_cmd_;
    return in;
  }
  if (wire_.has_key() && rx.front() != nullptr) wire_.refresh_local_timestamp();  // the clock, or the newest seen or sent
  while (!in.mode_cmd) {
    const MavBytes* m = rx.front();
    if (m == nullptr) break;
    const std::int64_t t = m->arrival_ns;
    // A mode command ends the drain (the worker acts on it first); bytes after it in the same item
    // are parsed now and their frames handled. A command after it goes through the same checks; an
    // accepted mode command is kept for the next drain (an item holds a poll's reads, MavlinkIo), a
    // third in one item is refused as busy.
    wire_.parser(m->link).feed(Span<const std::uint8_t>(m->data, m->len), [&](const mav::Frame& f) {
      if (in.mode_cmd && f.msgid == mav::CommandLong::kId) {
        MavInputs later;
        on_frame(f, t, later);
        if (later.mode_cmd) {
          if (has_next_cmd_) {
            wire_.counters().increment(MavCounter::kCmdUnsupported);
          } else {
            next_cmd_ = later.cmd;
            has_next_cmd_ = true;
          }
        }
        return;
      }
      on_frame(f, t, in);
    });
    MavBytes drop;
    (void)rx.try_pop(drop);
  }
  return in;
}

void MavlinkEndpoint::on_frame(const mav::Frame& f, std::int64_t arrival_ns, MavInputs& in) noexcept {
  ++frames_rx_;
  const bool from_ap_system = f.sysid == cfg_.mavlink_autopilot_system_id;
  const bool from_ap = from_ap_system && f.compid == cfg_.mavlink_autopilot_component_id;
  if (f.msgid == mav::CommandLong::kId) {
    on_command(f, from_ap, in);
    return;
  }
  if (!from_ap_system) {
    wire_.counters().increment(MavCounter::kForeignSystem);
    return;
  }
  if (f.msgid == mav::Heartbeat::kId) {
    if (f.compid != cfg_.mavlink_autopilot_component_id) return;  // other components of the vehicle (cameras, gimbals)
    mav::Heartbeat h;
    mav::decode(f, h);
    if (ap_seen_ && arrival_ns - ap_last_hb_ns_ > kApSilentNs) origin_acked_ = false;  // it rebooted: its EKF has no origin
    ap_last_hb_ns_ = arrival_ns;
    ap_seen_ = true;
    ap_custom_mode_ = h.custom_mode;
    ap_armed_ = (h.base_mode & mav::kMavModeFlagSafetyArmed) != 0;
  } else if (f.msgid == mav::Attitude::kId && from_ap) {
    mav::Attitude a;
    mav::decode(f, a);
    if (!std::isfinite(a.roll) || !std::isfinite(a.pitch) || !std::isfinite(a.yaw)) {
      wire_.counters().increment(MavCounter::kBadAttitude);
      return;
    }
    in.attitude = true;
    in.attitude_ns = arrival_ns;
    in.roll_rad = static_cast<double>(a.roll);
    in.pitch_rad = static_cast<double>(a.pitch);
    in.yaw_rad = static_cast<double>(a.yaw);
  } else if (f.msgid == mav::GpsGlobalOrigin::kId && from_ap) {
    on_origin(f);
  } else if (f.msgid == mav::SystemTime::kId && from_ap) {
    mav::SystemTime st;
    mav::decode(f, st);
    ap_unix_usec_ = st.time_unix_usec;
  } else {
    wire_.counters().increment(MavCounter::kUnusedMessage);
  }
}

// A COMMAND_LONG: for us, signed when it must be, from the autopilot, a mode command with good parameters.
void MavlinkEndpoint::on_command(const mav::Frame& f, bool from_ap, MavInputs& in) noexcept {
  mav::CommandLong c;
  mav::decode(f, c);
  if (c.target_system != cfg_.mavlink_system_id || (c.target_component != 0 && c.target_component != cfg_.mavlink_component_id)) {
    wire_.counters().increment(MavCounter::kCmdNotForUs);
    return;
  }
  if (wire_.signing_required() && (!wire_.has_key() || !f.signature_verified)) {
    wire_.counters().increment(MavCounter::kCmdUnsigned);
    if (log_) std::fprintf(log_, "{\"event\":\"mavlink_refused\",\"command\":%u,\"from_system\":%u,\"from_component\":%u,\"why\":\"%s\"}\n",
                           c.command, f.sysid, f.compid, wire_.has_key() ? "not signed with mavlink.key_file" : "signing key not loaded");
    return;  // unauthenticated: no answer, never acted on
  }
  if (!from_ap) {
    wire_.counters().increment(MavCounter::kCmdWrongSender);
    if (log_) std::fprintf(log_, "{\"event\":\"mavlink_refused\",\"command\":%u,\"from_system\":%u,\"from_component\":%u,\"why\":\"not the autopilot\"}\n",
                           c.command, f.sysid, f.compid);
    return;  // a DENIED would tell an intruder it was heard: nothing is sent, the count says it
  }
  cmd_sys_ = f.sysid;
  cmd_comp_ = f.compid;
  if (c.command != kMavCmdSetMode) {
    wire_.counters().increment(MavCounter::kCmdUnsupported);
    defer_ack(c.command, kMavResultUnsupported, f);
    return;
  }
  const float p1 = c.param1, p2 = c.param2;
  const bool ok = std::isfinite(p1) && std::isfinite(p2) && p1 >= 0.0f && p1 <= 5.0f && p1 == std::floor(p1) && p2 >= 0.0f &&
                  p2 <= 65535.0f && p2 == std::floor(p2);
  if (!ok) {
    wire_.counters().increment(MavCounter::kCmdBadParam);
    defer_ack(c.command, kMavResultDenied, f);
    return;
  }
  in.mode_cmd = true;
  in.cmd.mode = static_cast<qc::Mode>(static_cast<int>(p1));
  in.cmd.route_id = static_cast<std::uint16_t>(p2);
  in.cmd.reverse = c.param3 >= 0.5f;
  in.cmd.reset_nav = c.param4 >= 0.5f;
}

// The autopilot's EKF origin: ours is in place (stop repeating), or it already had another one
// (ArduPilot keeps the first origin it is given until it reboots): reported, not fought over.
void MavlinkEndpoint::on_origin(const mav::Frame& f) noexcept {
  mav::GpsGlobalOrigin g;
  mav::decode(f, g);
  if (!cfg_.mavlink_origin) {
    wire_.counters().increment(MavCounter::kUnusedMessage);
    return;
  }
  const bool was = origin_acked_;
  origin_acked_ = true;
  if (was) return;
  const mav::SetGpsGlobalOrigin want = origin_message(cfg_);
  // Within 1e-7 deg horizontally and 1 cm vertically (ArduPilot keeps altitude in cm).
  const bool same = std::abs(static_cast<std::int64_t>(g.latitude) - want.latitude) <= 1 &&
                    std::abs(static_cast<std::int64_t>(g.longitude) - want.longitude) <= 1 &&
                    std::abs(static_cast<std::int64_t>(g.altitude) - want.altitude) <= 10;
  if (!same) origin_mismatch_ = true;
  if (log_)
    std::fprintf(log_, "{\"event\":\"mavlink_origin\",\"lat_e7\":%d,\"lon_e7\":%d,\"alt_mm\":%d,\"matches_config\":%s,\"sent\":%u}\n",
                 g.latitude, g.longitude, g.altitude, same ? "true" : "false", origins_sent_);
}

mav::CommandAck MavlinkEndpoint::make_ack(std::uint16_t command, std::uint8_t result, std::uint8_t sys, std::uint8_t comp) noexcept {
  mav::CommandAck a;
  a.command = command;
  a.result = result;
  a.target_system = sys;
  a.target_component = comp;
  return a;
}

void MavlinkEndpoint::defer_ack(std::uint16_t command, std::uint8_t result, const mav::Frame& f) noexcept {
  pending_ack_ = make_ack(command, result, f.sysid, f.compid);
  has_pending_ack_ = true;
}

void MavlinkEndpoint::ack(bool accepted, const char* why, SpscRing<MavBytes>& tx) noexcept {
  wire_.send(make_ack(kMavCmdSetMode, accepted ? kMavResultAccepted : kMavResultFailed, cmd_sys_, cmd_comp_), tx);
  if (accepted) ++commands_accepted_;
  if (!accepted) {
    char text[51];
    std::snprintf(text, sizeof text, "qnav: mode refused: %s", why != nullptr ? why : "?");
    wire_.status_text(kSeverityWarning, text, tx);
  }
}

void MavlinkEndpoint::publish(const MavSnapshot& s, SpscRing<MavBytes>& tx) noexcept {
  if (has_pending_ack_) {
    wire_.send(pending_ack_, tx);
    has_pending_ack_ = false;
  }
  const std::int64_t t = s.now_ns;
  if (origin_mismatch_) {
    wire_.status_text(kSeverityWarning, "qnav: autopilot EKF origin differs from mavlink.origin", tx);
    origin_mismatch_ = false;
  }
  if (cfg_.mavlink_origin && !origin_acked_ && t >= next_origin_ns_) {
    wire_.send(origin_message(cfg_), tx);
    ++origins_sent_;
    next_origin_ns_ = t + kOriginPeriodNs;
  }
  if (streams_.publish(s, autopilot_guided_armed(), tx)) log_signing(t);  // its 1 Hz slot
}

// Signing refusals, once a second at most and only when they changed (the health line's mavlink
// event has the total in parser_rejects; this line says which rule refused).
void MavlinkEndpoint::log_signing(std::int64_t t) noexcept {
  if (!wire_.signing_required() && wire_.signing_rejects() == 0) return;
  const std::uint32_t n = wire_.signing_rejects() + wire_.counters().get(MavCounter::kCmdUnsigned);
  if (n == signing_logged_ || log_ == nullptr) return;
  signing_logged_ = n;
  const auto at = [this](mav::ParserCounter c) { return wire_.parser_count(c); };
  std::fprintf(log_,
               "{\"event\":\"mavlink_signing\",\"t_s\":%.1f,\"signing\":%s,\"cmd_unsigned\":%u,\"bad_signature\":%u,\"replay\":%u,"
               "\"stale_timestamp\":%u,\"signed_refused\":%u,\"signing_streams\":%u}\n",
               static_cast<double>(t - streams_.start_ns()) * 1e-9, wire_.has_key() ? "true" : "false", wire_.counters().get(MavCounter::kCmdUnsigned),
               at(mav::ParserCounter::kBadSignature), at(mav::ParserCounter::kReplay), at(mav::ParserCounter::kStaleTimestamp),
               at(mav::ParserCounter::kSignedRefused), at(mav::ParserCounter::kSigningStreams));
}

}  // namespace qnav::daemon
