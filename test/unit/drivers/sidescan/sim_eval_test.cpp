// Side-scan simulator end to end (host only, heavier): a tile built from simulated scanlines with
// exact navigation matches the ground-truth reflectivity and is georeferenced to better than a pixel.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <utility>
#include <vector>

#include "drivers/sidescan/sim_seabed.hpp"
#include "drivers/sidescan/sim_sidescan.hpp"
#include "drivers/sidescan/sim_trajectory.hpp"
#include "nav/sonar/scanline_corrector.hpp"
#include "nav/sonar/tile_builder.hpp"
#include "test/support/alloc_guard.hpp"

namespace qnav::sidescan {
namespace {

SeabedConfig flat_seabed() {
  SeabedConfig c;
  c.ripple_height_m = 0.0f;  // reflectivity-only seabed: what the sonar sees is reflectivity * geometry
  c.rock_cell_m = 0.0f;
  return c;
}

// Box-filtered (2r+1)^2 means of the tile and of a truth raster over pixels whose whole window was
// measured (coverage 1), then their normalised correlation. r = 0 is the raw per-pixel correlation.
double smoothed_correlation(const sonar::SonarTile& t, const std::vector<float>& truth, int rad) {
  const int W = t.intensity.width(), H = t.intensity.height();
  double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
  long n = 0;
  for (int r = rad; r < H - rad; r += 1 + rad)
    for (int c = rad; c < W - rad; c += 1 + rad) {
      double a = 0.0, b = 0.0;
      bool full = true;
      for (int dy = -rad; dy <= rad && full; ++dy)
        for (int dx = -rad; dx <= rad; ++dx) {
          if (t.coverage(c + dx, r + dy) != 1) {
            full = false;
            break;
          }
          a += static_cast<double>(t.intensity(c + dx, r + dy));
          b += static_cast<double>(truth[static_cast<std::size_t>((r + dy) * W + c + dx)]);
        }
      if (!full) continue;
      sa += a;
      sb += b;
      saa += a * a;
      sbb += b * b;
      sab += a * b;
      ++n;
    }
  const double ca = saa - sa * sa / n, cb = sbb - sb * sb / n, cab = sab - sa * sb / n;
  return cab / std::sqrt(ca * cb);
}

struct SimPipeline {
  Seabed bed;
  SideScanSimulator sim;
  sonar::ScanlineCorrector corr;
  sonar::TileBuilder tb;
  ArenaStorage arena{16u << 20};
  Status init(const SeabedConfig& bc, bool speckle, float egn_alpha) {
    QNAV_RETURN_IF_ERROR(bed.init(bc));
    SideScanSimConfig sc;
    sc.samples_per_side = 512;
    sc.slant_range_m = 25.0f;
    sc.speckle = speckle;
    QNAV_RETURN_IF_ERROR(sim.init(sc, &bed));
    sonar::ScanlineCorrectorConfig cc;
    cc.max_samples_per_side = 512;
    cc.ground_bins_per_side = 240;
    cc.ground_bin_m = 0.1f;
    cc.nadir_gap_m = 1.0f;
    cc.spreading_db = sc.spreading_db;
    cc.egn_alpha = egn_alpha;
    QNAV_RETURN_IF_ERROR(corr.init(cc, arena));
    sonar::TileBuilderConfig tcfg;
    tcfg.resolution_m = 0.1;
    tcfg.tile_width_px = 600;
    tcfg.tile_height_px = 600;
    tcfg.scanlines_per_tile = 300;
    tcfg.scanline_stride = 300;
    tcfg.max_bins_per_side = 240;
    return tb.init(tcfg, arena);
  }
  // Flies the route, detecting the bottom (no altimeter); warm_up pings settle the EGN means and
  // are not part of the tile. Returns false if no tile was built.
  bool run(const TrajectoryConfig& trc, int warm_up) {
    Trajectory traj;
    if (!traj.init(trc).is_ok()) return false;
    TrajectorySample s;
    int k = 0;
    while (traj.next(s)) {
      const Result<sonar::SonarPing> p = sim.ping(s.truth, s.altitude_m, s.index, s.stamp_ns);
      if (!p.is_ok()) return false;
      sonar::SonarPing ping = p.value();
      ping.altitude_m = -1.0f;
      sonar::CorrectedScanline line;
      if (!corr.correct(ping, line).is_ok()) return false;
      EXPECT_NEAR(line.altitude_m, static_cast<float>(trc.altitude_m), 0.15f);
      if (k++ == warm_up) tb.reset();
      const Result<bool> r = tb.push(line, s.nav);
      if (!r.is_ok()) return false;
      if (r.value()) return true;
    }
    return false;
  }
  std::vector<float> truth_raster() const {
    const sonar::SonarTile& t = tb.tile();
    const int W = t.intensity.width(), H = t.intensity.height();
    std::vector<float> truth(static_cast<std::size_t>(W * H));
    for (int r = 0; r < H; ++r)
      for (int c = 0; c < W; ++c) {
        const Vec2d ne = t.pixel_to_ne(c + 0.5, r + 0.5);
        truth[static_cast<std::size_t>(r * W + c)] = bed.reflectivity(ne.x(), ne.y());
      }
    return truth;
  }
};

// Runs the chain once and returns the per-pixel (first) and 5x5-mean (second) correlations.
std::pair<double, double> tile_truth_correlation(bool speckle) {
  SimPipeline p;
  EXPECT_TRUE(p.init(flat_seabed(), speckle, 0.01f).is_ok());
  TrajectoryConfig trc;
  EXPECT_TRUE(trc.waypoints_ne.push_back(Vec2d(-20.0, 30.0)).is_ok());
  EXPECT_TRUE(trc.waypoints_ne.push_back(Vec2d(60.0, 50.0)).is_ok());
  trc.altitude_m = 5.0;
  EXPECT_TRUE(p.run(trc, 100));
  const std::vector<float> truth = p.truth_raster();
  const double c1 = smoothed_correlation(p.tb.tile(), truth, 0), c5 = smoothed_correlation(p.tb.tile(), truth, 2);
  std::printf("[sim tile] correlation with ground-truth reflectivity (speckle %s): %.3f per pixel, %.3f over 5x5 px means (coverage %.2f)\n",
              speckle ? "on" : "off", c1, c5, static_cast<double>(p.tb.tile().coverage_fraction));
  return {c1, c5};
}

TEST(SideScanSim, TileFromSimulatedPingsMatchesGroundTruthReflectivity) {
  // Without speckle the chain (sim -> bottom detection -> TVG -> ground range -> EGN -> tile) keeps
  // the reflectivity pattern; EGN's running mean removes part of the slow (patch) variation.
  EXPECT_GT(tile_truth_correlation(false).first, 0.75);
  // Speckle (Rayleigh, std/mean 0.52) bounds the per-pixel value; 5x5 px means lift it.
  const std::pair<double, double> c = tile_truth_correlation(true);
  EXPECT_GT(c.first, 0.3);
  EXPECT_GT(c.second, 0.5);
}

TEST(SideScanSim, TileGeoreferencingErrorBelowOnePixelWithExactNav) {
  // Bright flat discs (no height: no shadow or layover) on a uniform seabed, both sides of a track
  // at 14 deg; the intensity-weighted centroid of each disc in the tile vs its true position.
  SeabedConfig bc = flat_seabed();
  bc.texture_contrast = 0.0f;
  bc.patch_contrast = 0.0f;
  bc.ripple_contrast = 0.0f;
  const double heading = deg_to_rad(14.0);
  const Vec2d fwd(std::cos(heading), std::sin(heading)), right(-std::sin(heading), std::cos(heading));
  const double along[4] = {10.0, 18.0, 26.0, 34.0};
  const double across[4] = {-15.0, -6.0, 7.5, 17.0};
  std::vector<Vec2d> truth_ne;
  for (int i = 0; i < 4; ++i) {
    SeabedObject o;
    o.kind = SeabedObject::Kind::kCylinder;
    o.width_m = 1.0f;
    o.height_m = 0.0f;
    o.reflectivity = 1.0f;
    const Vec2d p = along[i] * fwd + across[i] * right;
    o.north_m = p.x();
    o.east_m = p.y();
    ASSERT_TRUE(bc.objects.push_back(o).is_ok());
    truth_ne.push_back(p);
  }
  SimPipeline p;
  ASSERT_TRUE(p.init(bc, false, 0.01f).is_ok());
  TrajectoryConfig trc;
  ASSERT_TRUE(trc.waypoints_ne.push_back(-5.0 * fwd).is_ok());
  ASSERT_TRUE(trc.waypoints_ne.push_back(60.0 * fwd).is_ok());
  trc.altitude_m = 5.0;
  ASSERT_TRUE(p.run(trc, 0));
  const sonar::SonarTile& t = p.tb.tile();
  double worst_px = 0.0;
  for (const Vec2d& q : truth_ne) {
    const Vec2d c = t.ne_to_pixel(q.x(), q.y());
    double sx = 0, sy = 0, sw = 0;
    for (int r = static_cast<int>(c.y()) - 15; r <= static_cast<int>(c.y()) + 15; ++r)
      for (int k = static_cast<int>(c.x()) - 15; k <= static_cast<int>(c.x()) + 15; ++k) {
        if (!t.coverage.contains(k, r) || t.coverage(k, r) == 0) continue;
        const double w = static_cast<double>(t.intensity(k, r)) - 1.2;  // uniform seabed -> 1.0, disc -> 1.49
        if (w <= 0.0) continue;
        sx += w * (k + 0.5);
        sy += w * (r + 0.5);
        sw += w;
      }
    ASSERT_GT(sw, 0.0);
    const double err = std::hypot(sx / sw - c.x(), sy / sw - c.y());
    worst_px = std::max(worst_px, err);
  }
  std::printf("[sim tile] georeferencing error with exact navigation: worst %.3f px of %.2f m\n", worst_px, t.resolution_m);
  EXPECT_LT(worst_px, 1.0);
}

}  // namespace
}  // namespace qnav::sidescan
