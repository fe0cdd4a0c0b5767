// Host-side tile pipeline for the route tools: side-scan pings (simulated, or from an XTF file) ->
// ScanlineCorrector -> TileBuilder (north-up tiles on the nav pose) -> TileFeatureExtractor ->
// a route node (keypoints in the tile frame, tile pose in the pass's dead-reckoned frame), plus the
// ground truth when the pass is simulated. Used by `qnav route train|repeat|eval` and the demo.
// Not flight code: it owns its arena and std::function sinks; the nav stages inside it are the
// flight ones. Header-only: it is compiled into the qnav tool, which links drivers/sidescan and
// nav/route after qnav_tools (a .cpp in qnav_tools could not reach them in link order).
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "drivers/sidescan/sim_seabed.hpp"
#include "drivers/sidescan/sim_sidescan.hpp"
#include "drivers/sidescan/sim_trajectory.hpp"
#include "nav/core/arena.hpp"
#include "nav/core/status.hpp"
#include "nav/route/route_types.hpp"
#include "nav/route/tile_features.hpp"
#include "nav/sonar/scanline_corrector.hpp"
#include "nav/sonar/tile_builder.hpp"

namespace qnav::tools {

struct RouteTile {
  route::RouteNode node;           // keypoints + meta (pose = nav pose of the tile, along_m = nav distance)
  double nav_step_m = 0.0;         // nav distance travelled since the previous tile of the pass
  double truth_along_m = -1.0;     // simulated passes: along-route distance of the tile centre
  double truth_lateral_m = 0.0;    // simulated passes: offset right of the route's forward direction
  Pose2 truth_pose{};              // simulated passes: true pose at the tile's pose ping (keypoint
                                   // truth position ~ truth_pose.apply(keypoint), dead-reckoning drift aside)
  bool has_truth_pose = false;
  float coverage_fraction = 0.0f;
  std::uint32_t tile_index = 0;
};

struct RouteTileConfig {
  sonar::ScanlineCorrectorConfig corrector;
  sonar::TileBuilderConfig tiles;
  route::TileFeatureConfig features;
};

// Defaults tuned for the simulator at 5 Hz / 1.5 m/s: 0.2 m raster 704 x 704 (141 m square),
// 300 scanlines per tile (90 m of track) every 200 scanlines (60 m node spacing), so a sensed tile
// never overlaps its nearest node by less than two thirds along track; ground bins 0.2 m x 256.
RouteTileConfig default_route_tile_config();
sidescan::SideScanSimConfig default_route_sonar_config();
sidescan::SeabedConfig default_route_seabed_config(std::uint64_t seed);

using RouteTileSink = std::function<bool(const RouteTile&)>;  // return false to stop the pass

class RouteTilePipeline {
 public:
  Status init(const RouteTileConfig& config);
  // Flies a simulated pass over the seabed; calls sink for every tile.
  Status run_sim_pass(const sidescan::Seabed& seabed, const sidescan::SideScanSimConfig& sonar,
                      const sidescan::TrajectoryConfig& trajectory, const RouteTileSink& sink);
  // Feeds one raw ping at its nav pose (XTF replay); emits finished tiles to sink.
  Status push_ping(const sonar::SonarPing& ping, const Pose2& nav_pose, const RouteTileSink& sink, bool* stop);
  Status flush(const RouteTileSink& sink);
  void reset_pass();
  const RouteTileConfig& config() const noexcept { return cfg_; }
  const sonar::TileBuilder& builder() const noexcept { return *builder_; }
  const route::TileFeatureExtractor& features() const noexcept { return *features_; }
  // The last tile's raster (for debug images).
  const sonar::SonarTile& last_tile() const noexcept { return builder_->tile(); }

