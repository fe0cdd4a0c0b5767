// TileBuilder: georeferencing of scanlines into the north-up raster, emission cadence, hole filling,
// bad input, no allocation while building.
#include "nav/sonar/tile_builder.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "test/support/alloc_guard.hpp"

namespace qnav::sonar {
namespace {

// A smooth seabed pattern in world coordinates.
float pattern(double n, double e) {
  return static_cast<float>(1.0 + 0.5 * std::sin(2.0 * kPi * n / 7.0) * std::cos(2.0 * kPi * e / 5.0));
}

struct LineSource {
  int bins = 200;
  float bin_m = 0.1f;
  std::vector<float> port, stbd;
  std::vector<std::uint8_t> pv, sv;
  CorrectedScanline make(const Pose2& pose, std::uint32_t ping) {
    port.assign(static_cast<std::size_t>(bins), 0.0f);
    stbd.assign(static_cast<std::size_t>(bins), 0.0f);
    pv.assign(static_cast<std::size_t>(bins), 1);
    sv.assign(static_cast<std::size_t>(bins), 1);
    const Vec2d sb = starboard_unit(pose.heading_rad);
    for (int b = 0; b < bins; ++b) {
      const double g = (b + 0.5) * static_cast<double>(bin_m);
      const Vec2d ps = pose.translation() + g * sb, pp = pose.translation() - g * sb;
      stbd[static_cast<std::size_t>(b)] = pattern(ps.x(), ps.y());
      port[static_cast<std::size_t>(b)] = pattern(pp.x(), pp.y());
    }
    pv[0] = sv[0] = 0;  // a nadir bin without data
    CorrectedScanline l;
    l.ping_number = ping;
    l.stamp_ns = ping * 100000000ull;
    l.bin_m = bin_m;
    l.port = Span<const float>(port.data(), port.size());
    l.stbd = Span<const float>(stbd.data(), stbd.size());
    l.port_valid = Span<const std::uint8_t>(pv.data(), pv.size());
    l.stbd_valid = Span<const std::uint8_t>(sv.data(), sv.size());
    return l;
  }
};

TileBuilderConfig small_config() {
  TileBuilderConfig c;
  c.resolution_m = 0.1;
  c.tile_width_px = 512;
  c.tile_height_px = 512;
  c.scanlines_per_tile = 100;
  c.scanline_stride = 100;
  c.max_bins_per_side = 256;
  return c;
}

TEST(TileBuilder, PlacesScanlinesAtTheirWorldPosition) {
  const TileBuilderConfig cfg = small_config();
  ArenaStorage arena(TileBuilder::arena_bytes(cfg));
  TileBuilder tb;
  ASSERT_TRUE(tb.init(cfg, arena).is_ok());
  LineSource src;
  const double heading = deg_to_rad(30.0), step = 0.15;
  bool built = false;
  for (int k = 0; k < 100; ++k) {
    const Pose2 pose{100.0 + k * step * std::cos(heading), -40.0 + k * step * std::sin(heading), heading};
    const Result<bool> r = tb.push(src.make(pose, static_cast<std::uint32_t>(k)), pose);
    ASSERT_TRUE(r.is_ok());
    built = r.value();
  }
  ASSERT_TRUE(built);
  const SonarTile& t = tb.tile();
  EXPECT_EQ(t.index, 0u);
  EXPECT_EQ(t.scanlines, 100u);
  EXPECT_EQ(t.first_ping, 0u);
  EXPECT_EQ(t.last_ping, 99u);
  EXPECT_NEAR(t.pose.x_m, 100.0 + 50 * step * std::cos(heading), 1e-9);
  // Grid snapped to the resolution.
  EXPECT_NEAR(std::remainder(t.origin_north_m, 0.1), 0.0, 1e-9);
  EXPECT_NEAR(std::remainder(t.origin_east_m, 0.1), 0.0, 1e-9);
  // Every measured pixel holds the pattern value at its own centre (bilinear interpolation of a
  // smooth field: error well below the pattern's 0.5 amplitude).
  double err = 0.0;
  int measured = 0;
  for (int r = 0; r < t.coverage.height(); ++r)
    for (int c = 0; c < t.coverage.width(); ++c) {
      if (t.coverage(c, r) != 1) continue;
      const Vec2d ne = t.pixel_to_ne(c + 0.5, r + 0.5);
      err += std::fabs(static_cast<double>(t.intensity(c, r) - pattern(ne.x(), ne.y())));
      ++measured;
    }
  ASSERT_GT(measured, 20000);
  EXPECT_LT(err / measured, 0.02) << "mean abs error over " << measured << " pixels";
  // The swath (2 x 20 m wide, 15 m long) covers about 40 * 15 / 0.01 = 60000 pixels of 262144.
  EXPECT_NEAR(t.coverage_fraction, 60000.0 / 262144.0, 0.03);
  EXPECT_EQ(t.clipped_splats, 0u);
  // Footprint corners: first port end is 20 m to port of the first pose.
  EXPECT_NEAR((t.footprint_ne[0] - Vec2d(100.0, -40.0)).norm(), 20.0, 1e-5);
}

TEST(TileBuilder, EmitsEveryStrideAndFlushesTheRest) {
  TileBuilderConfig cfg = small_config();
  cfg.scanline_stride = 50;
  ArenaStorage arena(TileBuilder::arena_bytes(cfg));
  TileBuilder tb;
  ASSERT_TRUE(tb.init(cfg, arena).is_ok());
  LineSource src;
  int tiles = 0;
  std::vector<std::uint32_t> first_pings;
  for (int k = 0; k < 230; ++k) {
    const Pose2 pose{k * 0.15, 0.0, 0.0};
    const Result<bool> r = tb.push(src.make(pose, static_cast<std::uint32_t>(k)), pose);
    ASSERT_TRUE(r.is_ok());
    if (r.value()) {
      ++tiles;
      first_pings.push_back(tb.tile().first_ping);
    }
  }
  // Tiles after 100, 150, 200 scanlines, overlapping by 50.
  ASSERT_EQ(tiles, 3);
  EXPECT_EQ(first_pings[0], 0u);
  EXPECT_EQ(first_pings[1], 50u);
  EXPECT_EQ(first_pings[2], 100u);
  const Result<bool> f = tb.flush();
  ASSERT_TRUE(f.is_ok());
  EXPECT_TRUE(f.value());
  EXPECT_EQ(tb.tile().last_ping, 229u);
  EXPECT_EQ(tb.tile().first_ping, 150u);
  EXPECT_EQ(tb.tiles_built(), 4u);
}

// The intensity raster overlays the accumulator, which normalise() empties as it goes (and the next
// tile clears only the previous tile's box): each tile of a turning track, built after others, must
// be bit for bit the tile a fresh builder makes from the same scanlines alone. Without the u8 raster
// (qnavd) intensity, coverage and coverage fraction are the same and intensity_u8 is empty.
TEST(TileBuilder, ATileCarriesNothingOfThePreviousOneWithOrWithoutTheU8Raster) {
  TileBuilderConfig cfg = small_config();
  cfg.scanline_stride = 40;
  ArenaStorage arena(TileBuilder::arena_bytes(cfg));
  TileBuilder tb;
  ASSERT_TRUE(tb.init(cfg, arena).is_ok());
  TileBuilderConfig fresh_cfg = small_config();
  fresh_cfg.u8_raster = false;
  EXPECT_LT(TileBuilder::arena_bytes(fresh_cfg), TileBuilder::arena_bytes(cfg));
  LineSource src;
  std::vector<Pose2> poses;
  double n = 0.0, e = 0.0, heading = 0.0;
  int tiles = 0;
  for (int k = 0; k < 400; ++k) {
    heading += deg_to_rad(k < 200 ? 0.9 : -1.3);  // the tile's box moves and changes shape
    n += 0.15 * std::cos(heading);
    e += 0.15 * std::sin(heading);
    poses.push_back(Pose2{n, e, heading});
    const Result<bool> r = tb.push(src.make(poses.back(), static_cast<std::uint32_t>(k)), poses.back());
    ASSERT_TRUE(r.is_ok());
    if (!r.value()) continue;
    ++tiles;
    const SonarTile& t = tb.tile();
    ArenaStorage fresh_arena(TileBuilder::arena_bytes(fresh_cfg));
    TileBuilder fresh;
    ASSERT_TRUE(fresh.init(fresh_cfg, fresh_arena).is_ok());
    bool built = false;
    LineSource src2;
    for (std::uint32_t p = t.first_ping; p <= t.last_ping; ++p) {
      const Result<bool> r2 = fresh.push(src2.make(poses[p], p), poses[p]);
      ASSERT_TRUE(r2.is_ok());
      built = r2.value();
    }
    ASSERT_TRUE(built) << "tile " << t.index;
    const SonarTile& f = fresh.tile();
    EXPECT_TRUE(f.intensity_u8.empty());
    ASSERT_FALSE(t.intensity_u8.empty());
    EXPECT_EQ(f.coverage_fraction, t.coverage_fraction) << "tile " << t.index;
    EXPECT_EQ(f.origin_north_m, t.origin_north_m);
    EXPECT_EQ(f.origin_east_m, t.origin_east_m);
    int differ = 0;
    for (int row = 0; row < t.intensity.height(); ++row)
      for (int c = 0; c < t.intensity.width(); ++c)
        differ += (f.intensity(c, row) != t.intensity(c, row) || f.coverage(c, row) != t.coverage(c, row)) ? 1 : 0;
    EXPECT_EQ(differ, 0) << "tile " << t.index;
  }
  EXPECT_EQ(tiles, 8);
}

// Scanlines whose valid bins have gaps that differ from ping to ping (the splat's masked bins around
// the run valid on both lines), on a turning track, over a flat seabed of intensity 1.5 (negative bins
// of no data, as a caller may pass them, must not be splatted): every measured pixel is 1.5 (a
// weighted mean of 1.5s), the u8 raster is the quantised intensity everywhere, and each filled
// pixel is exactly what the plain four-direction search of the header's rule gives.
TEST(TileBuilder, IrregularMasksGiveTheMeanTheU8AndTheHoleFillOfTheRule) {
  for (const int min_neighbours : {2, 3}) {
    TileBuilderConfig cfg = small_config();
    cfg.hole_fill_min_neighbours = min_neighbours;
    cfg.hole_fill_radius_px = 3;
    ArenaStorage arena(TileBuilder::arena_bytes(cfg));
    TileBuilder tb;
    ASSERT_TRUE(tb.init(cfg, arena).is_ok());
    const int bins = 200;
    std::vector<float> port(bins), stbd(bins);
    std::vector<std::uint8_t> pv(bins), sv(bins);
    double n = 0.0, e = 0.0, heading = 0.3;
    bool built = false;
    for (int k = 0; k < 100 && !built; ++k) {
      heading += deg_to_rad(0.7);
      n += 0.12 * std::cos(heading);
      e += 0.12 * std::sin(heading);
      for (int b = 0; b < bins; ++b) {
        // Nadir gaps of 3..9 bins, holes every 17 + k % 5 bins, a ragged far end.
        const bool p_ok = b >= 3 + k % 7 && (b + k) % (17 + k % 5) != 0 && b < bins - (k % 4);
        const bool s_ok = b >= 5 + k % 3 && (b * 3 + k) % 23 != 0 && b < bins - 1;
        pv[static_cast<std::size_t>(b)] = p_ok ? 1 : 0;
        sv[static_cast<std::size_t>(b)] = s_ok ? 1 : 0;
        port[static_cast<std::size_t>(b)] = p_ok ? 1.5f : -1.0f;
        stbd[static_cast<std::size_t>(b)] = s_ok ? 1.5f : 0.0f;
      }
      CorrectedScanline l;
      l.ping_number = static_cast<std::uint32_t>(k);
      l.bin_m = 0.1f;
      l.port = Span<const float>(port.data(), port.size());
      l.stbd = Span<const float>(stbd.data(), stbd.size());
      l.port_valid = Span<const std::uint8_t>(pv.data(), pv.size());
      l.stbd_valid = Span<const std::uint8_t>(sv.data(), sv.size());
      const Result<bool> r = tb.push(l, Pose2{n, e, heading});
      ASSERT_TRUE(r.is_ok());
      built = r.value();
    }
    ASSERT_TRUE(built);
    const SonarTile& t = tb.tile();
    const int W = t.coverage.width(), H = t.coverage.height(), R = cfg.hole_fill_radius_px;
    int measured = 0, filled = 0, u8_wrong = 0, mean_wrong = 0, fill_wrong = 0;
    for (int r = 0; r < H; ++r)
      for (int c = 0; c < W; ++c) {
        const float v = t.intensity(c, r);
        const float u = std::min(std::max(v * (255.0f / cfg.display_max) + 0.5f, 0.0f), 255.0f);
        u8_wrong += t.intensity_u8(c, r) != static_cast<std::uint8_t>(static_cast<int>(u)) ? 1 : 0;
        if (t.coverage(c, r) == 1) {
          ++measured;
          mean_wrong += std::fabs(v - 1.5f) > 1e-5f ? 1 : 0;
          continue;
        }
        // The rule: the nearest measured pixel within R left, right, up and down; a pair on a row or a
        // column, at least min_neighbours directions; the inverse-distance mean in that order.
        const int dc[4] = {-1, 1, 0, 0}, dr[4] = {0, 0, -1, 1};
        int kd[4] = {0, 0, 0, 0};
        for (int d = 0; d < 4; ++d)
          for (int k = 1; k <= R; ++k) {
            const int cc = c + k * dc[d], rr = r + k * dr[d];
            if (cc < 0 || rr < 0 || cc >= W || rr >= H) break;
            if (t.coverage(cc, rr) == 1) {
              kd[d] = k;
              break;
            }
          }
        const int dirs = (kd[0] > 0) + (kd[1] > 0) + (kd[2] > 0) + (kd[3] > 0);
        const bool fill = ((kd[0] > 0 && kd[1] > 0) || (kd[2] > 0 && kd[3] > 0)) && dirs >= min_neighbours;
        if (!fill) {
          fill_wrong += (t.coverage(c, r) != 0 || v != 0.0f) ? 1 : 0;
          continue;
        }
        ++filled;
        float acc = 0.0f, wsum = 0.0f;
        for (int d = 0; d < 4; ++d) {
          if (kd[d] == 0) continue;
          const float w = 1.0f / static_cast<float>(kd[d]);
          acc += w * t.intensity(c + kd[d] * dc[d], r + kd[d] * dr[d]);
          wsum += w;
        }
        fill_wrong += (t.coverage(c, r) != 2 || v != acc / wsum) ? 1 : 0;
      }
    EXPECT_GT(measured, 20000) << "min_neighbours " << min_neighbours;
    EXPECT_GT(filled, 100) << "min_neighbours " << min_neighbours;
    EXPECT_EQ(mean_wrong, 0) << "min_neighbours " << min_neighbours;
    EXPECT_EQ(u8_wrong, 0) << "min_neighbours " << min_neighbours;
    EXPECT_EQ(fill_wrong, 0) << "min_neighbours " << min_neighbours;
  }
}

TEST(TileBuilder, InterpolatesBetweenSparseScanlinesAndFillsSmallHoles) {
  TileBuilderConfig cfg = small_config();
  cfg.max_substeps = 1;  // no along-track interpolation: 0.3 m gaps leave holes
  cfg.hole_fill_radius_px = 2;
  ArenaStorage arena(TileBuilder::arena_bytes(cfg));
  TileBuilder tb;
  ASSERT_TRUE(tb.init(cfg, arena).is_ok());
  LineSource src;
  for (int k = 0; k < 100; ++k) {
    const Pose2 pose{k * 0.3, 0.0, 0.0};
    ASSERT_TRUE(tb.push(src.make(pose, static_cast<std::uint32_t>(k)), pose).is_ok());
  }
  const SonarTile& t = tb.tile();
  int filled = 0, measured = 0;
  double err = 0.0;
  for (int r = 0; r < t.coverage.height(); ++r)
    for (int c = 0; c < t.coverage.width(); ++c) {
      if (t.coverage(c, r) == 2) {
        ++filled;
        const Vec2d ne = t.pixel_to_ne(c + 0.5, r + 0.5);
        err += std::fabs(static_cast<double>(t.intensity(c, r) - pattern(ne.x(), ne.y())));
      }
      if (t.coverage(c, r) == 1) ++measured;
    }
  EXPECT_GT(filled, measured / 4) << "holes between 0.3 m scanlines must be filled";
  EXPECT_LT(err / filled, 0.08);
}

TEST(TileBuilder, RejectsBadPosesAndScanlines) {
  const TileBuilderConfig cfg = small_config();
  ArenaStorage arena(TileBuilder::arena_bytes(cfg));
  TileBuilder tb;
  ASSERT_TRUE(tb.init(cfg, arena).is_ok());
  LineSource src;
  const Pose2 bad{std::nan(""), 0.0, 0.0};
  EXPECT_EQ(tb.push(src.make(Pose2{}, 0), bad).status(), StatusCode::kInvalidArgument);
  EXPECT_EQ(tb.counters().get(TileCounter::kBadPose), 1u);
  src.bins = 300;  // above max_bins_per_side
  EXPECT_EQ(tb.push(src.make(Pose2{}, 0), Pose2{}).status(), StatusCode::kInvalidArgument);
  EXPECT_EQ(tb.counters().get(TileCounter::kBadScanline), 1u);
  src.bins = 200;
  CorrectedScanline l = src.make(Pose2{}, 0);
  src.stbd[5] = std::nanf("");
  EXPECT_EQ(tb.push(l, Pose2{}).status(), StatusCode::kInvalidArgument);
  EXPECT_EQ(tb.counters().get(TileCounter::kBadScanline), 2u);
  EXPECT_EQ(tb.buffered(), 0);
  TileBuilderConfig c2 = cfg;
  c2.scanline_stride = 0;
  TileBuilder tb2;
  EXPECT_EQ(tb2.init(c2, arena), StatusCode::kInvalidArgument);
}

TEST(TileBuilder, NavJumpIsNotInterpolatedAcross) {
  const TileBuilderConfig cfg = small_config();
  ArenaStorage arena(TileBuilder::arena_bytes(cfg));
  TileBuilder tb;
  ASSERT_TRUE(tb.init(cfg, arena).is_ok());
  LineSource src;
  for (int k = 0; k < 100; ++k) {
    const Pose2 pose{k * 0.15 + (k >= 50 ? 8.0 : 0.0), 0.0, 0.0};
    ASSERT_TRUE(tb.push(src.make(pose, static_cast<std::uint32_t>(k)), pose).is_ok());
  }
  EXPECT_EQ(tb.counters().get(TileCounter::kNavJump), 1u);
  // The 8 m gap between the halves stays empty on the track line.
  const SonarTile& t = tb.tile();
  const Vec2d mid = t.ne_to_pixel(49 * 0.15 + 4.0, 5.0);
  EXPECT_EQ(t.coverage(static_cast<int>(mid.x()), static_cast<int>(mid.y())), 0);
}

// A damaged file's navigation: one pose 1e28 m away and bins 1e6 m wide (fuzz_sonar_chain_xtf found
// the float-to-int overflow of the first). The tile is built without undefined behaviour (the
// sanitizer builds check), the jump is counted, and the bins are not spread over more pixels than
// the tile has (the wide tile is built at once, not after 1e6 / 0.1 sub-steps per bin).
TEST(TileBuilder, AbsurdPoseOrBinWidthBuildsWithoutOverflow) {
  const TileBuilderConfig cfg = small_config();
  ArenaStorage arena(TileBuilder::arena_bytes(cfg));
  TileBuilder tb;
  ASSERT_TRUE(tb.init(cfg, arena).is_ok());
  LineSource src;
  for (int k = 0; k < 99; ++k) {
    const Pose2 pose{k * 0.15, 0.0, 0.0};
    ASSERT_TRUE(tb.push(src.make(pose, static_cast<std::uint32_t>(k)), pose).is_ok());
  }
  const Pose2 far{-3.9e28, 1.0e28, 0.0};
  ASSERT_TRUE(tb.push(src.make(far, 99), far).is_ok());
  EXPECT_EQ(tb.counters().get(TileCounter::kNavJump), 1u);
  EXPECT_EQ(tb.tiles_built(), 1u);

  ArenaStorage wide_arena(TileBuilder::arena_bytes(cfg));
  TileBuilder wide;
  ASSERT_TRUE(wide.init(cfg, wide_arena).is_ok());
  src.bins = 4;
  src.bin_m = 1.0e6f;
  for (int k = 0; k < 100; ++k) {
    const Pose2 pose{k * 0.15, 0.0, 0.0};
    ASSERT_TRUE(wide.push(src.make(pose, static_cast<std::uint32_t>(k)), pose).is_ok());
  }
  EXPECT_EQ(wide.tiles_built(), 1u);
}

TEST(TileBuilder, PushAndBuildMakeNoHeapAllocation) {
  const TileBuilderConfig cfg = small_config();
  ArenaStorage arena(TileBuilder::arena_bytes(cfg));
  TileBuilder tb;
  ASSERT_TRUE(tb.init(cfg, arena).is_ok());
  LineSource src;
  std::vector<CorrectedScanline> lines;
  std::vector<LineSource> srcs(100);
  for (int k = 0; k < 100; ++k) lines.push_back(srcs[static_cast<std::size_t>(k)].make(Pose2{k * 0.15, 0.0, 0.0}, static_cast<std::uint32_t>(k)));
  int built = 0;
  QNAV_EXPECT_NO_ALLOC(for (int k = 0; k < 100; ++k) {
    const Result<bool> r = tb.push(lines[static_cast<std::size_t>(k)], Pose2{k * 0.15, 0.0, 0.0});
    if (r.is_ok() && r.value()) ++built;
  });
  EXPECT_EQ(built, 1);
}


// Tiles by distance: a straight run at `step_m` per ping; returns (first ping, last ping, centre
// distance) of every tile. stride_at (optional): set_next_stride_m() after that tile.
struct DistanceTile {
  std::uint32_t first, last;
  double start_m, end_m;
};
std::vector<DistanceTile> run_by_distance(TileBuilder& tb, double step_m, int pings, int stride_after = -1, double stride_m = 0.0) {
  LineSource src;
  src.bins = 60;
  std::vector<DistanceTile> out;
  for (int k = 0; k < pings; ++k) {
    const Pose2 pose{k * step_m, 0.0, 0.0};
    const Result<bool> r = tb.push(src.make(pose, static_cast<std::uint32_t>(k)), pose);
    EXPECT_TRUE(r.is_ok());
    if (r.is_ok() && r.value()) {
      const SonarTile& t = tb.tile();
      out.push_back({t.first_ping, t.last_ping, t.first_pose.x_m, t.last_pose.x_m});
      if (static_cast<int>(out.size()) - 1 == stride_after) tb.set_next_stride_m(stride_m);
    }
  }
  return out;
}

TileBuilderConfig distance_config() {
  TileBuilderConfig c = small_config();
  c.tile_length_m = 10.0;
  c.tile_stride_m = 6.0;
  c.scanlines_per_tile = 210;  // a full 10 m tile down to 0.05 m between pings
  return c;
}

TEST(TileBuilder, ByDistanceTilesHaveTheirLengthAtAnyPingSpacing) {
  for (double step : {0.05, 0.1, 0.3, 0.7}) {
    const TileBuilderConfig cfg = distance_config();
    ArenaStorage arena(TileBuilder::arena_bytes(cfg));
    TileBuilder tb;
    ASSERT_TRUE(tb.init(cfg, arena).is_ok());
    const std::vector<DistanceTile> tiles = run_by_distance(tb, step, static_cast<int>(std::ceil(40.0 / step)) + 2);
    // Tiles end at 10, 16, 22, 28, 34, 40 m (the first ping at or past each), each 10 m long.
    ASSERT_EQ(tiles.size(), 6u) << "step " << step;
    for (std::size_t i = 0; i < tiles.size(); ++i) {
      EXPECT_NEAR(tiles[i].end_m, 10.0 + 6.0 * static_cast<double>(i), step + 1e-9) << "step " << step;
      EXPECT_NEAR(tiles[i].end_m - tiles[i].start_m, 10.0, step + 1e-9) << "step " << step;
    }
    EXPECT_EQ(tb.counters().get(TileCounter::kTileOverflow), 0u);
  }
}

TEST(TileBuilder, ByDistanceTooManyPingsAreCountedNotACrash) {
  const TileBuilderConfig cfg = distance_config();  // holds 210 pings
  ArenaStorage arena(TileBuilder::arena_bytes(cfg));
  TileBuilder tb;
  ASSERT_TRUE(tb.init(cfg, arena).is_ok());
  const std::vector<DistanceTile> tiles = run_by_distance(tb, 0.02, 1201);  // 500 pings per 10 m
  ASSERT_EQ(tiles.size(), 3u);  // ends at 10, 16, 22 m
  for (const DistanceTile& t : tiles) {
    EXPECT_EQ(t.last - t.first + 1, 210u);  // cut short to the ring's capacity
    EXPECT_NEAR(t.end_m - t.start_m, 209 * 0.02, 1e-9);
  }
  EXPECT_EQ(tb.counters().get(TileCounter::kTileOverflow), 3u);
}

TEST(TileBuilder, ByDistanceNextStrideMovesTheNextTileOnly) {
  const TileBuilderConfig cfg = distance_config();
  ArenaStorage arena(TileBuilder::arena_bytes(cfg));
  TileBuilder tb;
  ASSERT_TRUE(tb.init(cfg, arena).is_ok());
  const std::vector<DistanceTile> tiles = run_by_distance(tb, 0.1, 401, 0, 9.0);  // after tile 0: next in 9 m
  ASSERT_GE(tiles.size(), 4u);
  EXPECT_NEAR(tiles[0].end_m, 10.0, 1e-6);
  EXPECT_NEAR(tiles[1].end_m, 19.0, 0.1 + 1e-6);
  EXPECT_NEAR(tiles[2].end_m, 25.0, 0.1 + 1e-6);  // back to the 6 m stride
  EXPECT_NEAR(tiles[3].end_m, 31.0, 0.1 + 1e-6);
}

TEST(TileBuilder, ByDistanceBadLengthsAreNamedErrors) {
  for (double len : {-1.0, std::nan(""), 1e9}) {
    TileBuilderConfig c = distance_config();
    c.tile_length_m = len;
    ArenaStorage arena(TileBuilder::arena_bytes(c));
    TileBuilder tb;
    const Status s = tb.init(c, arena);
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
    EXPECT_NE(std::string(s.message()).find("tile_length_m"), std::string::npos);
  }
  TileBuilderConfig c = distance_config();
  c.tile_stride_m = 0.0;
  ArenaStorage arena(TileBuilder::arena_bytes(c));
  TileBuilder tb;
  const Status s = tb.init(c, arena);
  EXPECT_NE(std::string(s.message()).find("tile_stride_m"), std::string::npos);
}

TEST(TileBuilder, ByDistanceAFrozenPoseIsFramedAtTheLastPingSpacing) {
  // Dead reckoning without odometry (a DVL loss) freezes the pose: the pings go on, so do the tiles.
  const TileBuilderConfig cfg = distance_config();
  ArenaStorage arena(TileBuilder::arena_bytes(cfg));
  TileBuilder tb;
  ASSERT_TRUE(tb.init(cfg, arena).is_ok());
  LineSource src;
  src.bins = 60;
  std::vector<std::uint32_t> last_pings;
  for (int k = 0; k < 400; ++k) {
    const Pose2 pose{std::min(k, 150) * 0.1, 0.0, 0.0};  // moves 15 m, then frozen
    const Result<bool> r = tb.push(src.make(pose, static_cast<std::uint32_t>(k)), pose);
    ASSERT_TRUE(r.is_ok());
    if (r.value()) last_pings.push_back(tb.tile().last_ping);
  }
  // Tiles end at pings 100, 160, 220, 280, 340, 400 (every 60 pings of 0.1 m, frozen or not).
  ASSERT_EQ(last_pings.size(), 5u);
  for (std::size_t i = 0; i < last_pings.size(); ++i) EXPECT_NEAR(static_cast<double>(last_pings[i]), 100.0 + 60.0 * static_cast<double>(i), 1.0);
  EXPECT_EQ(tb.counters().get(TileCounter::kFrozenPose), 249u);
}

TEST(TileBuilder, ByDistanceAStationaryVehicleMakesNoTile) {
  const TileBuilderConfig cfg = distance_config();
  ArenaStorage arena(TileBuilder::arena_bytes(cfg));
  TileBuilder tb;
  ASSERT_TRUE(tb.init(cfg, arena).is_ok());
  EXPECT_TRUE(run_by_distance(tb, 0.0, 1000).empty());
}

}  // namespace
}  // namespace qnav::sonar
