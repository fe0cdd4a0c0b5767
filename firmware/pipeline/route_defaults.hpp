// The tuned settings of route teach and repeat, defined once. qnavd's configuration starts from
// these (docs/configuration.md lists the keys that override them) and the qnav tool's train, repeat,
// eval, xtf and camera commands use them unchanged, so the daemon and the evaluation run the same
// numbers. Every value here was measured by `qnav route eval` (docs/route.md says with which run).
#pragma once

#include <cstddef>
#include <cstdint>

#include "drivers/sidescan/sim_seabed.hpp"
#include "drivers/sidescan/sim_sidescan.hpp"
#include "nav/route/route_localiser.hpp"
#include "nav/route/tile_features.hpp"
#include "nav/sonar/scanline_corrector.hpp"
#include "nav/sonar/tile_builder.hpp"

namespace qnav::pipeline {

struct RouteTileConfig {
  sonar::ScanlineCorrectorConfig corrector;
  sonar::TileBuilderConfig tiles;
  route::TileFeatureConfig features;
  // false: tiles only, no keypoints (`qnav sonar tiles`, which draws the rasters): the pipeline takes
  // no feature arena and a RouteTile's node has no keypoints (its meta is filled as usual).
  bool extract_features = true;
};

// Tiles are framed by along-track distance (the dead-reckoned distance between pings), sized by the
// swath (2 x slant range): a tile covers kTileLengthSwaths x the swath of track, a new one (a route
// node) every kTileStrideSwaths x the swath, so a sensed tile overlaps its nearest node by at least
// two thirds along track whatever the ping rate and speed. The tile buffers hold a full tile down to
// kMinPingSpacingM between pings (e.g. 15 pings/s at 0.75 m/s; more pings are counted as
// tile_overflow). The keypoint budget follows the tile's area in feature pixels: one keypoint per
// kFeaturePixelsPerKeypoint (downsample x resolution)^2, within [kMinKeypointBudget, kMaxKeypointsPerNode].
inline constexpr double kTileLengthSwaths = 0.9;
inline constexpr double kTileStrideSwaths = 0.6;
inline constexpr double kMinPingSpacingM = 0.05;
inline constexpr double kFeaturePixelsPerKeypoint = 190.0;
inline constexpr std::size_t kMinKeypointBudget = 16;
// The keypoint budget of a tile length_m x swath_m seen in feature pixels of feature_pixel_m.
std::size_t keypoint_budget(double length_m, double swath_m, double feature_pixel_m);
// Frames c's tiles by distance: length_m / stride_m (0: from the swath as above), the tile ring sized
// for min_ping_spacing_m, the keypoint budget from the tile's area.
void frame_tiles_by_distance(RouteTileConfig& c, double swath_m, double min_ping_spacing_m, double length_m = 0.0, double stride_m = 0.0);
// The nominal node spacing of tiles so framed (by ping count: stride pings x speed / ping rate).
double tile_stride_m(const RouteTileConfig& c, double speed_mps, double ping_rate_hz);
// How old a tile's pose is when the tile is finished (half a tile of travel), at this speed and ping
// rate: what a closed loop's autopilot allows for when it steers on the tile's guidance.
double tile_age_s(const RouteTileConfig& c, double speed_mps, double ping_rate_hz);
// The same as travel: half the tile length for tiles by distance (0 by ping count). An autopilot that
// looks its pose up this far back along its own dead reckoning is right whatever its speed over ground
// (a current ahead or astern changes the time a tile takes, not its length).
double tile_age_m(const RouteTileConfig& c);

// The share of a repeat pass's start belief on the route's entry end (RepeatSessionConfig::entry_prior,
// qnavd's route.entry_prior): a pass starts where the route does (docs/route.md, "Routes that learn").
inline constexpr double kDefaultEntryPrior = 0.5;

// Tiles for the simulator's sonar (50 m slant range, swath 100 m): 0.2 m raster 704 x 704 (141 m
// square), tiles of 90 m of track every 60 m (the node spacing), 128 keypoints; ground bins 0.2 m x 256.
RouteTileConfig default_route_tile_config();
// Tiles for a recorded pass whose median slant range is range_m and median ping spacing
// ping_spacing_m: 300 ground bins per side (0.1 m for the Iver2's 30 m), rasters at the bin size
// large enough for the tile, tiles by distance (length_m / stride_m; 0: from the swath), the ring
// holding a tile down to half the median ping spacing. lines > 0: frame by ping count instead
// (`lines` pings per tile every `stride`).
RouteTileConfig file_route_tile_config(double range_m, double ping_spacing_m, double length_m = 0.0, double stride_m = 0.0, int lines = 0,
                                       int stride = 0);

sidescan::SideScanSimConfig default_route_sonar_config();
sidescan::SeabedConfig default_route_seabed_config(std::uint64_t seed);

// The localiser as `qnav route eval` measured it (filter, registration, guidance).
route::LocaliserConfig default_localiser_config(route::RouteDirection direction, std::size_t max_nodes);
// Registration on real tiles at 0.1 m (tighter than the simulator's 0.6 m feature pixels), guidance
// distances scaled by the route's node spacing.
route::LocaliserConfig file_localiser_config(route::RouteDirection direction, std::size_t max_nodes, std::size_t nodes, double spacing_m);

// A route file's header: the sensor, node spacing, tile size and pixel, and the feature settings'
// keypoint and detector fields (side-scan tiles below, camera tiles in camera_tile_pipeline.hpp).
route::RouteParams route_params_for(route::SensorKind sensor, double spacing_m, double tile_length_m, double tile_width_m, double pixel_m,
                                   const route::TileFeatureConfig& features);
// A route file's header for tiles of this configuration.
route::RouteParams side_scan_route_params(const RouteTileConfig& config, double spacing_m, double swath_m);

}  // namespace qnav::pipeline
