// Stereo sequence layouts and calibration files (host-side only, for the tool and tests).
//  - KITTI (our copy in shared/data/stereo/kitti_*): left/NNNNNNNNNN.png, right/NNNNNNNNNN.png with
//    the same names, optional calib.txt ("key value" lines: width, height, f, cu, cv, baseline_m).
//    Frames are the sorted file names present in both folders; stamps are the frame index * 1e8 ns
//    (10 Hz) since the copy has no timestamps file.
//  - EuRoC/ASL: mav0-like folder with cam0/ and cam1/, each with data.csv ("#timestamp [ns],filename"
//    lines) and data/<file>, plus sensor.yaml. Frames are the timestamps present in both data.csv files.
//  - EuRoC sensor.yaml: intrinsics [fu, fv, cu, cv], distortion_coefficients [k1, k2, p1, p2],
//    resolution [w, h], T_BS (4x4 row-major, camera -> body); models other than pinhole +
//    radial-tangential are rejected (kUnsupported).
// These use std::string/std::vector (host code; allocate freely, never in the daemon's hot path).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "nav/core/geometry.hpp"
#include "nav/core/status.hpp"
#include "nav/vision/rectify.hpp"

namespace qnav::tools {

struct StereoFrame {
  std::int64_t stamp_ns = 0;
  std::string left_path;
  std::string right_path;
};

struct KittiCalib {
  int width = 0, height = 0;
  double f_px = 0.0, cu_px = 0.0, cv_px = 0.0, baseline_m = 0.0;
};

struct EurocCamera {
  vision::PinholeRadTan model;  // intrinsics, distortion, resolution
  Pose3 T_BS;                   // camera -> body (p_body = R p_cam + t)
  double rate_hz = 0.0;
};

// Reads a KITTI-layout folder (dir/left, dir/right). Errors: kIoError, kNotFound (no common frames).
Status read_kitti_sequence(const std::string& dir, std::vector<StereoFrame>& frames) noexcept;
// Reads dir/calib.txt. Errors: kIoError, kCorrupt (missing key / not a number), kInvalidArgument (<= 0).
Result<KittiCalib> read_kitti_calib(const std::string& path) noexcept;

// Reads an EuRoC/ASL folder (dir/cam0, dir/cam1). Errors: kIoError, kCorrupt, kNotFound.
Status read_euroc_sequence(const std::string& dir, std::vector<StereoFrame>& frames) noexcept;
// Reads one camera's sensor.yaml. Errors: kIoError, kCorrupt, kUnsupported, kInvalidArgument (NaN,
// non-positive focal length, T_BS rotation not orthonormal).
Result<EurocCamera> read_euroc_camera(const std::string& path) noexcept;
// Reads an OpenCV / ROS camera_info YAML (image_width, image_height, camera_matrix data (9),
// distortion_model plumb_bob, distortion_coefficients data (4 or 5; k3 must be 0)), read bounded at
// 1 MiB. Errors: kIoError, kCorrupt (a key missing or not numbers), kUnsupported (k3 != 0, another
// distortion model), kInvalidArgument (vision::validate refuses the model).
Result<vision::PinholeRadTan> read_opencv_camera(const std::string& path) noexcept;
// Stereo extrinsics from two sensor.yaml: T_left_right = inv(T_BS_left) * T_BS_right.
Pose3 euroc_stereo_extrinsics(const EurocCamera& left, const EurocCamera& right) noexcept;

}  // namespace qnav::tools
