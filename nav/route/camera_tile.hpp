// CameraTileProjector: a downward-looking camera frame as a route tile. Projects a rectified
// (pinhole; lens distortion and the flat-port refraction already removed by nav/vision's RemapTable)
// 8-bit frame onto the flat seabed / ground plane and resamples it into the north-up raster that
// TileFeatureExtractor takes from the side-scan tile builder, so camera routes use the same keypoints,
// route file, registration, filter and guidance as sonar routes (SensorKind::kCamera).
//
// Frames: world is north-east-down (NED) with the ground plane at down = ground_down_m (the vehicle's
// depth + altitude from a DVL / altimeter, or a rover's wheel contact); the camera pose ned_T_cam maps
// camera coordinates (x right, y down in the image, z along the optical axis) to NED. Tile raster:
// the same convention as nav/sonar's SonarTile (row 0 north, columns east, pixel (c, r) centre at
// north = origin_north_m - (r + 0.5) res, east = origin_east_m + (c + 0.5) res), centred on the ground
// point of the optical axis; the tile pose is the camera's nadir (the vehicle's position, as a sonar
// tile's pose is, so guidance's cross-track and side are the vehicle's and not where a rolled or
// pitched camera happens to look: 2 deg of roll at 0.8 m moves the optical axis 2.8 cm) with the
// vehicle's compass heading.
// A raster pixel is covered when its ground point projects inside the image (bilinear sample) and lies
// in front of the camera; the rest is coverage 0 and TileFeatureExtractor ignores it.
// Flat-ground assumption: relief of height h seen from range Z shifts by h/Z of its offset from the
// nadir (3 cm of relief at 0.8 m: < 4 % of the offset).
// Errors (counted): image or output empty or too small, non-finite pose or intrinsics, ground not
// below the camera (the optical axis does not meet the ground in front of it), a tile with no covered
// pixel. Cost O(W H) of the output raster; no heap; no I/O.
#pragma once

#include <cstdint>

#include "nav/core/counters.hpp"
#include "nav/core/geometry.hpp"
#include "nav/core/image.hpp"
#include "nav/core/status.hpp"
#include "nav/route/tile_features.hpp"

namespace qnav::route {

struct CameraIntrinsics {
  double fx_px = 0.0;
  double fy_px = 0.0;
  double cu_px = 0.0;
  double cv_px = 0.0;
};

struct CameraTileConfig {
  double resolution_m = 0.004;  // ground sample of the output raster
  int width_px = 192;           // output raster (<= TileFeatureConfig max_width / max_height)
  int height_px = 192;
  double max_tilt_rad = deg_to_rad(60.0);  // optical axis from straight down beyond this: refused
};

enum class CameraTileCounter : std::uint8_t { kBadInput, kGroundNotVisible, kEmptyTile, kCount };
inline constexpr const char* kCameraTileCounterNames[] = {"camera_bad_input", "camera_ground_not_visible",
                                                          "camera_empty_tile"};

class CameraTileProjector {
 public:
  CameraTileProjector() noexcept : counters_(kCameraTileCounterNames) {}
  // Errors: kInvalidArgument (resolution not positive and finite, raster smaller than 8x8, tilt limit
  // outside (0, 90) deg).
  Status init(const CameraTileConfig& config) noexcept;
  // Fills out (width_px x height_px of the config; a larger view is used from its top-left) and coverage
  // (same size), and geometry (resolution, origin, pose = camera nadir + heading_rad).
  // Returns the covered fraction of the raster.
  Result<double> project(ConstImageViewU8 image, const CameraIntrinsics& k, const Pose3& ned_T_cam, double ground_down_m,
                         double heading_rad, ImageViewF32 out, ImageViewU8 coverage, TileGeometry& geometry) noexcept;
  const CameraTileConfig& config() const noexcept { return config_; }
  const CounterSet<CameraTileCounter>& counters() const noexcept { return counters_; }

 private:
  CameraTileConfig config_{};
  bool ready_ = false;
  CounterSet<CameraTileCounter> counters_;
};

}  // namespace qnav::route
