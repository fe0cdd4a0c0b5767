// 3D rigid motion between two matched point sets (Souvannavong et al. sec. 3.3):
//   6D-VME: (R, T) minimising sum w_i |p_i - (R c_i + T)|^2 by Arun's SVD with the reflection fix
//           (Umeyama: D = diag(1, 1, sign(det(V U^T))) so R is a rotation, never a mirror).
//   3D-VME: T = sum w_i (p_i - R c_i) / sum w_i with R given by the attitude sensor (eq. 9).
//   IRLS:   optional robust refinement of either (Huber weights on the residual norm, fixed iterations).
// Convention: p_i in the previous camera frame, c_i in the current one; the result is the pose of the
// current camera in the previous frame (p = R c + T).
// Covariance: Gauss-Newton (J^T W J)^-1 * s^2 with s^2 the weighted residual variance (floored by
// sigma_floor_m^2); 6D order (rotation vector [rad], translation [m]), rotation perturbed on the left.
// Bounds: n <= kMaxRigidPoints; cost O(n) per solve + one 3x3 SVD; IRLS O(iterations * n). No heap
// (Eigen fixed-size only). Errors: kInvalidArgument (sizes, NaN), kDegenerate (< 3 points for 6D,
// < 1 for 3D, collinear / coincident points, singular covariance).
#pragma once

#include <cstddef>

#include "nav/core/geometry.hpp"
#include "nav/core/span.hpp"
#include "nav/core/status.hpp"

namespace qnav::motion {

constexpr std::size_t kMaxRigidPoints = 65535;

struct RigidEstimate {
  Pose3 pose;                          // current camera in previous frame
  Mat6d covariance = Mat6d::Zero();    // [rotvec, t]; rotation block zero for 3D-VME
  double rms_residual_m = 0.0;
  std::size_t points = 0;
  std::size_t inliers = 0;             // residual < inlier_m (IRLS) or all points
};

struct IrlsConfig {
  std::size_t iterations = 5;
  double huber_m = 0.01;      // residual where Huber weights start to fall
  double inlier_m = 0.03;     // residual counted as an inlier in the report
};

// weights may be empty (all 1). Non-finite points are an error (the caller filters).
Result<RigidEstimate> estimate_rigid_6d(Span<const Vec3d> prev, Span<const Vec3d> cur, Span<const double> weights,
                                        double sigma_floor_m = 0.001) noexcept;
Result<RigidEstimate> estimate_translation_3d(Span<const Vec3d> prev, Span<const Vec3d> cur, const Mat3d& R,
                                              Span<const double> weights, double sigma_floor_m = 0.001) noexcept;

// IRLS refinement. weights_scratch must have prev.size() elements (caller-owned, overwritten). The
// Huber weight of each point multiplies base_weights (empty = all 1), e.g. 1 / sigma^2.
Result<RigidEstimate> refine_irls_6d(Span<const Vec3d> prev, Span<const Vec3d> cur, const RigidEstimate& initial,
                                     const IrlsConfig& config, Span<double> weights_scratch,
                                     Span<const double> base_weights = {}) noexcept;
Result<RigidEstimate> refine_irls_3d(Span<const Vec3d> prev, Span<const Vec3d> cur, const RigidEstimate& initial,
                                     const IrlsConfig& config, Span<double> weights_scratch,
                                     Span<const double> base_weights = {}) noexcept;

// Stereo point error model: a point p seen from a camera at the origin has covariance
//   sigma_ray(z)^2 u u^T + sigma_lat(z)^2 (I - u u^T),  u = p / |p|, z = p.z(),
//   sigma_ray = ray_sigma_per_z2 * z^2 (depth from disparity: z^2 sigma_d / (f b)),
//   sigma_lat = lateral_sigma_per_z * z (image-plane error: z sigma_px / f).
// Depth errors are several times the lateral ones, so an isotropic weight wastes the precise directions
// (measured on the Mars yard: the rotation error of 6D-VME drops several-fold, see docs/vo.md).
struct StereoPointModel {
  double ray_sigma_per_z2 = 0.0;     // [1/m]
  double lateral_sigma_per_z = 0.0;  // [-]
  double min_sigma_m = 1e-4;         // floor of both sigmas
  // Linearise (and evaluate the covariances) at the fused landmark (true, the default: unbiased when the
  // two ends are one physical point measured with this model's noise) or at the measurements (false:
  // the plain Gauss-Newton). StereoVo uses false for pairs of two independent Harris detections, which
  // the model does not describe (their association error made the fused form worse: docs/vo.md).
  bool fused_linearisation = true;
};

// Gauss-Newton refinement of a 6D motion with the anisotropic stereo covariance of each pair
// (Sigma_i = Sigma(X_i) + R Sigma(R^T (X_i - t)) R^T, evaluated at the fused landmark X_i, the
// maximum-likelihood point given both measurements; the rotation Jacobian is taken at X_i too, which
// makes the gradient that of the likelihood with the landmark eliminated: linearising at the noisy
// measurements biased the rotation, test Rigid6dStereo.IsUnbiasedUnderAnisotropicStereoNoise),
// Huber weights on the Mahalanobis distance (huber_k sigmas),
// fixed iterations (<= 20). Covariance = (J^T W J)^-1 scaled by max(1, chi2 / dof), rotation left-perturbed
// as for estimate_rigid_6d. rms_residual_m is the plain rms. O(iterations * n), no heap. Errors:
// kInvalidArgument (sizes, NaN, model), kDegenerate (< 3 points, singular normal equations).
Result<RigidEstimate> refine_rigid_6d_stereo(Span<const Vec3d> prev, Span<const Vec3d> cur, const RigidEstimate& initial,
                                             const StereoPointModel& model, std::size_t iterations = 5,
                                             double huber_k = 2.5) noexcept;

// Rotation vector (axis * angle) of R, and R from it. Small-angle safe.
Vec3d rotation_log(const Mat3d& R) noexcept;
Mat3d rotation_exp(const Vec3d& w) noexcept;

}  // namespace qnav::motion
