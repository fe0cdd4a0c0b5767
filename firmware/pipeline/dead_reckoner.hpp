// DeadReckoner: the causal navigation source of the route pipeline on a vehicle. It integrates DVL
// body velocities (forward, starboard; m/s) turned by the attitude source's heading into a north/east
// position, using only samples at or before the time asked for: a DVL sample at t_k moves the
// position by v_k * (t_k - t_{k-1}) along the newest heading at or before t_k; pose_at(t) extrapolates
// the newest velocity to t (never past max_extrapolation_s). Distance travelled is the integral of
// the ground speed. No heap, O(1) per sample.
// Stale handling is the caller's: has_velocity()/velocity_age_s() tell how old the newest DVL sample is.
#pragma once

#include <cmath>
#include <cstdint>

#include "nav/core/geometry.hpp"

namespace qnav::pipeline {

// What a DVL reports for a vehicle that went from `a` to `b` (north/east metres) in dt_s seconds,
// heading b.heading_rad: the body velocities (forward, starboard; m/s) that DeadReckoner turns back
// into that displacement. The simulators' DVL.
inline void body_velocity_between(const Pose2& a, const Pose2& b, double dt_s, double& forward_mps, double& starboard_mps) noexcept {
  const double dn = (b.x_m - a.x_m) / dt_s, de = (b.y_m - a.y_m) / dt_s;
  const double c = std::cos(b.heading_rad), s = std::sin(b.heading_rad);
  forward_mps = c * dn + s * de;
  starboard_mps = -s * dn + c * de;
}

class DeadReckoner {
 public:
  explicit DeadReckoner(double max_extrapolation_s = 1.0) noexcept : max_extrap_s_(max_extrapolation_s) {}

  // A new origin (a pass starts): position and distance restart; the newest heading and velocity
  // samples stay (the sensors did not stop).
  void reset(const Pose2& start = Pose2{}) noexcept {
    pose_ = start;
    distance_m_ = 0.0;
  }
  // Forgets the sensors too (nothing known until the next samples).
  void clear() noexcept {
    reset();
    have_heading_ = have_velocity_ = false;
    last_v_ns_ = 0;
  }
  // Compass heading (rad) measured at t_ns. Non-finite values are refused (false; the caller counts).
  bool on_heading(std::int64_t t_ns, double heading_rad) noexcept {
    if (!std::isfinite(heading_rad)) return false;
    heading_rad_ = heading_rad;
    heading_ns_ = t_ns;
    have_heading_ = true;
    pose_.heading_rad = heading_rad;
    return true;
  }
  // Body velocity (forward, starboard) measured at t_ns. Refused (false) when not finite, faster than
  // max_speed_mps, not after the previous sample, or before any heading.
  // A sample more than max_gap_s after the previous one starts the integration afresh: a velocity is
  // not stretched over a gap (the position holds through it, and gaps() counts it).
  bool on_velocity(std::int64_t t_ns, double forward_mps, double starboard_mps, double max_speed_mps = 10.0,
                   double max_gap_s = 1e9) noexcept {
    if (!std::isfinite(forward_mps) || !std::isfinite(starboard_mps) || std::hypot(forward_mps, starboard_mps) > max_speed_mps) return false;
    if (!have_heading_ || (have_velocity_ && t_ns <= last_v_ns_)) return false;
    if (have_velocity_ && static_cast<double>(t_ns - last_v_ns_) * 1e-9 > max_gap_s) {
      ++gaps_;
    } else if (have_velocity_) {
      const double dt = static_cast<double>(t_ns - last_v_ns_) * 1e-9;
      advance(dt, forward_mps, starboard_mps, pose_);
      distance_m_ += dt * std::hypot(forward_mps, starboard_mps);
    }
    fwd_mps_ = forward_mps;
    stbd_mps_ = starboard_mps;
    last_v_ns_ = t_ns;
    have_velocity_ = true;
    return true;
  }
  bool has_velocity() const noexcept { return have_velocity_; }
  // The newest body velocity (forward, starboard; m/s).
  double forward_mps() const noexcept { return fwd_mps_; }
  double starboard_mps() const noexcept { return stbd_mps_; }
  bool has_heading() const noexcept { return have_heading_; }
  double velocity_age_s(std::int64_t now_ns) const noexcept { return have_velocity_ ? static_cast<double>(now_ns - last_v_ns_) * 1e-9 : 1e9; }
  double heading_age_s(std::int64_t now_ns) const noexcept { return have_heading_ ? static_cast<double>(now_ns - heading_ns_) * 1e-9 : 1e9; }
  // The pose at t_ns (>= the newest velocity sample: extrapolated; earlier: the newest pose).
  Pose2 pose_at(std::int64_t t_ns) const noexcept {
    Pose2 p = pose_;
    if (have_velocity_ && t_ns > last_v_ns_) {
      const double dt = std::fmin(static_cast<double>(t_ns - last_v_ns_) * 1e-9, max_extrap_s_);
      advance(dt, fwd_mps_, stbd_mps_, p);
    }
    return p;
  }
  double distance_m() const noexcept { return distance_m_; }
  std::uint32_t gaps() const noexcept { return gaps_; }

 private:
  void advance(double dt, double fwd, double stbd, Pose2& p) const noexcept {
    const double c = std::cos(heading_rad_), s = std::sin(heading_rad_);
    // north/east from forward/starboard with a compass heading (clockwise from north)
    p.x_m += dt * (c * fwd - s * stbd);
    p.y_m += dt * (s * fwd + c * stbd);
    p.heading_rad = heading_rad_;
  }
  double max_extrap_s_;
  Pose2 pose_{};
  double distance_m_ = 0.0;
  double heading_rad_ = 0.0;
  std::int64_t heading_ns_ = 0;
  bool have_heading_ = false;
  double fwd_mps_ = 0.0, stbd_mps_ = 0.0;
  std::int64_t last_v_ns_ = 0;
  bool have_velocity_ = false;
  std::uint32_t gaps_ = 0;
};

}  // namespace qnav::pipeline
