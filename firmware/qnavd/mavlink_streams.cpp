#include "firmware/qnavd/mavlink_streams.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace qnav::daemon {

namespace mav = drivers::mavlink;
namespace qc = drivers::qnavcan;

namespace {
constexpr std::uint8_t kSeverityCritical = 2, kSeverityInfo = 6;
constexpr std::uint8_t kMavStateActive = 4, kMavStateCritical = 5;
constexpr std::uint8_t kDistanceSensorUltrasound = 1, kRotationPitch270 = 25;  // acoustic, looking down
// SET_POSITION_TARGET_LOCAL_NED type_mask: position only (velocity, acceleration, yaw, yaw rate ignored).
constexpr std::uint16_t kTypeMaskPositionOnly = 8 | 16 | 32 | 64 | 128 | 256 | 1024 | 2048;
constexpr std::int64_t kNsPerS = 1000000000;
float nanf_() noexcept { return std::numeric_limits<float>::quiet_NaN(); }
}  // namespace

std::int64_t MavlinkStreams::odometry_grid_after(std::int64_t t) const noexcept {
  const std::int64_t period = static_cast<std::int64_t>(1e9 / cfg_.mavlink_odometry_hz);
  const std::int64_t k = t >= 0 ? t / period : -((-t + period - 1) / period);  // floor(t / period)
  return (k + 1) * period;
}

std::uint32_t MavlinkStreams::boot_ms(std::int64_t now_ns) const noexcept {
  return static_cast<std::uint32_t>(std::max<std::int64_t>(0, now_ns - start_ns_) / 1000000);
}

bool MavlinkStreams::publish(const MavSnapshot& s, bool guided_armed, SpscRing<MavBytes>& tx) noexcept {
  if (!started_) {
    started_ = true;
    start_ns_ = s.now_ns;
    next_hb_ns_ = next_slow_ns_ = s.now_ns;
    next_odo_ns_ = odometry_grid_after(s.now_ns - 1);
    last_mode_ = s.mode;
    last_faults_ = s.faults;
  }
  const std::int64_t t = s.now_ns;
  status_changes(s, tx);
  if (t >= next_hb_ns_) {
    mav::Heartbeat h;
    h.type = mav::kMavTypeOnboardController;
    h.autopilot = mav::kMavAutopilotInvalid;
    h.custom_mode = static_cast<std::uint32_t>(s.mode);
    h.system_status = s.loss ? kMavStateCritical : kMavStateActive;
    wire_.send(h, tx);
    next_hb_ns_ = t + kNsPerS;
  }
  if (s.estimate != nullptr && t >= next_odo_ns_) odometry(s, *s.estimate, tx);
  if (t < next_slow_ns_) return false;
  next_slow_ns_ = t + kNsPerS;
  slow(s, guided_armed, tx);
  return true;
}

// STATUSTEXT on a mode change and on a fault bit that rises.
void MavlinkStreams::status_changes(const MavSnapshot& s, SpscRing<MavBytes>& tx) noexcept {
  if (s.mode != last_mode_) {
    char text[51];
    std::snprintf(text, sizeof text, "qnav: mode %s", qc::mode_name(s.mode));
    wire_.status_text(kSeverityInfo, text, tx);
    last_mode_ = s.mode;
  }
  const std::uint16_t risen = static_cast<std::uint16_t>(s.faults & ~last_faults_);
  if (risen != 0) {
    char text[51];
    std::size_t n = static_cast<std::size_t>(std::snprintf(text, sizeof text, "qnav: fault"));
    for (int b = 0; b < qc::fault::kBitCount && n < sizeof text; ++b)
      if (risen & (1u << b)) n += static_cast<std::size_t>(std::snprintf(text + n, sizeof text - n, " %s", qc::fault::kSignalNames[b] + 5));
    wire_.status_text(kSeverityCritical, text, tx);
  }
  last_faults_ = s.faults;
}

void MavlinkStreams::odometry(const MavSnapshot& s, const pipeline::NavEstimate& est, SpscRing<MavBytes>& tx) noexcept {
  const pipeline::NavEstimate* e = &est;
  const std::int64_t t = s.now_ns;
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
  wire_.send(o, tx);
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
    wire_.send(d, tx);
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
    wire_.send(ds, tx);
  }
}

// The 1 Hz slot: the repeat's named values, and the GUIDED target.
void MavlinkStreams::slow(const MavSnapshot& s, bool guided_armed, SpscRing<MavBytes>& tx) noexcept {
  const std::int64_t t = s.now_ns;
  if (s.in_repeat) {
    const auto nvf = [&](const char* name, double v) {
      mav::NamedValueFloat n;
      n.time_boot_ms = boot_ms(t);
      mav::set_string(n.name, name);
      n.value = static_cast<float>(v);
      wire_.send(n, tx);
    };
    nvf("xtrack_m", s.guidance_valid ? s.cross_track_m : std::numeric_limits<double>::quiet_NaN());
    nvf("xtrack_sig", s.guidance_valid ? s.cross_track_sigma_m : std::numeric_limits<double>::quiet_NaN());
    nvf("side", s.side);
    nvf("node", s.node);
  }
  // GUIDED (opt-in): the look-ahead waypoint, route frame = the published frame after a route fix.
  const pipeline::NavEstimate* e = s.estimate;
  if (cfg_.mavlink_guided && s.in_repeat && s.route_fix && s.guidance_valid && !s.loss && guided_armed && e != nullptr) {
    mav::SetPositionTargetLocalNed p;
    p.time_boot_ms = boot_ms(t);
    p.target_system = static_cast<std::uint8_t>(cfg_.mavlink_autopilot_system_id);
    p.target_component = static_cast<std::uint8_t>(cfg_.mavlink_autopilot_component_id);
    p.coordinate_frame = mav::kMavFrameLocalNed;
    p.type_mask = kTypeMaskPositionOnly;
    p.x = static_cast<float>(s.waypoint_ne.x());
    p.y = static_cast<float>(s.waypoint_ne.y());
    p.z = static_cast<float>(e->down_m());
    wire_.send(p, tx);
    ++targets_sent_;
  }
}

}  // namespace qnav::daemon
