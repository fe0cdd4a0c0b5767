#include "firmware/pipeline/route_autopilot.hpp"

#include <algorithm>
#include <cmath>

namespace qnav::pipeline {

namespace qc = drivers::qnavcan;

const char* to_string(AutopilotMode m) noexcept {
  switch (m) {
    case AutopilotMode::kHoldCourse: return "hold_course";
    case AutopilotMode::kFollowing: return "following";
    case AutopilotMode::kStopped: return "stopped";
  }
  return "?";
}

Vec2d RouteAutopilot::pt(std::size_t i) const noexcept {
  const std::size_t n = track_.size();
  return track_[cfg_.reverse ? n - 1 - i : i].translation();
}

Status RouteAutopilot::reset(const RouteAutopilotConfig& config, Span<const Pose2> track,
                             Span<const std::uint32_t> node_at, std::int64_t t_ns, const Pose2& dr_pose) noexcept {
  if (track.size() < 2 || node_at.size() < 1)
    return Status(StatusCode::kInvalidArgument, "route autopilot: the taught track needs >= 2 poses and >= 1 node");
  for (std::size_t i = 0; i < node_at.size(); ++i)
    if (node_at[i] >= track.size() || (i > 0 && node_at[i] <= node_at[i - 1]))
      return Status(StatusCode::kInvalidArgument,
                    "route autopilot: node indices must increase and lie inside the track");
  if (!(config.lookahead_m > 0.0) || !(config.max_intercept_rad > 0.0) || !(config.cross_track_gain >= 0.0) ||
      !(config.guidance_age_m >= 0.0 && config.guidance_age_m < 1e6))
    return Status(StatusCode::kInvalidArgument, "route autopilot: lookahead, intercept limit or gain out of range");
  cfg_ = config;
  track_ = track;
  node_at_ = node_at;
  track_length_m_ = 0.0;
  for (std::size_t i = 0; i + 1 < track.size(); ++i)
    track_length_m_ += (track[i + 1].translation() - track[i].translation()).norm();
  // The mean node spacing: DistToNext is counted from the next node.
  const std::size_t nodes = node_at.size();
  spacing_m_ = 0.0;
  for (std::size_t i = 0; i + 1 < nodes; ++i)
    spacing_m_ +=
        (track[node_at[i + 1]].translation() - track[node_at[i]].translation()).norm() / static_cast<double>(nodes - 1);
  seg_hint_ = 0;
  cum_hint_ = 0.0;
  pose_ = dr_pose;
  sideslip_rad_ = 0.0;
  has_line_ = stopped_ = following_ = route_end_ = false;
  dr_to_teach_ = Pose2{};
  chi_hold_ = stop_heading_ = last_course_ = dr_pose.heading_rad;
  have_guidance_ = have_seq_ = false;
  last_seq_ = 0;
  hist_n_ = hist_head_ = 0;
  travelled_m_ = 0.0;
  counters_.reset();
  on_nav(t_ns, dr_pose, 0.0);
  return Status::ok();
}

void RouteAutopilot::set_frame(const Pose2& dr_to_teach) noexcept {
  if (!dr_to_teach.is_finite()) return;
  dr_to_teach_ = dr_to_teach;
  has_line_ = following_ = true;
}

void RouteAutopilot::on_nav(std::int64_t t_ns, const Pose2& dr_pose, double sideslip_rad) noexcept {
  if (dr_pose.is_finite()) {
    if (hist_n_ > 0) travelled_m_ += (dr_pose.translation() - pose_.translation()).norm();
    pose_ = dr_pose;
  }
  if (std::isfinite(sideslip_rad)) sideslip_rad_ = sideslip_rad;
  const std::size_t last = (hist_head_ + kHistory - 1) % kHistory;
  if (hist_n_ == 0 || static_cast<double>(t_ns - hist_[last].t_ns) * 1e-9 >= kHistoryStepS) {
    hist_[hist_head_] = Hist{t_ns, pose_, travelled_m_};
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

Pose2 RouteAutopilot::pose_travelled_back(double back_m) const noexcept {
  // The newest history entry at least back_m of own travel before now (the oldest one otherwise).
  const double want = travelled_m_ - back_m;
  Pose2 best = pose_;
  for (std::size_t k = 0; k < hist_n_; ++k) {
    const Hist& h = hist_[(hist_head_ + kHistory - 1 - k) % kHistory];
    best = h.pose;
    if (h.travelled_m <= want) break;
  }
  return best;
}

void RouteAutopilot::locate(const Vec2d& p, double& along_m, double& cross_m, Vec2d& foot,
                            std::size_t& seg) const noexcept {
  // Nearest segment within a window around the last foot point (a track that comes back near
  // itself is not confused); the first segment extends backwards and the last one forwards.
  const std::size_t nseg = track_.size() - 1;
  std::size_t lo = seg_hint_ >= 2 ? seg_hint_ - 2 : 0;
  double cum = cum_hint_;
  for (std::size_t i = seg_hint_; i > lo; --i) cum -= (pt(i) - pt(i - 1)).norm();
  const std::size_t hi = std::min(nseg, seg_hint_ + 8);
  double best = 1e300;
  along_m = cross_m = 0.0;
  foot = pt(0);
  seg = seg_hint_;
  for (std::size_t i = lo; i < hi; ++i) {
    const Vec2d a = pt(i), d = pt(i + 1) - a;
    const double len = d.norm();
    if (len > 0.0) {
      const Vec2d u = d / len;
      const double t = std::clamp((p - a).dot(u), i == 0 ? -1e300 : 0.0, i + 1 == nseg ? 1e300 : len);
      const Vec2d f = a + t * u;
      const double dist = (p - f).norm();
      if (dist < best) {
        best = dist;
        along_m = cum + t;
        cross_m = (p - a).dot(Vec2d(-u.y(), u.x()));
        foot = f;
        seg = i;
      }
    }
    cum += len;
  }
}

Vec2d RouteAutopilot::point_at(double along_m) const noexcept {
  const std::size_t nseg = track_.size() - 1;
  double cum = cum_hint_;
  for (std::size_t i = seg_hint_; i < nseg; ++i) {
    const Vec2d a = pt(i), d = pt(i + 1) - a;
    const double len = d.norm();
    if ((along_m <= cum + len || i + 1 == nseg) && len > 0.0) return a + (along_m - cum) / len * d;
    cum += len;
  }
  return pt(nseg);
}

void RouteAutopilot::on_fix(const RouteFix& fix, std::int64_t t_ns, double age_s) noexcept {
  counters_.increment(AutopilotCounter::kFixes);
  if (stopped_) return;
  switch (fix.status) {
    case qc::GuidanceState::kRouteEnd:
      // qnav's last node is the centre of the teach's last tile, up to half a tile before the taught
      // track's end: with a frame, follow the track on to its end (command() stops past it).
      if (has_line_) {
        route_end_ = following_ = true;
        return;
      }
      stopped_ = true;
      following_ = false;
      stop_heading_ = pose_.heading_rad;
      return;
    case qc::GuidanceState::kTracking:
    case qc::GuidanceState::kDeadReckoned: {
      const std::size_t nodes = node_at_.size();
      if (!std::isfinite(fix.cross_track_m) || !std::isfinite(fix.heading_error_rad) ||
          !std::isfinite(fix.dist_to_next_m) || fix.node >= nodes)
        return;
      counters_.increment(AutopilotCounter::kSteerFixes);
      const std::int64_t age_ns = static_cast<std::int64_t>(std::llround(std::max(0.0, age_s) * 1e9));
      const Pose2 a = cfg_.guidance_age_m > 0.0 ? pose_travelled_back(cfg_.guidance_age_m) : age_ns > 0 ? pose_at(t_ns - age_ns) : pose_;
      const double sgn = cfg_.reverse ? -1.0 : 1.0;
      const Pose2 in_node{sgn * (spacing_m_ - fix.dist_to_next_m), sgn * fix.cross_track_m,
                          wrap_angle_rad(fix.heading_error_rad - (cfg_.reverse ? kPi : 0.0))};
      const Pose2 v = track_[node_at_[fix.node]].compose(in_node);
      dr_to_teach_ = v.compose(a.inverse());
      // The foot-point search restarts at the node's segment (travel order).
      const std::size_t idx = cfg_.reverse ? track_.size() - 1 - node_at_[fix.node] : node_at_[fix.node];
      seg_hint_ = idx > 0 ? idx - 1 : 0;
      cum_hint_ = 0.0;
      for (std::size_t i = 0; i < seg_hint_; ++i) cum_hint_ += (pt(i + 1) - pt(i)).norm();
      has_line_ = following_ = true;
      return;
    }
    case qc::GuidanceState::kHoldCourse:
    case qc::GuidanceState::kNotRepeating:
      if ((cfg_.follow_track_on_hold || route_end_) && has_line_) return;  // the track on dead reckoning, last frame
      if (following_) chi_hold_ = last_course_;
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
  fix.dist_to_next_m = guidance_.dist_to_next_m;
  fix.node = guidance_.target_node;
  on_fix(fix, t_ns, cfg_.guidance_age_s);
  return Status::ok();
}

AutopilotCommand RouteAutopilot::command() noexcept {
  AutopilotCommand c;
  c.has_line = has_line_;
  const double beta = cfg_.crab_compensation ? sideslip_rad_ : 0.0;
  if (has_line_ && !stopped_) {
    const Vec2d p = dr_to_teach_.apply(pose_.translation());
    Vec2d foot;
    std::size_t seg = seg_hint_;
    locate(p, c.along_m, c.cross_track_m, foot, seg);
    // Keep the hint on the foot point's segment.
    while (seg_hint_ < seg) {
      cum_hint_ += (pt(seg_hint_ + 1) - pt(seg_hint_)).norm();
      ++seg_hint_;
    }
    while (seg_hint_ > seg) {
      --seg_hint_;
      cum_hint_ -= (pt(seg_hint_ + 1) - pt(seg_hint_)).norm();
    }
    if (following_ && c.along_m >= track_length_m_) {  // past the taught track's end
      stopped_ = true;
      following_ = false;
      stop_heading_ = pose_.heading_rad;
    }
    if (following_) {
      const Vec2d carrot = point_at(c.along_m + cfg_.lookahead_m);
      const Vec2d d = carrot - foot;
      const double chi_ahead = std::atan2(d.y(), d.x());
      const double lim = cfg_.max_intercept_rad;
      const double intercept =
          std::clamp(std::atan(cfg_.cross_track_gain * c.cross_track_m / cfg_.lookahead_m), -lim, lim);
      c.mode = AutopilotMode::kFollowing;
      c.course_rad = wrap_angle_rad(chi_ahead - intercept - dr_to_teach_.heading_rad);
      c.heading_rad = wrap_angle_rad(c.course_rad - beta);
      c.speed_mps = cfg_.cruise_speed_mps;
      last_course_ = c.course_rad;
      return c;
    }
  }
  if (stopped_) {
    c.mode = AutopilotMode::kStopped;
    c.heading_rad = stop_heading_;
    c.course_rad = stop_heading_ + beta;
    c.speed_mps = 0.0;
    return c;
  }
  c.mode = AutopilotMode::kHoldCourse;
  c.course_rad = chi_hold_;
  c.heading_rad = wrap_angle_rad(c.course_rad - beta);
  c.speed_mps = cfg_.cruise_speed_mps;
  return c;
}

}  // namespace qnav::pipeline