 private:
  Status emit(const RouteTileSink& sink, bool* stop);
  RouteTileConfig cfg_{};
  std::unique_ptr<ArenaStorage> arena_;
  std::unique_ptr<sonar::ScanlineCorrector> corrector_;
  std::unique_ptr<sonar::TileBuilder> builder_;
  std::unique_ptr<route::TileFeatureExtractor> features_;
  std::unique_ptr<RouteTile> tile_;
  // per-pass state
  std::vector<double> ping_along_m_;   // truth along-route per ping (sim)
  std::vector<Pose2> ping_truth_;      // true pose per ping (sim)
  std::vector<double> ping_nav_dist_m_;  // nav distance per ping from the pass start
  double truth_lateral_m_ = 0.0;
  double last_tile_nav_m_ = 0.0;
  bool have_prev_nav_ = false;
  Pose2 prev_nav_{};
  double nav_dist_m_ = 0.0;
};

// ---- implementation ----
inline RouteTileConfig default_route_tile_config() {
  RouteTileConfig c;
  c.corrector.max_samples_per_side = 1024;
  c.corrector.ground_bins_per_side = 256;
  c.corrector.ground_bin_m = 0.2f;
  c.corrector.nadir_gap_m = 2.0f;
  c.tiles.resolution_m = 0.2;
  c.tiles.tile_width_px = 704;
  c.tiles.tile_height_px = 704;
  c.tiles.scanlines_per_tile = 300;  // 90 m of track: tiles overlap their neighbours by half a node
  c.tiles.scanline_stride = 200;
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
  return c;
}

inline sidescan::SideScanSimConfig default_route_sonar_config() {
  sidescan::SideScanSimConfig s;
  s.samples_per_side = 512;
  s.slant_range_m = 50.0f;
  return s;
}

inline sidescan::SeabedConfig default_route_seabed_config(std::uint64_t seed) {
  sidescan::SeabedConfig c;
  c.seed = seed;
  return c;
}

inline Status RouteTilePipeline::init(const RouteTileConfig& config) {
  cfg_ = config;
  const std::size_t bytes = sonar::ScanlineCorrector::arena_bytes(config.corrector) + sonar::TileBuilder::arena_bytes(config.tiles) +
                            route::TileFeatureExtractor::arena_bytes(config.features) + 4096;
  arena_ = std::make_unique<ArenaStorage>(bytes);
  if (!arena_->valid()) return Status(StatusCode::kCapacityExceeded, "route tiles: cannot allocate arena");
  corrector_ = std::make_unique<sonar::ScanlineCorrector>();
  builder_ = std::make_unique<sonar::TileBuilder>();
  features_ = std::make_unique<route::TileFeatureExtractor>();
  tile_ = std::make_unique<RouteTile>();
  QNAV_RETURN_IF_ERROR(corrector_->init(config.corrector, *arena_));
  QNAV_RETURN_IF_ERROR(builder_->init(config.tiles, *arena_));
  QNAV_RETURN_IF_ERROR(features_->init(config.features, *arena_));
  reset_pass();
  return Status::ok();
}

inline void RouteTilePipeline::reset_pass() {
  if (builder_) builder_->reset();
  ping_along_m_.clear();
  ping_truth_.clear();
  ping_nav_dist_m_.clear();
  last_tile_nav_m_ = 0.0;
  have_prev_nav_ = false;
  nav_dist_m_ = 0.0;
  truth_lateral_m_ = 0.0;
}

inline Status RouteTilePipeline::emit(const RouteTileSink& sink, bool* stop) {
  const sonar::SonarTile& t = builder_->tile();
  RouteTile& out = *tile_;
  route::TileGeometry g;
  g.resolution_m = t.resolution_m;
  g.origin_north_m = t.origin_north_m;
  g.origin_east_m = t.origin_east_m;
  g.pose = t.pose;
  const Status s = features_->extract(t.intensity, t.coverage, g, out.node);
  if (!s && s.code() != StatusCode::kEmpty) return s;
  const std::uint32_t mid = (t.first_ping + t.last_ping) / 2;
  out.node.meta.stamp_ns = (t.first_stamp_ns + t.last_stamp_ns) / 2;
  out.node.meta.along_m = mid < ping_nav_dist_m_.size() ? ping_nav_dist_m_[mid] : nav_dist_m_;
  out.nav_step_m = out.node.meta.along_m - last_tile_nav_m_;
  last_tile_nav_m_ = out.node.meta.along_m;
  out.truth_along_m = mid < ping_along_m_.size() ? ping_along_m_[mid] : -1.0;
  out.truth_lateral_m = truth_lateral_m_;
  const std::uint32_t pose_ping = t.first_ping + (t.last_ping - t.first_ping + 1) / 2;  // the builder's pose slot
  out.has_truth_pose = pose_ping < ping_truth_.size();
  out.truth_pose = out.has_truth_pose ? ping_truth_[pose_ping] : Pose2{};
  out.coverage_fraction = t.coverage_fraction;
  out.tile_index = t.index;
  if (!sink(out) && stop != nullptr) *stop = true;
  return Status::ok();
}

inline Status RouteTilePipeline::push_ping(const sonar::SonarPing& ping, const Pose2& nav, const RouteTileSink& sink, bool* stop) {
  if (have_prev_nav_) nav_dist_m_ += std::hypot(nav.x_m - prev_nav_.x_m, nav.y_m - prev_nav_.y_m);
  prev_nav_ = nav;
  have_prev_nav_ = true;
  if (ping.ping_number >= ping_nav_dist_m_.size()) ping_nav_dist_m_.resize(ping.ping_number + 1, nav_dist_m_);
  ping_nav_dist_m_[ping.ping_number] = nav_dist_m_;
  sonar::CorrectedScanline line;
  const Status cs = corrector_->correct(ping, line);
  if (!cs) return Status::ok();  // counted by the corrector; the ping is skipped
  Result<bool> built = builder_->push(line, nav);
  if (!built) return Status::ok();  // counted by the builder
  if (*built) return emit(sink, stop);
  return Status::ok();
}

inline Status RouteTilePipeline::flush(const RouteTileSink& sink) {
  Result<bool> built = builder_->flush(builder_->config().scanlines_per_tile / 2);
  if (built && *built) return emit(sink, nullptr);
  return Status::ok();
}

inline Status RouteTilePipeline::run_sim_pass(const sidescan::Seabed& seabed, const sidescan::SideScanSimConfig& sonar_cfg,
                                       const sidescan::TrajectoryConfig& trajectory, const RouteTileSink& sink) {
  reset_pass();
  truth_lateral_m_ = trajectory.lateral_offset_m;
  sidescan::Trajectory traj;
  QNAV_RETURN_IF_ERROR(traj.init(trajectory));
  auto sim = std::make_unique<sidescan::SideScanSimulator>();
  QNAV_RETURN_IF_ERROR(sim->init(sonar_cfg, &seabed));
  sidescan::TrajectorySample s;
  bool stop = false;
  while (!stop && traj.next(s)) {
    Result<sonar::SonarPing> p = sim->ping(s.truth, s.altitude_m, s.index, s.stamp_ns);
    if (!p) return p.status();
    sonar::SonarPing ping = *p;
    ping.ping_number = s.index;
    ping.altitude_m = s.altitude_m;
    if (s.index >= ping_along_m_.size()) ping_along_m_.resize(s.index + 1, s.along_route_m);
    ping_along_m_[s.index] = s.along_route_m;
    if (s.index >= ping_truth_.size()) ping_truth_.resize(s.index + 1, s.truth);
    ping_truth_[s.index] = s.truth;
    QNAV_RETURN_IF_ERROR(push_ping(ping, s.nav, sink, &stop));
  }
  return Status::ok();
}

}  // namespace qnav::tools
