#include "firmware/qnavd/components/vo_component.hpp"

#include "firmware/qnavd/software_fault.hpp"

#include <algorithm>

#include "drivers/qnavcan/messages.hpp"

namespace qnav::daemon {

namespace qc = drivers::qnavcan;

Status VoComponent::init(StaticMemory* mem, qc::QnavCanPublisher& publisher) {
  publisher_ = &publisher;
  const DaemonConfig& cfg = *ctx_.cfg;
  if (!cfg.vo_enabled) return Status::ok();
  Result<Arena*> a = arena_.take(mem, "vo", vo::StereoVo::arena_bytes(cfg.vo));
  if (!a) return a.status();
  QNAV_RETURN_IF_ERROR(vo_.init(cfg.vo, vo_body_T_cam(cfg), cfg.vo_prior, *a.value()));
  ready_ = true;
  return Status::ok();
}

void VoComponent::reset(std::int64_t now_ns) noexcept {
  vo_.reset();
  anchor_ = last_set_ = Pose3{};
  interval_inliers_ = 0;
  mode_start_ns_ = now_ns;
  prev_dr_valid_ = false;
  chain_started_ = false;
}

bool VoComponent::camera_lost(std::int64_t now_ns) const noexcept {
  return now_ns - std::max(order_.last_ns, mode_start_ns_) > static_cast<std::int64_t>(ctx_.cfg->vo_stale_s * 1e9);
}

FrameReport* VoComponent::on_pair(const FrameMsg& f, const std::uint8_t* slot, const NavInputs& inputs) noexcept {
  const DaemonConfig& cfg = *ctx_.cfg;
  const int W = cfg.vo.max_width, H = cfg.vo.max_height;
  if (!QNAVD_CHECK(f.width == W && f.height == H, "stereo pair of another size than its pool slot")) return nullptr;
  const std::uint8_t* left = slot;
  const std::uint8_t* right = slot + static_cast<std::size_t>(W) * static_cast<std::size_t>(H);
  Mat3d world_R_body = Mat3d::Identity();
  const bool has_attitude = inputs.attitude_at(f.stamp.sample_ns, &world_R_body);
  const pipeline::DeadReckoner& dr = inputs.dr();
  FrameReport& r = report_;
  r = FrameReport{};
  r.seq = f.sequence;
  r.stamp_ns = f.stamp.sample_ns;
  r.has_truth = f.has_truth;
  r.truth_world_T_body = f.truth_world_T_body;
  r.truth_path_m = f.truth_path_m;
  pipeline::VoFrameInput in;
  in.left = ConstImageViewU8::make(left, W, H).value();
  in.right = ConstImageViewU8::make(right, W, H).value();
  in.stamp_ns = static_cast<std::uint64_t>(f.stamp.sample_ns);
  if (has_attitude) {
    in.has_attitude = true;
    in.world_R_body = world_R_body;
  }
  // The DVL (or wheel odometry on the DVL's interface) as the translation prior: the dead-reckoned
  // displacement since the previous pair (level, 20 % + 2 cm).
  const bool odo = dr.has_velocity() && dr.velocity_age_s(f.stamp.sample_ns) <= cfg.dvl_stale_s;
  const Pose2 dr_now = dr.pose_at(f.stamp.sample_ns);
  if (odo && prev_dr_valid_) {
    in.has_body_displacement = true;
    in.body_displacement_world_m = Vec3d(dr_now.x_m - prev_dr_.x_m, dr_now.y_m - prev_dr_.y_m, 0.0);
    in.displacement_sigma_m = 0.02 + 0.2 * in.body_displacement_world_m.norm();
  }
  prev_dr_ = dr_now;
  prev_dr_valid_ = odo;
  Result<vo::VoStep> step = vo_.step(in);
  if (!step) {
    ++no_attitude_;  // 3D-VME needs the attitude: the pair is not processed (FaultAttitudeLost says why)
  } else {
    r.processed = true;
    r.flags = step->flags;
    r.visual = step->visual;
    r.inliers = static_cast<std::uint32_t>(step->visual ? step->matches : 0);
    if (chain_started_) {
      publish_increment(r.inliers);
    } else {
      // The chain's first pair fixes the body's attitude: increments are measured from here.
      anchor_ = last_set_ = vo_.body_pose();
      chain_started_ = true;
    }
  }
  r.world_T_body = vo_.body_pose();
  return &r;
}

void VoComponent::log_pair(const FrameReport& r) const noexcept {
  if (ctx_.json()) {
    const Vec3d& p = r.world_T_body.t;
    const Vec3d tp = r.has_truth ? r.truth_world_T_body.t : Vec3d::Zero();
    std::fprintf(ctx_.log,
                 "{\"event\":\"vo\",\"seq\":%u,\"t_s\":%.1f,\"processed\":%s,\"visual\":%s,\"flags\":%u,\"inliers\":%u,"
                 "\"north_m\":%.4f,\"east_m\":%.4f,\"down_m\":%.4f,\"truth_north_m\":%.4f,\"truth_east_m\":%.4f,\"truth_path_m\":%.3f,"
                 "\"latency_ms\":%.2f}\n",
                 r.seq, ctx_.clock->t_s(), r.processed ? "true" : "false", r.visual ? "true" : "false", r.flags, r.inliers, p.x(), p.y(), p.z(),
                 tp.x(), tp.y(), r.truth_path_m, r.latency_ms);
  } else if (ctx_.key_value()) {
    std::fprintf(ctx_.log, "vo seq=%u processed=%d visual=%d inliers=%u north_m=%.3f east_m=%.3f\n", r.seq, r.processed ? 1 : 0,
                 r.visual ? 1 : 0, r.inliers, r.world_T_body.t.x(), r.world_T_body.t.y());
  }
}

// QNAV_VO_STEP carries the motion since the last one sent: while the publisher still holds the last
// value, this step is added to it (the increment grows from the same anchor); once it went out, a
// new increment starts where that one ended.
void VoComponent::publish_increment(std::uint32_t inliers) noexcept {
  if (!publisher_->vo_pending()) {
    anchor_ = last_set_;
    interval_inliers_ = inliers;
  } else {
    interval_inliers_ = std::min(interval_inliers_, inliers);
  }
  last_set_ = vo_.body_pose();
  const pipeline::PlanarIncrement inc = pipeline::planar_increment(anchor_, last_set_);
  qc::VoStep m;
  m.dx_m = qc::clamp_to_signal(qc::kIdVoStep, "Dx", inc.forward_m);
  m.dy_m = qc::clamp_to_signal(qc::kIdVoStep, "Dy", inc.right_m);
  m.dyaw_rad = qc::clamp_to_signal(qc::kIdVoStep, "Dyaw", inc.yaw_rad);
  m.inliers = static_cast<std::uint8_t>(std::min<std::uint32_t>(interval_inliers_, 255));
  publisher_->set(m);
}

}  // namespace qnav::daemon
