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

Status VoOdometry::init(const vo::VoConfig& config, const Pose3& body_T_cam, const VoPriorConfig& prior) {
  arena_.reset(new ArenaStorage(vo::StereoVo::arena_bytes(config)));
  if (!arena_->valid()) return Status(StatusCode::kCapacityExceeded, "vo: cannot allocate the arena");
  return init(config, body_T_cam, prior, *arena_);
}

Status VoOdometry::init(const vo::VoConfig& config, const Pose3& body_T_cam, const VoPriorConfig& prior, Arena& arena) {
  if (!body_T_cam.is_finite()) return Status(StatusCode::kInvalidArgument, "vo: camera mount is not finite");
  if (!(prior.zero_sigma_m > 0.0) || !(prior.first_sigma_m >= 0.0)) return Status(StatusCode::kInvalidArgument, "vo: bad prior sigma");
  arena_bytes_ = vo::StereoVo::arena_bytes(config);
  QNAV_RETURN_IF_ERROR(vo_.init(config, arena));
  body_T_cam_ = body_T_cam;
  cam_T_body_ = body_T_cam.inverse();
  prior_ = prior;
  reset();
  return Status::ok();
}

void VoOdometry::reset(const Pose3& world_T_body, bool keep_start_attitude) noexcept {
  keep_start_attitude_ = keep_start_attitude;
  vo_.reset(world_T_body.compose(body_T_cam_));
  started_ = false;
  have_velocity_ = false;
  velocity_t_ = Vec3d::Zero();
  velocity_R_ = Mat3d::Identity();
  prev_world_R_cam_ = Mat3d::Identity();
  prev_world_R_body_ = Mat3d::Identity();
}

Result<vo::VoStep> VoOdometry::step(const VoFrameInput& in) noexcept {
  const bool attitude = in.has_attitude && in.world_R_body.allFinite();
  if (!attitude && vo_.config().mode != vo::VmeMode::k6D) return Status(StatusCode::kNotReady, "vo: no attitude for the frame");
  const Mat3d world_R_cam = attitude ? Mat3d(in.world_R_body * body_T_cam_.R) : Mat3d::Identity();
  vo::VoInput v;
  v.left = in.left;
  v.right = in.right;
  v.stamp_ns = in.stamp_ns;
  v.has_absolute_attitude = attitude;
  v.world_R_cam = world_R_cam;
  v.attitude_recalibrated = in.attitude_recalibrated;
  if (!started_) {
    // The chain starts with the body where reset() put it, in the attitude of this first pair.
    if (attitude && !keep_start_attitude_) {
      const Pose3 world_T_body{in.world_R_body, body_pose().t};
      vo_.reset(world_T_body.compose(body_T_cam_));
    }
  } else {
    // Rotation prior: the sensor's relative attitude, else the last visual step's (constant velocity).
    v.R_prev_cur = attitude ? Mat3d(prev_world_R_cam_.transpose() * world_R_cam) : (prior_.zero_motion ? Mat3d::Identity() : velocity_R_);
    const bool camera_prior = attitude && in.has_camera_translation_prior && in.t_prev_cur_cam_m.allFinite() &&
                              std::isfinite(in.camera_translation_sigma_m) && in.camera_translation_sigma_m >= 0.0;
    const bool odometry = attitude && in.has_body_displacement && in.body_displacement_world_m.allFinite() &&
                          std::isfinite(in.displacement_sigma_m) && in.displacement_sigma_m >= 0.0;
    if (camera_prior) {
      v.has_translation_prior = true;
      v.t_prev_cur_prior_m = in.t_prev_cur_cam_m;
      v.t_prior_sigma_m = in.camera_translation_sigma_m;
    } else if (odometry) {
      // Camera at p_b + R_wb t_bc: its displacement in the previous camera frame.
      const Vec3d& t_bc = body_T_cam_.t;
      const Vec3d d_world = in.body_displacement_world_m + (in.world_R_body - prev_world_R_body_) * t_bc;
      v.has_translation_prior = true;
      v.t_prev_cur_prior_m = prev_world_R_cam_.transpose() * d_world;
      v.t_prior_sigma_m = in.displacement_sigma_m;
    } else if (prior_.zero_motion) {
      v.has_translation_prior = true;
      v.t_prev_cur_prior_m = Vec3d::Zero();
      v.t_prior_sigma_m = prior_.zero_sigma_m;
    } else if (have_velocity_) {
      v.has_translation_prior = true;
      v.t_prev_cur_prior_m = velocity_t_;
      v.t_prior_sigma_m = 0.1 + 0.2 * velocity_t_.norm();
    } else if (prior_.first_sigma_m > 0.0) {
      v.has_translation_prior = true;
      v.t_prev_cur_prior_m = Vec3d::Zero();
      v.t_prior_sigma_m = prior_.first_sigma_m;
    }
  }
  Result<vo::VoStep> r = vo_.process(v);
  if (!r) return r;
  ++frames_;
  started_ = true;
  prev_world_R_cam_ = world_R_cam;
  prev_world_R_body_ = attitude ? in.world_R_body : Mat3d::Identity();
  if (r->visual) {
    ++visual_;
    velocity_t_ = r->prev_T_cur.t;
    velocity_R_ = r->prev_T_cur.R;
    have_velocity_ = true;
  }
  return r;
}

}  // namespace qnav::pipeline
