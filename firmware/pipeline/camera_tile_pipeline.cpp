#include "firmware/pipeline/camera_tile_pipeline.hpp"

#include <utility>

#include "firmware/pipeline/route_defaults.hpp"

namespace qnav::pipeline {

CameraTileSettings camera_tile_settings() {
  CameraTileSettings s;  // projector: 4 mm raster, 192 x 192 (0.77 m square)
  s.features.max_width = s.projector.width_px;
  s.features.max_height = s.projector.height_px;
  s.features.max_keypoints = 128;
  s.features.downsample = 1;  // 4 mm pixels: grains (8 mm) and rock rims give the corners
  s.features.blur_radius_px = 1;
  s.features.harris_nms_radius = 4;
  s.features.harris_norm_cell_px = 32;
  return s;
}

route::RouteParams camera_route_params(const CameraTileSettings& s, double node_spacing_m, double footprint_across_m) {
  return route_params_for(route::SensorKind::kCamera, node_spacing_m, s.projector.height_px * s.projector.resolution_m, footprint_across_m,
                          s.projector.resolution_m, s.features);
}

Status CameraTilePipeline::init(const CameraTileSettings& settings) {
  settings_ = settings;
  QNAV_RETURN_IF_ERROR(projector_.init(settings.projector));
  arena_ = std::make_unique<ArenaStorage>(route::TileFeatureExtractor::arena_bytes(settings.features));
  if (!arena_->valid()) return Status(StatusCode::kCapacityExceeded, "camera tiles: cannot allocate the feature arena");
  QNAV_RETURN_IF_ERROR(features_.init(settings.features, *arena_));
  Result<Image<float>> r = Image<float>::allocate(settings.projector.width_px, settings.projector.height_px);
  if (!r) return r.status();
  raster_ = std::move(r.value());
  Result<Image<std::uint8_t>> c = Image<std::uint8_t>::allocate(settings.projector.width_px, settings.projector.height_px);
  if (!c) return c.status();
  coverage_ = std::move(c.value());
  return Status::ok();
}

Status CameraTilePipeline::push_frame(const CameraFrame& f, route::RouteNode& out, Pose2* ground_pose) {
  route::TileGeometry g;
  const Result<double> cov = projector_.project(f.image, f.intrinsics, f.ned_T_cam, f.ground_down_m, f.heading_rad, raster_.view(), coverage_.view(), g);
  if (!cov) return cov.status();
  if (ground_pose != nullptr) *ground_pose = g.pose;
  // The tile in the navigation frame: its position mapped, the raster's origin moved with it.
  const Vec2d nav = f.nav_T_ground.apply(Vec2d(g.pose.x_m, g.pose.y_m));
  g.origin_north_m += nav.x() - g.pose.x_m;
  g.origin_east_m += nav.y() - g.pose.y_m;
  g.pose.x_m = nav.x();
  g.pose.y_m = nav.y();
  return features_.extract(raster_.view(), coverage_.view(), g, out);
}

}  // namespace qnav::pipeline
