#include "firmware/pipeline/route_autopilot.hpp"

#include <algorithm>
#include <cmath>

namespace qnav::pipeline {

namespace qc = drivers::qnavcan;

namespace {
Vec2d stbd(double h) noexcept { return Vec2d(-std::sin(h), std::cos(h)); }
}  // namespace

const char* to_string(AutopilotMode m) noexcept {
  switch (m) {
    case AutopilotMode::kHoldCourse: return "hold_course";
    case AutopilotMode::kFollowing: return "following";
    case AutopilotMode::kStopped: return "stopped";
  }
  return "?";
}

void RouteAutopilot::reset(const RouteAutopilotConfig& config, std::int64_t t_ns, const Pose2& dr_pose) noexcept {
  cfg_ = config;
  pose_ = dr_pose;
  sideslip_rad_ = 0.0;
  has_line_ = stopped_ = following_ = false;
  chi_r_ = chi_hold_ = stop_heading_ = dr_pose.heading_rad;
  line_pt_ = dr_pose.translation();
  have_guidance_ = have_seq_ = false;
  last_seq_ = 0;
  hist_n_ = hist_head_ = 0;
  counters_.reset();
  on_nav(t_ns, dr_pose, 0.0);
}

void RouteAutopilot::on_nav(std::int64_t t_ns, const Pose2& dr_pose, double sideslip_rad) noexcept {
  if (dr_pose.is_finite()) pose_ = dr_pose;
  if (std::isfinite(sideslip_rad)) sideslip_rad_ = sideslip_rad;
  const std::size_t last = (hist_head_ + kHistory - 1) % kHistory;
  if (hist_n_ == 0 || static_cast<double>(t_ns - hist_[last].t_ns) * 1e-9 >= kHistoryStepS) {
    hist_[hist_head_] = Hist{t_ns, pose_};
    hist_head_ = (hist_head_ + 1) % kHistory;
    hist_n_ = std::min(hist_n_ + 1, kHistory);
  }
}

Pose2 RouteAutopilot::pose_at(std::int64_t t_ns) const noexcept {
  // The newest history entry at or before t_ns (the oldest one when t_ns is older than all).
  Pose2 best = pose_;
  for (std::size_t k = 0; k < hist_n_; ++k) {
    const Hist& h = hist_[(hist_head_ + kHistory - 1 - k) % kHistory];
    best = h.pose;
    if (h.t_ns <= t_ns) break;
  }
  return best;
}

void RouteAutopilot::on_fix(const RouteFix& fix, std::int64_t t_ns, double age_s) noexcept {
  counters_.increment(AutopilotCounter::kFixes);
  if (stopped_) return;
  switch (fix.status) {
    case qc::GuidanceState::kRouteEnd:
      stopped_ = true;
      following_ = false;
      stop_heading_ = pose_.heading_rad;
      return;
    case qc::GuidanceState::kTracking:
    case qc::GuidanceState::kDeadReckoned: {
      if (!std::isfinite(fix.cross_track_m) || !std::isfinite(fix.heading_error_rad)) return;
      counters_.increment(AutopilotCounter::kSteerFixes);
      const std::int64_t age_ns = static_cast<std::int64_t>(std::llround(std::max(0.0, age_s) * 1e9));
      const Pose2 a = age_ns > 0 ? pose_at(t_ns - age_ns) : pose_;
      chi_r_ = wrap_angle_rad(a.heading_rad - fix.heading_error_rad);
      line_pt_ = a.translation() - fix.cross_track_m * stbd(chi_r_);
      chi_hold_ = chi_r_;
      has_line_ = true;
      following_ = true;
      return;
    }
    case qc::GuidanceState::kHoldCourse:
    case qc::GuidanceState::kNotRepeating:
      following_ = false;
      return;
  }
}

Status RouteAutopilot::on_frame(const hal::CanFrame& f, std::int64_t t_ns) noexcept {
  if (f.id == qc::kIdRouteGuidance) {
    counters_.increment(AutopilotCounter::kFrames);
    const Status s = qc::decode(f, guidance_);
    have_guidance_ = s.is_ok();
    if (!s) counters_.increment(AutopilotCounter::kDecodeErrors);
    return s;
  }
  if (f.id != qc::kIdRouteStatus) return Status::ok();
  counters_.increment(AutopilotCounter::kFrames);
  qc::RouteStatus st;
  const Status s = qc::decode(f, st);
  if (!s) {
    counters_.increment(AutopilotCounter::kDecodeErrors);
    return s;
  }
  if (!have_guidance_) {  // a status without its guidance: nothing to steer on
    counters_.increment(AutopilotCounter::kUnpairedStatus);
    return Status::ok();
  }
  have_guidance_ = false;
  if (have_seq_ && st.tile_seq == last_seq_) return Status::ok();  // the same tile repeated at the DBC period
  have_seq_ = true;
  last_seq_ = st.tile_seq;
  RouteFix fix;
  fix.status = st.status;
  fix.cross_track_m = guidance_.cross_track_m;
  fix.heading_error_rad = guidance_.heading_error_rad;
  on_fix(fix, t_ns, cfg_.guidance_age_s);
  return Status::ok();
}

AutopilotCommand RouteAutopilot::command() const noexcept {
  AutopilotCommand c;
  c.has_line = has_line_;
  const double beta = cfg_.crab_compensation ? sideslip_rad_ : 0.0;
  if (has_line_) c.cross_track_m = (pose_.translation() - line_pt_).dot(stbd(chi_r_));
  if (stopped_) {
    c.mode = AutopilotMode::kStopped;
    c.heading_rad = stop_heading_;
    c.course_rad = stop_heading_ + beta;
    c.speed_mps = 0.0;
    return c;
  }
  c.speed_mps = cfg_.cruise_speed_mps;
  if (following_) {
    c.mode = AutopilotMode::kFollowing;
    const double lim = cfg_.max_intercept_rad;
    const double intercept = std::clamp(std::atan(cfg_.cross_track_gain * c.cross_track_m / cfg_.lookahead_m), -lim, lim);
    c.course_rad = wrap_angle_rad(chi_r_ - intercept);
  } else {
    c.mode = AutopilotMode::kHoldCourse;
    c.course_rad = chi_hold_;
  }
  c.heading_rad = wrap_angle_rad(c.course_rad - beta);
  return c;
}

}  // namespace qnav::pipeline
