#include "firmware/qnavd/mavlink_endpoint.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

namespace qnav::daemon {

namespace mav = drivers::mavlink;
namespace qc = drivers::qnavcan;

namespace {
constexpr std::uint8_t kMavResultAccepted = 0, kMavResultDenied = 2, kMavResultUnsupported = 3, kMavResultFailed = 4;
constexpr std::uint8_t kSeverityCritical = 2, kSeverityWarning = 4, kSeverityInfo = 6;
constexpr std::uint8_t kMavStateActive = 4, kMavStateCritical = 5;
constexpr std::uint8_t kDistanceSensorUltrasound = 1, kRotationPitch270 = 25;  // acoustic, looking down
// SET_POSITION_TARGET_LOCAL_NED type_mask: position only (velocity, acceleration, yaw, yaw rate ignored).
constexpr std::uint16_t kTypeMaskPositionOnly = 8 | 16 | 32 | 64 | 128 | 256 | 1024 | 2048;
constexpr std::int64_t kNsPerS = 1000000000;
constexpr std::int64_t kSigningEpochUnixNs = 1420070400LL * kNsPerS;  // 2015-01-01T00:00:00Z
float nanf_() noexcept { return std::numeric_limits<float>::quiet_NaN(); }
}  // namespace

MavlinkEndpoint::MavlinkEndpoint(const DaemonConfig& c, FILE* log, const hal::Clock* utc) noexcept
    : cfg_(c),
      log_(log),
      enc_(static_cast<std::uint8_t>(c.mavlink_system_id), static_cast<std::uint8_t>(c.mavlink_component_id)),
      utc_(utc != nullptr ? utc : &system_utc_) {
  signing_required_ = !c.mavlink_key_file.empty();
  has_key_ = signing_required_ && c.mavlink_key_loaded;
  if (has_key_) {
    std::memcpy(key_.secret, c.mavlink_key_secret, sizeof key_.secret);
    key_.link_id = kSignLinkId;
    for (auto& p : parsers_) p.set_signing_key(key_);
  }
}

std::uint32_t MavlinkEndpoint::signing_rejects() const noexcept {
  std::uint64_t n = 0;
  for (const auto& p : parsers_) {
    const auto& k = p.counters();
    n += k.get(mav::ParserCounter::kBadSignature) + k.get(mav::ParserCounter::kReplay) + k.get(mav::ParserCounter::kStaleTimestamp) +
         k.get(mav::ParserCounter::kSignedRefused) + k.get(mav::ParserCounter::kSigningStreams);
  }
  return static_cast<std::uint32_t>(std::min<std::uint64_t>(n, UINT32_MAX));
}

std::uint64_t MavlinkEndpoint::utc_10us() const noexcept {
  const std::int64_t t = utc_->now_ns() - kSigningEpochUnixNs;
  return t > 0 ? static_cast<std::uint64_t>(t / 10000) : 0;
}

std::uint64_t MavlinkEndpoint::local_timestamp() const noexcept {
  std::uint64_t t = last_sign_ts_;
  for (const auto& p : parsers_) t = std::max(t, p.local_timestamp());
  return t;
}

std::uint64_t MavlinkEndpoint::next_sign_timestamp() noexcept {
  last_sign_ts_ = std::max({utc_10us(), local_timestamp(), last_sign_ts_ + 1});
  return last_sign_ts_;
}

mav::SetGpsGlobalOrigin MavlinkEndpoint::origin_message(const DaemonConfig& c) noexcept {
  mav::SetGpsGlobalOrigin o;
  o.target_system = static_cast<std::uint8_t>(c.mavlink_autopilot_system_id);
  o.latitude = static_cast<std::int32_t>(std::lround(c.mavlink_origin_lat_deg * 1e7));
  o.longitude = static_cast<std::int32_t>(std::lround(c.mavlink_origin_lon_deg * 1e7));
  o.altitude = static_cast<std::int32_t>(std::lround(c.mavlink_origin_alt_m * 1000.0));
  return o;
}

std::uint32_t MavlinkEndpoint::parser_rejects() const noexcept {
  std::uint64_t n = 0;
  for (const auto& p : parsers_) n += p.counters().total();
  return static_cast<std::uint32_t>(std::min<std::uint64_t>(n, UINT32_MAX));
}

std::uint32_t MavlinkEndpoint::rejected() const noexcept {
  return parser_rejects() + counters_.get(MavCounter::kCmdWrongSender) + counters_.get(MavCounter::kCmdBadParam) +
         counters_.get(MavCounter::kBadAttitude) + counters_.get(MavCounter::kCmdUnsigned);
}

std::int64_t MavlinkEndpoint::odometry_grid_after(std::int64_t t) const noexcept {
  const std::int64_t period = static_cast<std::int64_t>(1e9 / cfg_.mavlink_odometry_hz);
  const std::int64_t k = t >= 0 ? t / period : -((-t + period - 1) / period);  // floor(t / period)
  return (k + 1) * period;
}

std::uint32_t MavlinkEndpoint::boot_ms(std::int64_t now_ns) const noexcept {
  return static_cast<std::uint32_t>(std::max<std::int64_t>(0, now_ns - start_ns_) / 1000000);
}

template <typename M>
void MavlinkEndpoint::send(const M& m, SpscRing<MavBytes>& tx) noexcept {
  MavBytes b;
  Result<std::size_t> n = mav::encode(enc_, m, Span<std::uint8_t>(b.data, kMavBytes));
  if (!n) return;  // every message here is in the codec's table and fits
  std::size_t len = n.value();
  if (has_key_) {
    Result<std::size_t> sn = mav::sign_frame(b.data, len, kMavBytes, key_, next_sign_timestamp());
    if (!sn) return;  // a complete unsigned frame with room for the signature (kMavBytes = the largest signed frame)
    len = sn.value();
  }
  b.len = static_cast<std::uint16_t>(len);
  if (!tx.try_push(b)) counters_.increment(MavCounter::kTxQueueFull);
}

void MavlinkEndpoint::status_text(std::uint8_t severity, const char* text, SpscRing<MavBytes>& tx) noexcept {
  mav::StatusText st;
  st.severity = severity;
  mav::set_string(st.text, text);
  send(st, tx);
}

MavInputs MavlinkEndpoint::drain(SpscRing<MavBytes>& rx) noexcept {
  MavInputs in;
  if (has_next_cmd_) {  // the second command of the item drained before
    has_next_cmd_ = false;
    in.mode_cmd = true;
    in.cmd = next_cmd_;
    return in;
  }
  if (has_key_ && rx.front() != nullptr) {  // the parsers' local timestamp: the clock, or the newest seen or sent
    const std::uint64_t now = std::max(utc_10us(), local_timestamp());
    for (auto& p : parsers_) p.set_local_timestamp(now);
  }
  while (!in.mode_cmd) {
    const MavBytes* m = rx.front();
    if (m == nullptr) break;
    const std::uint8_t link = m->link < 3 ? m->link : 2;
    const std::int64_t t = m->arrival_ns;
    // A mode command ends the drain (the worker acts on it first); bytes after it in the same item
    // are parsed now and their frames handled. A command after it goes through the same checks; an
    // accepted mode command is kept for the next drain (an item holds a poll's reads, MavlinkIo), a
    // third in one item is refused as busy.
    parsers_[link].feed(Span<const std::uint8_t>(m->data, m->len), [&](const mav::Frame& f) {
      if (in.mode_cmd && f.msgid == mav::CommandLong::kId) {
        MavInputs later;
        on_frame(f, t, later);
        if (later.mode_cmd) {
          if (has_next_cmd_) {
            counters_.increment(MavCounter::kCmdUnsupported);
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
    mav::CommandLong c;
    mav::decode(f, c);
    if (c.target_system != cfg_.mavlink_system_id || (c.target_component != 0 && c.target_component != cfg_.mavlink_component_id)) {
      counters_.increment(MavCounter::kCmdNotForUs);
      return;
    }
    if (signing_required_ && (!has_key_ || !f.signature_verified)) {
      counters_.increment(MavCounter::kCmdUnsigned);
      if (log_) std::fprintf(log_, "{\"event\":\"mavlink_refused\",\"command\":%u,\"from_system\":%u,\"from_component\":%u,\"why\":\"%s\"}\n",
                             c.command, f.sysid, f.compid, has_key_ ? "not signed with mavlink.key_file" : "signing key not loaded");
      return;  // unauthenticated: no answer, never acted on
    }
    if (!from_ap) {
      counters_.increment(MavCounter::kCmdWrongSender);
      if (log_) std::fprintf(log_, "{\"event\":\"mavlink_refused\",\"command\":%u,\"from_system\":%u,\"from_component\":%u,\"why\":\"not the autopilot\"}\n",
                             c.command, f.sysid, f.compid);
      return;  // a DENIED would tell an intruder it was heard: nothing is sent, the count says it
    }
    cmd_sys_ = f.sysid;
    cmd_comp_ = f.compid;
    if (c.command != kMavCmdSetMode) {
      counters_.increment(MavCounter::kCmdUnsupported);
      defer_ack(c.command, kMavResultUnsupported, f);
      return;
    }
    const float p1 = c.param1, p2 = c.param2;
    const bool ok = std::isfinite(p1) && std::isfinite(p2) && p1 >= 0.0f && p1 <= 5.0f && p1 == std::floor(p1) && p2 >= 0.0f &&
                    p2 <= 65535.0f && p2 == std::floor(p2);
    if (!ok) {
      counters_.increment(MavCounter::kCmdBadParam);
      defer_ack(c.command, kMavResultDenied, f);
      return;
    }
    in.mode_cmd = true;
    in.cmd.mode = static_cast<qc::Mode>(static_cast<int>(p1));
    in.cmd.route_id = static_cast<std::uint16_t>(p2);
    in.cmd.reverse = c.param3 >= 0.5f;
    in.cmd.reset_nav = c.param4 >= 0.5f;
    return;
  }
  if (!from_ap_system) {
    counters_.increment(MavCounter::kForeignSystem);
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
      counters_.increment(MavCounter::kBadAttitude);
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
    counters_.increment(MavCounter::kUnusedMessage);
  }
}

// The autopilot's EKF origin: ours is in place (stop repeating), or it already had another one
// (ArduPilot keeps the first origin it is given until it reboots): reported, not fought over.
void MavlinkEndpoint::on_origin(const mav::Frame& f) noexcept {
  mav::GpsGlobalOrigin g;
  mav::decode(f, g);
  if (!cfg_.mavlink_origin) {
    counters_.increment(MavCounter::kUnusedMessage);
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
  send(make_ack(kMavCmdSetMode, accepted ? kMavResultAccepted : kMavResultFailed, cmd_sys_, cmd_comp_), tx);
  if (accepted) ++commands_accepted_;
  if (!accepted) {
    char text[51];
    std::snprintf(text, sizeof text, "qnav: mode refused: %s", why != nullptr ? why : "?");
    status_text(kSeverityWarning, text, tx);
  }
}

void MavlinkEndpoint::publish(const MavSnapshot& s, SpscRing<MavBytes>& tx) noexcept {
  if (has_pending_ack_) {
    send(pending_ack_, tx);
    has_pending_ack_ = false;
  }
  if (!started_) {
    started_ = true;
    start_ns_ = s.now_ns;
    next_hb_ns_ = next_slow_ns_ = s.now_ns;
    next_odo_ns_ = odometry_grid_after(s.now_ns - 1);
    last_mode_ = s.mode;
    last_faults_ = s.faults;
  }
  const std::int64_t t = s.now_ns;
  if (origin_mismatch_) {
    status_text(kSeverityWarning, "qnav: autopilot EKF origin differs from mavlink.origin", tx);
    origin_mismatch_ = false;
  }
  if (cfg_.mavlink_origin && !origin_acked_ && t >= next_origin_ns_) {
    send(origin_message(cfg_), tx);
    ++origins_sent_;
    next_origin_ns_ = t + kOriginPeriodNs;
  }
  if (s.mode != last_mode_) {
    char text[51];
    std::snprintf(text, sizeof text, "qnav: mode %s", qc::mode_name(s.mode));
    status_text(kSeverityInfo, text, tx);
    last_mode_ = s.mode;
  }
  const std::uint16_t risen = static_cast<std::uint16_t>(s.faults & ~last_faults_);
  if (risen != 0) {
    char text[51];
    std::size_t n = static_cast<std::size_t>(std::snprintf(text, sizeof text, "qnav: fault"));
    for (int b = 0; b < qc::fault::kBitCount && n < sizeof text; ++b)
      if (risen & (1u << b)) n += static_cast<std::size_t>(std::snprintf(text + n, sizeof text - n, " %s", qc::fault::kSignalNames[b] + 5));
    status_text(kSeverityCritical, text, tx);
  }
  last_faults_ = s.faults;
  if (t >= next_hb_ns_) {
    mav::Heartbeat h;
    h.type = mav::kMavTypeOnboardController;
    h.autopilot = mav::kMavAutopilotInvalid;
    h.custom_mode = static_cast<std::uint32_t>(s.mode);
    h.system_status = s.loss ? kMavStateCritical : kMavStateActive;
    send(h, tx);
    next_hb_ns_ = t + kNsPerS;
  }
  const pipeline::NavEstimate* e = s.estimate;
  if (e != nullptr && t >= next_odo_ns_) {
    // On the period's grid, multiples of the period in sample time (the worker wakes on its inputs:
    // a late wake does not shift later ones; the sim's AHRS streams on the same grid); after a gap
    // longer than a period the next grid instant after now (no burst of catch-up messages).
    next_odo_ns_ = odometry_grid_after(std::max(t, next_odo_ns_));
    const std::uint64_t usec = static_cast<std::uint64_t>(std::max<std::int64_t>(0, t) / 1000);
    const Eigen::Quaterniond q(s.world_R_body);
    mav::Odometry o;
    o.time_usec = usec;
    o.frame_id = mav::kMavFrameLocalFrd;
    o.child_frame_id = mav::kMavFrameBodyFrd;
    o.x = static_cast<float>(e->north_m());
    o.y = static_cast<float>(e->east_m());
    o.z = static_cast<float>(e->down_m());
    o.q[0] = static_cast<float>(q.w()), o.q[1] = static_cast<float>(q.x()), o.q[2] = static_cast<float>(q.y()), o.q[3] = static_cast<float>(q.z());
    const bool vel = s.have_velocity && !s.loss;
    o.vx = vel ? static_cast<float>(s.vx_mps) : nanf_();
    o.vy = vel ? static_cast<float>(s.vy_mps) : nanf_();
    o.vz = vel ? 0.0f : nanf_();
    o.rollspeed = o.pitchspeed = o.yawspeed = nanf_();
    o.pose_covariance[0] = nanf_();      // unknown (MAVLink: NaN in the first element)
    o.velocity_covariance[0] = nanf_();
    o.reset_counter = e->reset_counter();
    o.estimator_type = s.mode == qc::Mode::kVo ? mav::kMavEstimatorTypeVio : mav::kMavEstimatorTypeVision;
    // quality: -1 failed (a sensor the estimate needs is lost); in Repeat with a route fix the
    // localiser's confidence (at least 1); dead reckoning alone: 50 (good short-term, drifting).
    int quality = 50;
    if (s.in_repeat && s.route_fix) quality = std::max(1, std::min(100, static_cast<int>(std::lround(s.confidence_pct))));
    if (s.loss || !s.have_attitude) quality = -1;
    o.quality = static_cast<std::int8_t>(quality);
    send(o, tx);
    ++odometry_sent_;
    // VISION_POSITION_DELTA: the motion since the previous one, in the body frame of now; never
    // across a loss or a jump (rebased: the next one starts here).
    const Vec3d rpy = s.world_R_body.eulerAngles(2, 1, 0);  // yaw, pitch, roll
    const bool can_delta = !s.loss && s.have_attitude && delta_base_ && e->reset_counter() == delta_reset_ && t > delta_ns_;
    if (can_delta) {
      const Vec3d d_world(e->north_m() - delta_n_, e->east_m() - delta_e_, e->down_m() - delta_d_);
      const Vec3d d_body = s.world_R_body.transpose() * d_world;
      const auto wrap = [](double a) { return std::atan2(std::sin(a), std::cos(a)); };
      mav::VisionPositionDelta d;
      d.time_usec = usec;
      d.time_delta_usec = static_cast<std::uint64_t>((t - delta_ns_) / 1000);
      d.angle_delta[0] = static_cast<float>(wrap(rpy[2] - delta_roll_));
      d.angle_delta[1] = static_cast<float>(wrap(rpy[1] - delta_pitch_));
      d.angle_delta[2] = static_cast<float>(wrap(rpy[0] - delta_yaw_));
      d.position_delta[0] = static_cast<float>(d_body.x());
      d.position_delta[1] = static_cast<float>(d_body.y());
      d.position_delta[2] = static_cast<float>(d_body.z());
      d.confidence = static_cast<float>(quality);
      send(d, tx);
    }
    delta_base_ = !s.loss && s.have_attitude;
    delta_ns_ = t;
    delta_n_ = e->north_m(), delta_e_ = e->east_m(), delta_d_ = e->down_m();
    delta_yaw_ = rpy[0], delta_pitch_ = rpy[1], delta_roll_ = rpy[2];
    delta_reset_ = e->reset_counter();
    if (s.altitude_m >= 0.0 && !s.loss) {
      mav::DistanceSensor ds;
      ds.time_boot_ms = boot_ms(t);
      ds.min_distance = 10;
      ds.max_distance = 10000;
      ds.current_distance = static_cast<std::uint16_t>(std::min(65535.0, s.altitude_m * 100.0 + 0.5));
      ds.type = kDistanceSensorUltrasound;
      ds.orientation = kRotationPitch270;
      ds.covariance = 255;  // unknown
      send(ds, tx);
    }
  }
  if (t >= next_slow_ns_) {
    next_slow_ns_ = t + kNsPerS;
    log_signing(t);
    if (s.in_repeat) {
      const auto nvf = [&](const char* name, double v) {
        mav::NamedValueFloat n;
        n.time_boot_ms = boot_ms(t);
        mav::set_string(n.name, name);
        n.value = static_cast<float>(v);
        send(n, tx);
      };
      nvf("xtrack_m", s.guidance_valid ? s.cross_track_m : std::numeric_limits<double>::quiet_NaN());
      nvf("xtrack_sig", s.guidance_valid ? s.cross_track_sigma_m : std::numeric_limits<double>::quiet_NaN());
      nvf("side", s.side);
      nvf("node", s.node);
    }
    // GUIDED (opt-in): the look-ahead waypoint, route frame = the published frame after a route fix.
    if (cfg_.mavlink_guided && s.in_repeat && s.route_fix && s.guidance_valid && !s.loss && autopilot_guided_armed() && e != nullptr) {
      mav::SetPositionTargetLocalNed p;
      p.time_boot_ms = boot_ms(t);
      p.target_system = static_cast<std::uint8_t>(cfg_.mavlink_autopilot_system_id);
      p.target_component = static_cast<std::uint8_t>(cfg_.mavlink_autopilot_component_id);
      p.coordinate_frame = mav::kMavFrameLocalNed;
      p.type_mask = kTypeMaskPositionOnly;
      p.x = static_cast<float>(s.waypoint_ne.x());
      p.y = static_cast<float>(s.waypoint_ne.y());
      p.z = static_cast<float>(e->down_m());
      send(p, tx);
      ++targets_sent_;
    }
  }
}

// Signing refusals, once a second at most and only when they changed (the health line's mavlink
// event has the total in parser_rejects; this line says which rule refused).
void MavlinkEndpoint::log_signing(std::int64_t t) noexcept {
  if (!signing_required_ && signing_rejects() == 0) return;
  const std::uint32_t n = signing_rejects() + counters_.get(MavCounter::kCmdUnsigned);
  if (n == signing_logged_ || log_ == nullptr) return;
  signing_logged_ = n;
  std::uint32_t k[static_cast<int>(mav::ParserCounter::kCount)] = {};
  for (const auto& p : parsers_)
    for (int i = 0; i < static_cast<int>(mav::ParserCounter::kCount); ++i) k[i] += p.counters().get(static_cast<mav::ParserCounter>(i));
  const auto at = [&k](mav::ParserCounter c) { return k[static_cast<int>(c)]; };
  std::fprintf(log_,
               "{\"event\":\"mavlink_signing\",\"t_s\":%.1f,\"signing\":%s,\"cmd_unsigned\":%u,\"bad_signature\":%u,\"replay\":%u,"
               "\"stale_timestamp\":%u,\"signed_refused\":%u,\"signing_streams\":%u}\n",
               static_cast<double>(t - start_ns_) * 1e-9, has_key_ ? "true" : "false", counters_.get(MavCounter::kCmdUnsigned),
               at(mav::ParserCounter::kBadSignature), at(mav::ParserCounter::kReplay), at(mav::ParserCounter::kStaleTimestamp),
               at(mav::ParserCounter::kSignedRefused), at(mav::ParserCounter::kSigningStreams));
}

}  // namespace qnav::daemon
