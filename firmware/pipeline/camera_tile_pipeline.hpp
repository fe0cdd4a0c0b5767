// CameraTilePipeline: the per-frame wiring of the route on a downward camera (SensorKind::kCamera),
// the camera's counterpart of RouteTilePipeline: one rectified downward frame + the camera's pose (NED:
// its attitude; its height over the ground plane at ground_down_m) + the compass heading ->
// nav/route CameraTileProjector (north-up ground raster + coverage, the tile pose at the camera nadir)
// -> TileFeatureExtractor -> a route node whose tile pose is moved into the pass's navigation frame.
// `qnav route camera` (teach and repeat over the synthetic Mars yard) runs it; the repeat of its tiles
// is the repeat component (RouteRepeatSession) as for side-scan tiles.
// Settings: camera_tile_settings() (4 mm raster of 192 x 192 px, the feature settings tuned for it);
// camera_route_params() the route file header for them.
// Memory: init() allocates the raster and coverage (width x height x 5 bytes) and the extractor's
// arena; push_frame() allocates nothing. Time: one projection (O(raster pixels)) + one feature
// extraction (O(raster pixels) + the keypoint budget's descriptors).
#pragma once

#include <memory>

#include "nav/core/arena.hpp"
#include "nav/core/geometry.hpp"
#include "nav/core/image.hpp"
#include "nav/core/status.hpp"
#include "nav/route/camera_tile.hpp"
#include "nav/route/route_types.hpp"
#include "nav/route/tile_features.hpp"

namespace qnav::pipeline {

struct CameraTileSettings {
  route::CameraTileConfig projector{};  // the raster (its size is the extractor's largest tile)
  route::TileFeatureConfig features{};
};
// The tuned settings of the camera route: 4 mm pixels, 192 x 192 (0.77 m square), up to 128 keypoints,
// no downsampling (grains of 8 mm and rock rims give the corners), blur 1, NMS radius 4, norm cell 32.
CameraTileSettings camera_tile_settings();
// The route file header for tiles of these settings, nodes node_spacing_m apart, the camera's ground
// footprint footprint_across_m wide.
route::RouteParams camera_route_params(const CameraTileSettings& s, double node_spacing_m, double footprint_across_m);

struct CameraFrame {
  ConstImageViewU8 image;                 // rectified downward frame
  route::CameraIntrinsics intrinsics{};
  Pose3 ned_T_cam{};                      // the camera's pose (attitude, height) over the ground plane
  double ground_down_m = 0.0;             // the ground plane's down coordinate in ned_T_cam's frame
  double heading_rad = 0.0;               // the compass heading the tile is drawn north-up with
  // The projection's ground frame in the pass's navigation frame: the tile's position is mapped by it
  // (its heading stays heading_rad). Identity when ned_T_cam is already the navigation pose.
  Pose2 nav_T_ground{};
};

class CameraTilePipeline {
 public:
  Status init(const CameraTileSettings& settings);
  // One frame -> out (keypoints, meta.pose in the navigation frame; along_m and index are the
  // caller's). ground_pose (optional): the tile's pose in the projection's frame (a simulator's truth).
  // Errors: the projector's (a frame tilted beyond its limit, a bad pose) and the extractor's.
  Status push_frame(const CameraFrame& frame, route::RouteNode& out, Pose2* ground_pose = nullptr);
  const CameraTileSettings& settings() const noexcept { return settings_; }
  const route::CameraTileProjector& projector() const noexcept { return projector_; }
  const route::TileFeatureExtractor& features() const noexcept { return features_; }

 private:
  CameraTileSettings settings_{};
  route::CameraTileProjector projector_;
  route::TileFeatureExtractor features_;
  std::unique_ptr<ArenaStorage> arena_;
  Image<float> raster_;
  Image<std::uint8_t> coverage_;
};

}  // namespace qnav::pipeline
