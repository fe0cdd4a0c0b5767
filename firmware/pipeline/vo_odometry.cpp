#include "firmware/pipeline/vo_odometry.hpp"

#include <cmath>

namespace qnav::pipeline {

double heading_of(const Mat3d& R) noexcept { return std::atan2(R(1, 0), R(0, 0)); }

PlanarIncrement planar_increment(const Pose3& a, const Pose3& b) noexcept {
  PlanarIncrement inc;
  const double h = heading_of(a.R);
  const Vec3d d = b.t - a.t;
  const double c = std::cos(h), s = std::sin(h);
  inc.forward_m = c * d.x() + s * d.y();
  inc.right_m = -s * d.x() + c * d.y();
  inc.down_m = d.z();
  inc.yaw_rad = wrap_angle_rad(heading_of(b.R) - h);
  return inc;
}

Status VoOdometry::init(const vo::VoConfig& config, const Pose3& body_T_cam) {
  if (!body_T_cam.is_finite()) return Status(StatusCode::kInvalidArgument, "vo: camera mount is not finite");
  arena_.reset(new ArenaStorage(vo::StereoVo::arena_bytes(config)));
  QNAV_RETURN_IF_ERROR(vo_.init(config, *arena_));
  body_T_cam_ = body_T_cam;
  cam_T_body_ = body_T_cam.inverse();
  reset();
  return Status::ok();
}

void VoOdometry::reset(const Pose3& world_T_body) noexcept {
  vo_.reset(world_T_body.compose(body_T_cam_));
  started_ = false;
  have_velocity_ = false;
  velocity_t_ = Vec3d::Zero();
  prev_world_R_cam_ = Mat3d::Identity();
}

Result<vo::VoStep> VoOdometry::step(const VoFrameInput& in) noexcept {
  if (!in.has_attitude || !in.world_R_body.allFinite()) return Status(StatusCode::kNotReady, "vo: no attitude for the frame");
  const Mat3d world_R_cam = in.world_R_body * body_T_cam_.R;
  vo::VoInput v;
  v.left = in.left;
  v.right = in.right;
  v.stamp_ns = in.stamp_ns;
  v.has_absolute_attitude = true;
  v.world_R_cam = world_R_cam;
  v.attitude_recalibrated = in.attitude_recalibrated;
  if (!started_) {
    // The chain starts with the body where reset() put it, in the attitude of this first pair.
    const Pose3 world_T_body{in.world_R_body, body_pose().t};
    vo_.reset(world_T_body.compose(body_T_cam_));
  } else {
    v.R_prev_cur = prev_world_R_cam_.transpose() * world_R_cam;
    if (in.has_body_displacement && in.body_displacement_world_m.allFinite() && std::isfinite(in.displacement_sigma_m)) {
      // Camera at p_b + R_wb t_bc: its displacement in the previous camera frame.
      const Vec3d& t_bc = body_T_cam_.t;
      const Vec3d d_world = in.body_displacement_world_m + (in.world_R_body - prev_world_R_body_) * t_bc;
      v.has_translation_prior = true;
      v.t_prev_cur_prior_m = prev_world_R_cam_.transpose() * d_world;
      v.t_prior_sigma_m = in.displacement_sigma_m;
    } else if (have_velocity_) {
      v.has_translation_prior = true;
      v.t_prev_cur_prior_m = velocity_t_;
      v.t_prior_sigma_m = 0.1 + 0.2 * velocity_t_.norm();
    }
  }
  Result<vo::VoStep> r = vo_.process(v);
  if (!r) return r;
  ++frames_;
  started_ = true;
  prev_world_R_cam_ = world_R_cam;
  prev_world_R_body_ = in.world_R_body;
  if (r->visual) {
    ++visual_;
    velocity_t_ = r->prev_T_cur.t;
    have_velocity_ = true;
  }
  return r;
}

}  // namespace qnav::pipeline
