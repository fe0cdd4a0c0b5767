#include "firmware/pipeline/route_defaults.hpp"

#include <algorithm>
#include <cmath>

namespace qnav::pipeline {

std::size_t keypoint_budget(double length_m, double swath_m, double feature_pixel_m) {
  if (!(length_m > 0.0 && swath_m > 0.0 && feature_pixel_m > 0.0)) return kMinKeypointBudget;
  const double k = std::floor(length_m * swath_m / (feature_pixel_m * feature_pixel_m) / kFeaturePixelsPerKeypoint);
  if (!(k >= static_cast<double>(kMinKeypointBudget))) return kMinKeypointBudget;
  return k >= static_cast<double>(route::kMaxKeypointsPerNode) ? route::kMaxKeypointsPerNode : static_cast<std::size_t>(k);
}

void frame_tiles_by_distance(RouteTileConfig& c, double swath_m, double min_ping_spacing_m, double length_m, double stride_m) {
  const double len = length_m > 0.0 ? length_m : kTileLengthSwaths * swath_m;
  const double str = stride_m > 0.0 ? stride_m : kTileStrideSwaths * swath_m;
  c.tiles.tile_length_m = len;
  c.tiles.tile_stride_m = str;
  const double pings = std::ceil(len / std::max(1e-3, min_ping_spacing_m)) + 2.0;
  c.tiles.scanlines_per_tile = static_cast<int>(std::min(20000.0, std::max(20.0, pings)));
  c.tiles.scanline_stride = c.tiles.scanlines_per_tile;  // unused by distance
  c.features.max_keypoints = keypoint_budget(len, swath_m, c.tiles.resolution_m * c.features.downsample);
}

double tile_age_s(const RouteTileConfig& c, double speed_mps, double ping_rate_hz) {
  return c.tiles.tile_length_m > 0.0 ? 0.5 * c.tiles.tile_length_m / speed_mps : 0.5 * c.tiles.scanlines_per_tile / ping_rate_hz;
}

double tile_age_m(const RouteTileConfig& c) { return c.tiles.tile_length_m > 0.0 ? 0.5 * c.tiles.tile_length_m : 0.0; }

double tile_stride_m(const RouteTileConfig& c, double speed_mps, double ping_rate_hz) {
  if (c.tiles.tile_length_m > 0.0) return c.tiles.tile_stride_m;
  return c.tiles.scanline_stride * speed_mps / ping_rate_hz;
}

RouteTileConfig default_route_tile_config() {
  RouteTileConfig c;
  c.corrector.max_samples_per_side = 1024;
  c.corrector.ground_bins_per_side = 256;
  c.corrector.ground_bin_m = 0.2f;
  c.corrector.nadir_gap_m = 2.0f;
  c.tiles.resolution_m = 0.2;
  c.tiles.tile_width_px = 704;
  c.tiles.tile_height_px = 704;
  c.tiles.max_bins_per_side = 256;
  c.features.max_width = 704;
  c.features.max_height = 704;
  c.features.max_keypoints = 128;     // = kMaxKeypointsPerNode: more keypoints, more of them repeat at large offsets
  c.features.downsample = 3;          // 0.6 m pixels: sand ripples (0.9 m) and speckle average out
  c.features.descriptor_step_px = 2;  // 1.2 m between descriptor samples: 8.4 m footprint
  c.features.blur_radius_px = 2;      // 3 m box on 0.6 m pixels: corners of the seabed texture, not of speckle
  c.features.harris_block_radius = 1;
  c.features.harris_nms_radius = 3;
  c.features.harris_norm_cell_px = 16;
  // The simulator's sonar: 50 m slant range, swath 2 x 50 m -> tiles of 90 m every 60 m, 128 keypoints.
  frame_tiles_by_distance(c, 2.0 * static_cast<double>(default_route_sonar_config().slant_range_m), kMinPingSpacingM);
  return c;
}

RouteTileConfig file_route_tile_config(double range, double ping_spacing_m, double length_m, double stride_m, int lines, int stride) {
  const double bin = std::max(0.02, range / 300.0);
  const double swath = 2.0 * range;
  RouteTileConfig tc = default_route_tile_config();
  tc.corrector.ground_bins_per_side = 300;
  tc.corrector.ground_bin_m = static_cast<float>(bin);
  tc.corrector.nadir_gap_m = static_cast<float>(std::max(0.5, range / 30.0));
  tc.tiles.resolution_m = bin;
  tc.tiles.max_bins_per_side = 300;
  tc.features.downsample = 3;
  tc.features.blur_radius_px = 1;
  int px = 800;
  if (lines > 0) {
    tc.tiles.tile_length_m = 0.0;
    tc.tiles.scanlines_per_tile = lines;
    tc.tiles.scanline_stride = stride > 0 ? stride : lines;
    tc.features.max_keypoints = route::kMaxKeypointsPerNode;
  } else {
    frame_tiles_by_distance(tc, swath, 0.5 * ping_spacing_m, length_m, stride_m);
    // The raster holds the tile turned by 45 degrees (a turn inside the tile), at least 800 px.
    const double side_m = 1.45 * std::max(tc.tiles.tile_length_m, swath);
    px = std::max(800, std::min(2048, 32 * static_cast<int>(std::ceil(side_m / bin / 32.0))));
  }
  tc.tiles.tile_width_px = px;
  tc.tiles.tile_height_px = px;
  tc.features.max_width = px;
  tc.features.max_height = px;
  return tc;
}

sidescan::SideScanSimConfig default_route_sonar_config() {
  sidescan::SideScanSimConfig s;
  s.samples_per_side = 512;
  s.slant_range_m = 50.0f;
  // Speckle partly coherent between pings closer than 0.2 m, as the real Iver2 file's (docs/route.md,
  // "Is that the simulator or the sonar?"); the route's 0.3 m between pings renders as before.
  s.speckle_coherence_m = 0.2f;
  return s;
}

sidescan::SeabedConfig default_route_seabed_config(std::uint64_t seed) {
  sidescan::SeabedConfig c;
  c.seed = seed;
  return c;
}

route::LocaliserConfig default_localiser_config(route::RouteDirection d, std::size_t max_nodes) {
  route::LocaliserConfig c;
  c.filter.max_nodes = max_nodes;
  c.filter.direction = d;
  c.filter.motion = route::MotionModel::kOdometry;
  c.filter.kidnap_floor = 0.01;
  c.filter.lost_after_updates = 1;       // one update with strong similarity elsewhere and none near the estimate
  c.filter.lost_evidence_inliers = 8.0f;  // "strong": no registration with >= 8 inliers was wrong in `qnav route eval`
  c.filter.lost_reset_mass = 0.9;
  c.filter.chance_inliers = 5.0f;  // = min_inliers: a bare-minimum consensus carries no evidence
  c.registration.robust.inlier_threshold_m = 1.5;
  c.registration.robust.min_inliers = 5;
  c.registration.fc.sigma_dist_m = 1.0;
  c.registration.fc.sigma_dir_rad = 0.02;  // compass between passes: bias 0.003-0.004 rad + 0.002 rad noise
  c.registration.fc.max_points = 128;
  c.registration.fc.max_candidates_per_point = 3;
  c.registration.fc.min_appearance = 0.35f;
  c.filter.belief_registrations = 4;
  c.filter.wide_search_registrations = 6;
  c.filter.searching_registrations = 16;  // 2 belief + 14 wide while searching (update <= ~15 ms, 10,000 nodes)
  c.guidance.side_deadband_m = 1.0;
  c.guidance.min_inliers = 7;  // chance_inliers + 2: at 5-6 inliers the side was wrong on 8-30% of tiles
  c.guidance.dead_reckon_max_m = 150.0;  // ~2.5 nodes of travel steered on dead reckoning after the last fix
  c.guidance.dead_reckon_side_max_m = 450.0;  // ~7.5 nodes over which the dead-reckoned side is still reported
  c.guidance.dead_reckon_heading_sigma_rad = 0.025;  // measured: dead-reckoned cross-track error vs travel, `route eval`
  c.guidance.unconfident_min_inliers = 8;  // = lost_evidence_inliers: no registration this strong was wrong in `qnav route eval`
  // A registration more than 10 m + 3 sigma from where dead reckoning from the last fix puts the
  // vehicle needs a second one to confirm it (issue 27: a 7-inlier wrong transform 75 m across at
  // 2 pings/s gave 3 wrong sides; DVL dropouts and 1-2 deg of compass bias stay well inside 10 m).
  c.guidance.verify_gate_m = 10.0;
  c.guidance.verify_n_sigma = 3.0;
  return c;
}

// Registration on real tiles at 0.1 m: tighter positions than the simulator's 0.6 m feature pixels.
route::LocaliserConfig file_localiser_config(route::RouteDirection d, std::size_t max_nodes, std::size_t nodes, double spacing_m) {
  route::LocaliserConfig lc = default_localiser_config(d, max_nodes);
  lc.guidance.dead_reckon_max_m = 2.5 * spacing_m;  // as in the simulator: ~2.5 nodes after the last fix
  lc.guidance.dead_reckon_side_max_m = 7.5 * spacing_m;  // ... and ~7.5 nodes for the side
  lc.guidance.verify_gate_m = spacing_m / 6.0;            // as in the simulator: 10 m at 60 m between nodes
  lc.filter.belief_registrations = static_cast<std::uint32_t>(std::max<std::size_t>(1, std::min<std::size_t>(nodes, 8)));
  lc.registration.robust.inlier_threshold_m = 0.75;
  lc.registration.fc.sigma_dist_m = 0.5;
  return lc;
}

route::RouteParams route_params_for(route::SensorKind sensor, double spacing_m, double tile_length_m, double tile_width_m, double pixel_m,
                                   const route::TileFeatureConfig& f) {
  route::RouteParams p;
  p.sensor = sensor;
  p.depth_m = 0.0f;
  p.node_spacing_m = static_cast<float>(spacing_m);
  p.tile_length_m = static_cast<float>(tile_length_m);
  p.tile_width_m = static_cast<float>(tile_width_m);
  p.pixel_m = static_cast<float>(pixel_m);
  p.max_keypoints = static_cast<std::uint16_t>(f.max_keypoints);
  p.harris_window_px = static_cast<std::uint16_t>(2 * f.harris_block_radius + 1);
  p.keypoint_min_distance_px = static_cast<std::uint16_t>(f.harris_nms_radius);
  return p;
}

route::RouteParams side_scan_route_params(const RouteTileConfig& c, double spacing_m, double swath_m) {
  return route_params_for(route::SensorKind::kSideScan, spacing_m, c.tiles.tile_length_m > 0.0 ? c.tiles.tile_length_m : spacing_m, swath_m,
                          c.tiles.resolution_m, c.features);
}

}  // namespace qnav::pipeline
