// The side-scan chain shared by fuzz_sonar_chain_xtf and fuzz_sonar_chain_jsf: a file's bytes through
// exactly what `qnav route train --sonar` and qnavd's recorded passes run (firmware/tools/sonar_file:
// load_xtf / load_jsf, build_track, the median slant range; firmware/pipeline: file_route_tile_config
// and RouteTilePipeline = ScanlineCorrector -> TileBuilder -> TileFeatureExtractor -> route node),
// with the tile size reduced through the daemon's own configuration keys.
// Byte 0: bit 0 dead reckoning instead of fixes; bits 1-2 pings per tile 10/16/24/40 (stride half).
// Every tile's node must hold at most max_keypoints finite keypoints.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "firmware/pipeline/route_defaults.hpp"
#include "firmware/pipeline/route_tile_pipeline.hpp"
#include "firmware/tools/sonar_file.hpp"
#include "test/fuzz/fuzz_support.hpp"

namespace qnav::fuzz {

inline int run_sonar_chain(const std::uint8_t* data, std::size_t size, bool jsf) {
  if (size < 1) return 0;
  const bool dead_reckon = (data[0] & 1) != 0;
  static const int kLines[] = {10, 16, 24, 40};
  const int lines = kLines[(data[0] >> 1) & 3];
  const std::string path = write_scratch(jsf ? "chain.jsf" : "chain.xtf", data + 1, size - 1);
  tools::FileData fd;
  if ((jsf ? tools::load_jsf(path.c_str(), fd) : tools::load_xtf(path.c_str(), fd)) != 0) return 0;
  const tools::NavTrack track = tools::build_track(fd, dead_reckon, 0.0);
  std::vector<float> ranges;
  tools::collect_slant_ranges(fd, ranges);
  double range_m = 0.0;
  if (!tools::median_slant_range(ranges, range_m)) return 0;
  pipeline::RouteTileConfig tc = pipeline::file_route_tile_config(range_m, 0.0, 0.0, 0.0, lines, lines / 2);  // by ping count
  // Smaller tiles (the full 800 px ones cost seconds per input under ASan), set as qnavd's [route]
  // keys set them (firmware/qnavd/config.cpp): ground_bins_per_side = 64, ground_bin_m = resolution_m
  // = range / 64, tile_px = 160.
  const float bin_m = static_cast<float>(range_m / 64.0 > 0.02 ? range_m / 64.0 : 0.02);
  tc.corrector.ground_bins_per_side = 64;
  tc.tiles.max_bins_per_side = 64;
  tc.corrector.ground_bin_m = bin_m;
  tc.tiles.resolution_m = static_cast<double>(bin_m);
  tc.tiles.tile_width_px = tc.tiles.tile_height_px = 160;
  tc.features.max_width = tc.features.max_height = 160;
  pipeline::RouteTilePipeline pipe;
  if (!pipe.init(tc)) return 0;
  bool stop = false;
  const std::size_t max_kp = static_cast<std::size_t>(tc.features.max_keypoints);
  const pipeline::RouteTileSink sink = [max_kp](const pipeline::RouteTile& t) {
    if (t.node.keypoints.size() > max_kp) __builtin_trap();
    for (const route::RouteKeypoint& k : t.node.keypoints)
      if (!std::isfinite(k.x_m) || !std::isfinite(k.y_m)) __builtin_trap();
    return true;
  };
  for (std::size_t k = 0; k < fd.pings.size() && !stop; ++k) {
    if (!track.ok[k]) continue;
    sonar::SonarPing ping = tools::as_ping(fd.pings[k], false);
    ping.ping_number = static_cast<std::uint32_t>(k);
    if (!pipe.push_ping(ping, track.pose[k], sink, &stop)) break;
  }
  return 0;
}

}  // namespace qnav::fuzz
