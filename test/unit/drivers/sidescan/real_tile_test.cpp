// The real Iver2 pass over the Scotsman wreck through the whole chain (XTF reader -> first-return
// detection, TVG, slant->ground, EGN -> north-up tile on the file's fixes), host only. The wreck
// must be visible: around the hand-labelled hit (.hits: starboard sample 138 of ping 281) the tile
// holds the wreck's acoustic shadow (dark) and its bright returns, far more than the rest of the tile.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "drivers/sidescan/xtf_reader.hpp"
#include "nav/sonar/scanline_corrector.hpp"
#include "nav/sonar/tile_builder.hpp"
#include "firmware/tools/file_source.hpp"
#include "firmware/tools/shared_dir.hpp"

namespace qnav::sidescan {
namespace {

TEST(RealIver2, WreckIsVisibleInTheNorthUpTile) {
  const std::string path = qnav::tools::shared_dir() + "/data/sidescan/cidco-scotsman-iver2/scotsman-iver2.xtf";
  tools::FileSource src;
  if (!src.open(path.c_str())) GTEST_SKIP() << "missing " << path;
  XtfReader reader;
  ASSERT_TRUE(reader.init(XtfReaderConfig{}).is_ok());
  ASSERT_TRUE(reader.open(src).is_ok());
  sonar::ScanlineCorrectorConfig cc;
  cc.max_samples_per_side = 1024;
  cc.ground_bin_m = 0.05f;
  cc.ground_bins_per_side = 600;
  cc.nadir_gap_m = 1.0f;
  sonar::TileBuilderConfig tc;
  tc.resolution_m = 0.1;
  tc.scanlines_per_tile = 500;
  tc.scanline_stride = 500;
  tc.max_bins_per_side = 600;
  ArenaStorage arena(sonar::ScanlineCorrector::arena_bytes(cc) + sonar::TileBuilder::arena_bytes(tc));
  sonar::ScanlineCorrector corr;
  sonar::TileBuilder tb;
  ASSERT_TRUE(corr.init(cc, arena).is_ok());
  ASSERT_TRUE(tb.init(tc, arena).is_ok());
  std::vector<float> port(1024), stbd(1024);
  XtfRecord rec;
  double lat0 = 0.0, lon0 = 0.0;
  bool have0 = false;
  int corrected = 0;
  Vec2d hit_ne(0.0, 0.0);
  bool have_hit = false;
  for (;;) {
    const Result<bool> r = reader.next(rec, Span<float>(port.data(), 1024), Span<float>(stbd.data(), 1024));
    ASSERT_TRUE(r.is_ok());
    if (!r.value()) break;
    const XtfPing& x = rec.ping;
    if (!x.nav_valid) continue;
    if (!have0) {
      lat0 = x.sensor_y;
      lon0 = x.sensor_x;
      have0 = true;
    }
    const Pose2 pose{(x.sensor_y - lat0) * 111320.0, (x.sensor_x - lon0) * 111320.0 * std::cos(deg_to_rad(lat0)),
                     deg_to_rad(static_cast<double>(x.heading_deg))};
    sonar::SonarPing p;
    p.port = Span<const float>(port.data(), x.samples_per_side);
    p.stbd = Span<const float>(stbd.data(), x.samples_per_side);
    p.slant_range_m = x.slant_range_m;
    p.ping_number = x.ping_number;
    sonar::CorrectedScanline line;
    ASSERT_TRUE(corr.correct(p, line).is_ok()) << "ping " << x.ping_number;
    ++corrected;
    if (x.ping_number == 281) {
      // Ground position of starboard sample 138 (slant 138.5 * 30 m / 1024) at the detected altitude.
      const double rs = 138.5 * static_cast<double>(x.slant_range_m) / 1024.0, h = static_cast<double>(line.altitude_m);
      const double g = rs > h ? std::sqrt(rs * rs - h * h) : 0.0;
      // The label marks the wreck's near edge; its body and shadow lie further out: look 8 m beyond.
      hit_ne = pose.translation() + (g + 8.0) * sonar::starboard_unit(pose.heading_rad);
      have_hit = true;
    }
    ASSERT_TRUE(tb.push(line, pose).is_ok());
  }
  ASSERT_TRUE(tb.flush().is_ok());
  EXPECT_EQ(corrected, 460);
  ASSERT_TRUE(have_hit);
  const sonar::SonarTile& t = tb.tile();
  ASSERT_EQ(t.scanlines, 460u);
  // Shadow (< 0.25 of the mean level) and bright (> 2) pixel fractions within 12 m of a point 8 m
  // beyond the labelled hit vs the rest of the tile.
  const Vec2d c = t.ne_to_pixel(hit_ne.x(), hit_ne.y());
  const double rad_px = 12.0 / t.resolution_m;
  std::printf("[real tile] wreck centre (8 m beyond the label) at tile pixel (%.0f, %.0f)\n", c.x(), c.y());
  long near_n = 0, near_dark = 0, near_bright = 0, far_n = 0, far_dark = 0, far_bright = 0;
  for (int r = 0; r < t.coverage.height(); ++r)
    for (int k = 0; k < t.coverage.width(); ++k) {
      if (t.coverage(k, r) == 0) continue;
      const float v = t.intensity(k, r);
      const bool near = std::hypot(k + 0.5 - c.x(), r + 0.5 - c.y()) < rad_px;
      (near ? near_n : far_n)++;
      if (v < 0.25f) (near ? near_dark : far_dark)++;
      if (v > 2.0f) (near ? near_bright : far_bright)++;
    }
  ASSERT_GT(near_n, 10000);
  const double nd = static_cast<double>(near_dark) / near_n, fd = static_cast<double>(far_dark) / far_n;
  const double nb = static_cast<double>(near_bright) / near_n, fb = static_cast<double>(far_bright) / far_n;
  std::printf("[real tile] within 12 m of the wreck: %.1f %% shadow, %.1f %% bright; rest of the tile: %.1f %% / %.1f %%\n",
              100 * nd, 100 * nb, 100 * fd, 100 * fb);
  EXPECT_GT(nd, 10.0 * fd);
  EXPECT_GT(nb, 3.0 * fb);
}

}  // namespace
}  // namespace qnav::sidescan
