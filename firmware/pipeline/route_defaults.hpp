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
};

// Tiles for the simulator at 5 Hz / 1.5 m/s: 0.2 m raster 704 x 704 (141 m square), 300 scanlines per
// tile (90 m of track) every 200 scanlines (60 m node spacing), so a sensed tile never overlaps its
// nearest node by less than two thirds along track; ground bins 0.2 m x 256.
RouteTileConfig default_route_tile_config();
// Tiles for a recorded pass whose median slant range is range_m: 300 ground bins per side (0.1 m for
// the Iver2's 30 m), 800 x 800 px rasters at the bin size, `lines` pings per tile every `stride`.
RouteTileConfig file_route_tile_config(double range_m, int lines, int stride);

sidescan::SideScanSimConfig default_route_sonar_config();
sidescan::SeabedConfig default_route_seabed_config(std::uint64_t seed);

// The localiser as `qnav route eval` measured it (filter, registration, guidance).
route::LocaliserConfig default_localiser_config(route::RouteDirection direction, std::size_t max_nodes);
// Registration on real tiles at 0.1 m (tighter than the simulator's 0.6 m feature pixels), guidance
// distances scaled by the route's node spacing.
route::LocaliserConfig file_localiser_config(route::RouteDirection direction, std::size_t max_nodes, std::size_t nodes, double spacing_m);

// A route file's header for tiles of this configuration.
route::RouteParams side_scan_route_params(const RouteTileConfig& config, double spacing_m, double swath_m);

}  // namespace qnav::pipeline
