// RouteTilePipeline without its keypoints (extract_features = false, what `qnav sonar tiles` runs):
// the same tiles (raster, coverage, pose, framing) as the full pipeline qnavd's SonarTiles runs, with
// no feature arena and no keypoints; pings the corrector refuses are counted, not errors.
// Host only (test_firmware_pipeline_host): the simulated pass costs seconds under qemu.
#include "firmware/pipeline/route_tile_pipeline.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "firmware/pipeline/route_defaults.hpp"
#include "firmware/pipeline/sim_survey.hpp"

namespace {

using namespace qnav;
using namespace qnav::pipeline;

struct TileSeen {
  RouteTile tile;
  std::vector<float> intensity;
  std::vector<std::uint8_t> coverage;
};

std::vector<TileSeen> fly(RouteTilePipeline& pipe, const SimSurvey& w, const sidescan::TrajectoryConfig& t) {
  std::vector<TileSeen> out;
  EXPECT_TRUE(pipe.run_sim_pass(w.seabed, w.sonar_for(t.seed), t, [&](const RouteTile& tile) {
                    TileSeen s;
                    s.tile = tile;
                    const sonar::SonarTile& r = pipe.last_tile();
                    for (int y = 0; y < r.intensity.height(); ++y)
                      for (int x = 0; x < r.intensity.width(); ++x) {
                        s.intensity.push_back(r.intensity(x, y));
                        s.coverage.push_back(r.coverage(x, y));
                      }
                    out.push_back(std::move(s));
                    return true;
                  }).is_ok());
  return out;
}

TEST(RouteTilePipeline, WithoutFeaturesTheSameTilesAndNoKeypoints) {
  SimSurvey w;
  ASSERT_TRUE(w.init(200.0, 4).is_ok());
  const RouteTileConfig full = default_route_tile_config();
  RouteTileConfig bare = full;
  bare.extract_features = false;
  EXPECT_LT(RouteTilePipeline::arena_bytes(bare), RouteTilePipeline::arena_bytes(full));
  RouteTilePipeline a, b;
  ASSERT_TRUE(a.init(full).is_ok());
  ASSERT_TRUE(b.init(bare).is_ok());
  const sidescan::TrajectoryConfig pass = w.pass(0.1 * w.swath_m, false, repeat_pass_seed(4));
  const std::vector<TileSeen> ta = fly(a, w, pass), tb = fly(b, w, pass);
  ASSERT_GE(ta.size(), 3u);
  ASSERT_EQ(ta.size(), tb.size());
  std::size_t keypoints = 0;
  for (std::size_t i = 0; i < ta.size(); ++i) {
    const RouteTile &x = ta[i].tile, &y = tb[i].tile;
    EXPECT_EQ(x.ping_first, y.ping_first);
    EXPECT_EQ(x.ping_last, y.ping_last);
    EXPECT_EQ(x.node.meta.along_m, y.node.meta.along_m);
    EXPECT_EQ(x.node.meta.pose.x_m, y.node.meta.pose.x_m);
    EXPECT_EQ(x.node.meta.pose.y_m, y.node.meta.pose.y_m);
    EXPECT_EQ(x.node.meta.pose.heading_rad, y.node.meta.pose.heading_rad);
    EXPECT_EQ(x.truth_along_m, y.truth_along_m);
    EXPECT_EQ(ta[i].intensity, tb[i].intensity) << "tile " << i;
    EXPECT_EQ(ta[i].coverage, tb[i].coverage) << "tile " << i;
    EXPECT_EQ(y.node.keypoints.size(), 0u);
    EXPECT_EQ(y.node.meta.keypoint_count, 0u);
    keypoints += x.node.keypoints.size();
  }
  EXPECT_GT(keypoints, 0u);  // the full pipeline found some, so "none" above means something
  EXPECT_EQ(a.rejected_pings(), 0u);
  EXPECT_EQ(b.rejected_pings(), 0u);
}

TEST(RouteTilePipeline, RefusedPingIsCountedNotAnError) {
  RouteTileConfig c = default_route_tile_config();
  c.extract_features = false;
  RouteTilePipeline p;
  ASSERT_TRUE(p.init(c).is_ok());
  const std::vector<float> samples(16, 1.0f);
  sonar::SonarPing ping;
  ping.ping_number = 0;
  ping.stamp_ns = 1;
  ping.port = Span<const float>(samples.data(), samples.size());
  ping.stbd = Span<const float>(samples.data(), 4);  // sides of different lengths: refused by the corrector
  ping.slant_range_m = 40.0f;
  bool stop = false;
  int tiles = 0;
  const RouteTileSink sink = [&tiles](const RouteTile&) {
    ++tiles;
    return true;
  };
  EXPECT_TRUE(p.push_ping(ping, Pose2{}, sink, &stop).is_ok());
  ping.ping_number = 1;
  ping.slant_range_m = -1.0f;  // a bad range
  ping.stbd = ping.port;
  EXPECT_TRUE(p.push_ping(ping, Pose2{}, sink, &stop).is_ok());
  EXPECT_EQ(p.rejected_pings(), 2u);
  EXPECT_EQ(tiles, 0);
  EXPECT_FALSE(stop);
}

}  // namespace
