// StereoMatcher: stereo correlation at corners on a rectified pair, then 3D points with a per-point
// depth uncertainty (Mars paper, section 3 and eq. 1).
//
// Conventions: rectified images, same rows; a point at column xl in the left image is at
// xr = xl - d in the right image, d > 0 (the paper writes p_r(u + d, v) with the opposite sign).
// For each left corner (sub-pixel position rounded to the nearest pixel):
//  1. ZNCC of the (2r+1)^2 left patch with right patches at d = min_disparity_px .. max_disparity_px
//     along the same row (patches without texture, stddev < min_patch_stddev, are rejected);
//  2. reject if the best ZNCC < min_zncc (weak), if the best d is on the edge of the range, or if
//     another peak at |d - d_best| > 1 has ZNCC > best - uniqueness_margin (ambiguous);
//  3. left-right check: the right patch at xr searched back along the left row must find xl within
//     left_right_tolerance_px;
//  4. sub-pixel d from a parabola through the ZNCC at d_best-1, d_best, d_best+1 (|offset| <= 0.5)
//     (the disparity measured at round(x) is used for the sub-pixel corner x: depth is smooth at 1 px);
//  5. Z = b f / d, X = (x - cu) Z / f, Y = (y - cv) Z / f  (eq. 1 with f/wpix = focal_px),
//     sigma_Z = Z^2 / (b f) * disparity_sigma_px (first-order propagation of the disparity error).
// Cost per corner: O((max_d - min_d + 1) * (2r+1)^2) twice (forward + left-right); no allocation.
// Every rejection increments its named counter; no NaN is ever written.
#pragma once

#include <cstdint>

#include "nav/core/arena.hpp"
#include "nav/core/fixed_vector.hpp"
#include "nav/core/geometry.hpp"
#include "nav/core/image.hpp"
#include "nav/core/span.hpp"
#include "nav/core/status.hpp"
#include "nav/vision/corner.hpp"
#include "nav/vision/counters.hpp"

namespace qnav::vision {

// A rectified stereo pair: focal length in pixels (= f / wpix of the Mars paper), principal point
// of the left rectified image, baseline in metres.
struct StereoCamera {
  double focal_px = 0.0;
  double cu_px = 0.0;
  double cv_px = 0.0;
  double baseline_m = 0.0;
};

struct StereoConfig {
  int patch_radius = 3;             // ZNCC window (2r+1)^2
  int min_disparity_px = 1;         // search range (inclusive), pixels, >= 0
  int max_disparity_px = 64;        // <= kMaxDisparityRange - 1 + min_disparity_px
  float min_zncc = 0.8f;            // weak-match threshold
  float uniqueness_margin = 0.05f;  // second peak must be below best - margin
  bool left_right_check = true;
  float left_right_tolerance_px = 1.0f;
  float min_patch_stddev = 2.0f;    // grey levels; flatter patches are rejected
  float disparity_sigma_px = 0.3f;  // 1-sigma disparity error used for sigma_z_m
};

struct StereoPoint {
  float x_px = 0.0f;          // left image position (the corner's)
  float y_px = 0.0f;
  float disparity_px = 0.0f;  // sub-pixel, > 0
  float zncc = 0.0f;          // best correlation
  Vec3f p_m = Vec3f::Zero();  // 3D point in the left rectified camera frame (x right, y down, z fwd)
  float sigma_z_m = 0.0f;     // 1-sigma depth uncertainty
  std::uint32_t corner_index = 0;  // index into the corners passed to match()
};

// Z, X, Y from eq. 1 of the Mars paper; false (and nothing written) when d <= 0 or the camera is invalid.
bool triangulate(const StereoCamera& cam, float x_px, float y_px, float disparity_px, Vec3f& p_m) noexcept;
// sigma_Z = Z^2 / (b f) * sigma_d.
float depth_sigma_m(const StereoCamera& cam, float z_m, float disparity_sigma_px) noexcept;

class StereoMatcher {
 public:
  static constexpr int kMaxDisparityRange = 512;  // entries in the per-corner score buffer

  StereoMatcher() noexcept : counters_(kVisionCounterNames) {}
  // Validates config and camera (finite, focal > 0, baseline > 0, ranges sane). No arena needed:
  // the per-corner buffers are inline (kMaxDisparityRange scores, window correlations and twice that
  // of prefix sums: about 10 KB).
  Status init(const StereoConfig& config, const StereoCamera& camera) noexcept;

  // Matches every corner (in order) and appends accepted points to out (out is cleared first).
  // left and right must have the same size. Returns ok even when some corners are rejected
  // (see counters()); kCapacityExceeded when out filled up before the last corner (the points that
  // fit are kept); kNotReady before init(); kInvalidArgument for bad images.
  Status match(ConstImageViewU8 left, ConstImageViewU8 right, Span<const Corner> corners,
               BoundedVector<StereoPoint>& out) noexcept;

  // Matches one left pixel; the building block of match(). On success fills disparity and zncc.
  Status match_one(ConstImageViewU8 left, ConstImageViewU8 right, float x_px, float y_px, float& disparity_px,
                   float& zncc) noexcept;

  const StereoConfig& config() const noexcept { return config_; }
  const StereoCamera& camera() const noexcept { return camera_; }
  const VisionCounters& counters() const noexcept { return counters_; }

 private:
  StereoConfig config_{};
  StereoCamera camera_{};
  bool ready_ = false;
  float scores_[kMaxDisparityRange] = {};
  // Column prefix sums of the band searched (grey levels and their squares): one window per disparity
  // plus the patch width (<= 15) plus the leading 0.
  std::int32_t prefix_sum_[kMaxDisparityRange + 16] = {};
  std::int32_t prefix_sq_[kMaxDisparityRange + 16] = {};
  std::int32_t cross_[kMaxDisparityRange] = {};  // sum(t v) of each window of the scan (cross_run)
  VisionCounters counters_;
};

}  // namespace qnav::vision
