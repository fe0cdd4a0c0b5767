// Rectification / undistortion / flat-port refraction by lookup table (Mars paper: "dense correction
// maps"; underwater paper eq. 1 "implemented as a LUT").
//
// Camera model (EuRoC sensor.yaml): pinhole fx, fy, cx, cy + radial-tangential distortion k1, k2, p1, p2
// (the OpenCV/Bouguet model). RemapTable::build() computes, once at start-up, for every output pixel
// the source position in the raw image:
//   output pixel (u, v) -> ray K_out^-1 (u, v, 1) -> rotate into the raw camera frame (R_out_to_cam)
//   -> [refraction, underwater eq. 1, flat port with index ratio n: a ray at angle t in water enters
//       the housing at angle asin(n sin t): r_air = tan(asin(n * sin(atan(r_water))))]
//   -> radial-tangential distortion -> K_raw -> source (x, y).
// The output image is then a distortion-free, refraction-free pinhole image (a "water pinhole"
// camera when refraction is on). apply() does bilinear sampling with 8-bit fixed-point weights: the
// table is the only per-frame cost. Output pixels whose source falls outside the raw image get
// fill_value.
// Memory (Arena): 8 bytes per output pixel (int32 source offset + two 8-bit bilinear fractions + flag).
// build(): O(W*H) with trig per pixel (start-up only). apply(): O(W*H), no allocation.
//
// stereo_rectify(): Bouguet-style rectification of a calibrated pair: both cameras rotated half the
// relative rotation each, then about the baseline so that it lies along +x; a common K_rect with the
// mean focal length and principal point chosen so that the valid area is centred (no scaling search).
#pragma once

#include <cstddef>
#include <cstdint>

#include "nav/core/arena.hpp"
#include "nav/core/geometry.hpp"
#include "nav/core/image.hpp"
#include "nav/core/span.hpp"
#include "nav/core/status.hpp"

namespace qnav::vision {

struct PinholeRadTan {
  double fx = 0.0, fy = 0.0, cx = 0.0, cy = 0.0;  // pixels
  double k1 = 0.0, k2 = 0.0, p1 = 0.0, p2 = 0.0;  // radial-tangential distortion
  int width = 0, height = 0;                      // raw image size, pixels
};

// A camera without distortion: focal length f (pixels, fx = fy), principal point (cx, cy), size.
inline PinholeRadTan ideal_pinhole(double f, double cx, double cy, int width, int height) noexcept {
  PinholeRadTan k;
  k.fx = k.fy = f;
  k.cx = cx;
  k.cy = cy;
  k.width = width;
  k.height = height;
  return k;
}

// Underwater paper eq. 1: flat port, ray angle in water t_w, in air t_a = asin(n sin t_w).
struct FlatPortRefraction {
  bool enabled = false;
  double index_ratio = 1.33;  // n_water / n_air
};

// Checks a camera: finite values, fx, fy > 0, size within kMaxImageSide. kInvalidArgument / kDegenerate.
Status validate(const PinholeRadTan& cam) noexcept;

// Applies distortion to a normalised ray coordinate (x, y) = (X/Z, Y/Z) -> distorted normalised coords.
Vec2d distort_normalised(const PinholeRadTan& cam, const Vec2d& xy) noexcept;
// Inverse of distort_normalised by fixed-point iteration (max_iterations bounded, default 20);
// returns false if it did not converge to 1e-9.
bool undistort_normalised(const PinholeRadTan& cam, const Vec2d& xy_distorted, Vec2d& xy, int max_iterations = 20) noexcept;
// Refraction of eq. 1 on a normalised radius: tan(asin(n sin(atan(r)))); false when the ray is past
// the critical angle (n sin(atan r) >= 1).
bool refract_radius(double r_water, double index_ratio, double& r_air) noexcept;

// Raw pixel -> rectified pixel for a single point (iterative undistortion, inverse refraction);
// for mapping corners found on raw images. false when the point cannot be mapped.
bool rectify_point(const PinholeRadTan& cam, const Mat3d& R_out_to_cam, const Mat3d& K_out, const FlatPortRefraction& port,
                   const Vec2d& raw_px, Vec2d& out_px) noexcept;

struct RemapConfig {
  int max_width = 1280;  // largest output image
  int max_height = 1024;
  std::uint8_t fill_value = 0;  // output grey where the source is outside the raw image
};

class RemapTable {
 public:
  // Bytes init() takes from an arena for this configuration (8 per output pixel), alignment included.
  static std::size_t arena_bytes(const RemapConfig& config) noexcept;
  Status init(const RemapConfig& config, Arena& arena) noexcept;
  // Builds the table for an output image out_width x out_height with intrinsics K_out (3x3, upper
  // triangular, finite, fx, fy > 0), rotation R_out_to_cam (orthonormal, det +1) from the output
  // (rectified) camera frame to the raw camera frame, and optional refraction.
  // Errors: kNotReady, kInvalidArgument (NaN, bad sizes, non-rotation), kDegenerate (singular K).
  Status build(const PinholeRadTan& raw, const Mat3d& K_out, const Mat3d& R_out_to_cam, const FlatPortRefraction& port,
               int out_width, int out_height) noexcept;
  // Convenience: plain undistortion (identity rotation, K_out = K_raw, same size).
  Status build_undistort(const PinholeRadTan& raw, const FlatPortRefraction& port) noexcept;

  // Samples src (must be raw.width x raw.height) into dst (must be out_width x out_height).
  Status apply(ConstImageViewU8 src, ImageViewU8 dst) const noexcept;
  // Source position of output pixel (x, y) as stored in the table (8-bit fractions); false outside.
  bool source_of(int x, int y, float& sx, float& sy) const noexcept;
  int out_width() const noexcept { return out_w_; }
  int out_height() const noexcept { return out_h_; }
  // Number of output pixels whose source is inside the raw image (after build()).
  std::size_t valid_pixels() const noexcept { return valid_; }

 private:
  struct Entry {
    std::int32_t offset;  // y0 * raw_width + x0 of the bilinear 2x2's top-left pixel (0 when outside)
    std::uint8_t fx, fy;  // bilinear fractions in 1/256
    std::uint8_t valid;   // 0: source outside the raw image (fill_value)
    std::uint8_t pad;
  };
  RemapConfig config_{};
  bool ready_ = false;
  Span<Entry> table_;
  int out_w_ = 0, out_h_ = 0, raw_w_ = 0, raw_h_ = 0;
  std::size_t valid_ = 0;
};

struct StereoRectification {
  Mat3d R_left = Mat3d::Identity();   // rectified-left frame -> raw left camera frame (R_out_to_cam)
  Mat3d R_right = Mat3d::Identity();  // rectified-right frame -> raw right camera frame
  Mat3d K = Mat3d::Identity();        // common rectified intrinsics
  double baseline_m = 0.0;            // |t|, right camera at +baseline along rectified x
  int width = 0, height = 0;          // rectified image size
};

// T_left_right maps points from the right camera frame into the left camera frame
// (p_left = R p_right + t); for EuRoC: inv(T_BS_cam0) * T_BS_cam1.
// Errors: kInvalidArgument (NaN, non-rotation), kDegenerate (zero baseline, singular intrinsics).
Result<StereoRectification> stereo_rectify(const PinholeRadTan& left, const PinholeRadTan& right, const Pose3& T_left_right,
                                           int out_width, int out_height) noexcept;

}  // namespace qnav::vision
