// VoOdometry: the per-frame wiring of stereo visual odometry on a vehicle, shared by qnavd's vo mode
// and `qnav vo`: one rectified stereo pair + the attitude sensor's sample at the pair's time ->
// nav/vo StereoVo -> the vehicle's pose and planar increments.
//
// Frames. World: NED (x north, y east, z down). Body: FRD (x forward, y right, z down), as
// QNAV_ATTITUDE_IN gives roll, pitch and heading (R = Rz(heading) Ry(pitch) Rx(roll)). Camera: x right,
// y down, z forward; mount = body_T_cam (rotation and lever arm of the left camera on the body).
// Per frame: world_R_cam = world_R_body(attitude) * mount.R (3D-VME's absolute attitude); the relative
// attitude since the previous frame; the translation prior from the caller's odometry (the body's
// displacement turned into the previous camera frame through the mount) or else constant velocity (the
// last visual step, sigma 0.1 m + 20 % of it; before the first visual step VoPriorConfig says). A
// frame without attitude: with 3D-VME it is not processed (kNotReady; the caller counts it); with
// 6D-VME (a rig with no attitude sensor: `qnav vo --kitti/--euroc`, or vo.vme = "6d") the VO measures
// the rotation itself and the rotation prior is the last visual step's (or none, for a rig that barely
// moves: VoPriorConfig::zero_motion).
// Outputs: the body pose world_T_body (the camera pose through the mount) and, for QNAV_VO_STEP, the
// planar increment between two body poses in the level frame of the first's heading.
// Memory: init() allocates the StereoVo arena once (StereoVo::arena_bytes); step() allocates nothing.
// Time: one StereoVo::process (nav/vo/stereo_vo.hpp gives its worst case) + O(1).
#pragma once

#include <cstdint>
#include <memory>

#include "firmware/pipeline/vo_prior.hpp"
#include "nav/core/arena.hpp"
#include "nav/core/geometry.hpp"
#include "nav/core/image.hpp"
#include "nav/core/status.hpp"
#include "nav/vo/stereo_vo.hpp"

namespace qnav::pipeline {


struct VoFrameInput {
  ConstImageViewU8 left, right;
  std::uint64_t stamp_ns = 0;        // sample time (0 = none)
  bool has_attitude = false;
  Mat3d world_R_body = Mat3d::Identity();
  bool attitude_recalibrated = false;  // the sensor was just reset against an absolute reference
  // Odometry (wheels, DVL): the body's displacement since the previous pair, in the world frame, and
  // its 1-sigma; turned into the camera's through the mount and the attitude. Without it: constant
  // velocity.
  bool has_body_displacement = false;
  Vec3d body_displacement_world_m = Vec3d::Zero();
  double displacement_sigma_m = 0.05;
  // A translation prior already in the previous camera frame and its 1-sigma (a simulated odometry
  // step: `qnav vo eval`); used as it is, before the body displacement. Needs the frame's attitude.
  bool has_camera_translation_prior = false;
  Vec3d t_prev_cur_cam_m = Vec3d::Zero();
  double camera_translation_sigma_m = 0.0;
};

// Motion between two body poses in the level frame of the first's heading.
struct PlanarIncrement {
  double forward_m = 0.0, right_m = 0.0, down_m = 0.0;
  double yaw_rad = 0.0;  // heading change, clockwise positive, wrapped to (-pi, pi]
};
PlanarIncrement planar_increment(const Pose3& world_T_body_a, const Pose3& world_T_body_b) noexcept;
// Heading (yaw about NED z) of a body rotation.
double heading_of(const Mat3d& world_R_body) noexcept;

class VoOdometry {
 public:
  VoOdometry() = default;
  VoOdometry(const VoOdometry&) = delete;
  VoOdometry& operator=(const VoOdometry&) = delete;
  // Allocates the StereoVo arena and initialises it (kInvalidArgument for a bad configuration).
  Status init(const vo::VoConfig& config, const Pose3& body_T_cam, const VoPriorConfig& prior = VoPriorConfig{});
  // The same with the StereoVo arena taken from the caller's (qnavd: its static block; at least
  // StereoVo::arena_bytes(config)), which outlives this.
  Status init(const vo::VoConfig& config, const Pose3& body_T_cam, const VoPriorConfig& prior, Arena& arena);
  // Starts a new chain with the body at world_T_body. The chain takes its attitude from the first
  // pair's sensor sample, or with keep_start_attitude keeps world_T_body's (a start pose known better
  // than the sensor's: `qnav vo eval` starts on the simulator's truth).
  void reset(const Pose3& world_T_body = Pose3{}, bool keep_start_attitude = false) noexcept;
  // Processes one pair. Returns the StereoVo step (flags say visual / lost / dead-reckoned), or
  // kNotReady when a 3D-VME frame has no attitude (nothing integrated).
  Result<vo::VoStep> step(const VoFrameInput& in) noexcept;

  Pose3 body_pose() const noexcept { return vo_.pose().compose(cam_T_body_); }
  const Pose3& body_T_cam() const noexcept { return body_T_cam_; }
  const vo::StereoVo& vo() const noexcept { return vo_; }
  std::uint32_t frames() const noexcept { return frames_; }
  std::uint32_t visual_steps() const noexcept { return visual_; }
  std::size_t arena_bytes() const noexcept { return arena_bytes_; }

 private:
  std::unique_ptr<ArenaStorage> arena_;
  std::size_t arena_bytes_ = 0;
  vo::StereoVo vo_;
  Pose3 body_T_cam_, cam_T_body_;
  VoPriorConfig prior_;
  bool started_ = false;
  bool keep_start_attitude_ = false;
  Mat3d prev_world_R_cam_ = Mat3d::Identity();
  Mat3d prev_world_R_body_ = Mat3d::Identity();
  bool have_velocity_ = false;
  Vec3d velocity_t_ = Vec3d::Zero();  // last visual step (previous camera frame)
  Mat3d velocity_R_ = Mat3d::Identity();
  std::uint32_t frames_ = 0, visual_ = 0;
};

}  // namespace qnav::pipeline
