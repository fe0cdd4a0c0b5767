// Pose integration of visual-odometry steps (Souvannavong et al. sec. 3.3, "simple integration").
// world_T_cur = world_T_prev * step. Two modes: integrate the step rotation (6D-VME), or take the
// orientation from the attitude sensor (3D-VME: the translation is expressed in the previous frame and
// rotated by the previous absolute attitude). The translation covariance is propagated
// (cov_world += R_w cov_step R_w^T), the path length accumulated. A non-finite or rejected step leaves the
// pose unchanged and is counted. O(1), no heap.
#pragma once

#include <cstdint>

#include "nav/core/geometry.hpp"
#include "nav/core/status.hpp"

namespace qnav::motion {

class PoseIntegrator {
 public:
  void reset(const Pose3& world_T_start = Pose3{}) noexcept {
    pose_ = world_T_start;
    cov_t_ = Mat3d::Zero();
    path_m_ = 0.0;
    steps_ = 0;
  }
  // Adds a step (current camera in previous frame) with its 3x3 translation covariance. When
  // world_R_cur (absolute attitude) is given, the orientation is replaced by it after the step.
  Status add_step(const Pose3& prev_T_cur, const Mat3d& cov_t, const Mat3d* world_R_cur = nullptr) noexcept {
    if (!prev_T_cur.is_finite() || !cov_t.allFinite() || (world_R_cur != nullptr && !world_R_cur->allFinite())) {
      ++rejected_;
      return Status(StatusCode::kInvalidArgument, "non-finite VO step or attitude");
    }
    const Mat3d Rw = pose_.R;
    pose_ = pose_.compose(prev_T_cur);
    if (world_R_cur != nullptr) pose_.R = *world_R_cur;
    cov_t_ += Rw * cov_t * Rw.transpose();
    path_m_ += prev_T_cur.t.norm();
    ++steps_;
    return Status::ok();
  }
  const Pose3& pose() const noexcept { return pose_; }
  const Mat3d& translation_covariance() const noexcept { return cov_t_; }
  double path_length_m() const noexcept { return path_m_; }
  std::uint32_t steps() const noexcept { return steps_; }
  std::uint32_t rejected_steps() const noexcept { return rejected_; }

 private:
  Pose3 pose_;
  Mat3d cov_t_ = Mat3d::Zero();
  double path_m_ = 0.0;
  std::uint32_t steps_ = 0;
  std::uint32_t rejected_ = 0;
};

}  // namespace qnav::motion
