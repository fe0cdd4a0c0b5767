// Side-scan simulator: determinism, shadows, trajectories (repeat passes, reverse, DR noise), and
// the end-to-end check the route work relies on: a tile built from simulated scanlines with exact
// navigation matches the ground-truth reflectivity and is georeferenced to better than a pixel.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
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

TEST(SideScanSim, IsDeterministicPerSeedAndPing) {
  Seabed bed;
  ASSERT_TRUE(bed.init(SeabedConfig{}).is_ok());
  SideScanSimConfig sc;
  sc.samples_per_side = 256;
  SideScanSimulator a, b;
  ASSERT_TRUE(a.init(sc, &bed).is_ok());
  ASSERT_TRUE(b.init(sc, &bed).is_ok());
  std::vector<float> p1(256), s1(256), p2(256), s2(256);
  const Pose2 pose{10.0, 20.0, 0.3};
  ASSERT_TRUE(a.ping(pose, 8.0f, 5, Span<float>(p1.data(), 256), Span<float>(s1.data(), 256)).is_ok());
  ASSERT_TRUE(b.ping(pose, 8.0f, 5, Span<float>(p2.data(), 256), Span<float>(s2.data(), 256)).is_ok());
  EXPECT_EQ(p1, p2);
  EXPECT_EQ(s1, s2);
  ASSERT_TRUE(b.ping(pose, 8.0f, 6, Span<float>(p2.data(), 256), Span<float>(s2.data(), 256)).is_ok());
  EXPECT_NE(p1, p2);  // new speckle draw per ping
  // Seabed ground truth is a pure function of position and seed.
  Seabed other;
  SeabedConfig oc;
  oc.seed = 2;
  ASSERT_TRUE(other.init(oc).is_ok());
  EXPECT_EQ(bed.reflectivity(3.0, 4.0), Seabed(bed).reflectivity(3.0, 4.0));
  EXPECT_NE(bed.reflectivity(3.0, 4.0), other.reflectivity(3.0, 4.0));
}

TEST(SideScanSim, ObjectCastsAShadowOfTheExpectedLength) {
  SeabedConfig bc = flat_seabed();
  SeabedObject box;
  box.north_m = 0.0;
  box.east_m = 20.0;  // 20 m to starboard of a north-heading vehicle at the origin
  box.length_m = 6.0f;
  box.width_m = 2.0f;
  box.height_m = 2.0f;
  box.heading_rad = 0.0f;
  ASSERT_TRUE(bc.objects.push_back(box).is_ok());
  Seabed bed;
  ASSERT_TRUE(bed.init(bc).is_ok());
  SideScanSimConfig sc;
  sc.samples_per_side = 1000;
  sc.slant_range_m = 50.0f;
  sc.speckle = false;
  SideScanSimulator sim;
  ASSERT_TRUE(sim.init(sc, &bed).is_ok());
  std::vector<float> port(1000), stbd(1000);
  const float a = 10.0f;
  ASSERT_TRUE(sim.ping(Pose2{0.0, 0.0, 0.0}, a, 0, Span<float>(port.data(), 1000), Span<float>(stbd.data(), 1000)).is_ok());
  // Far edge of the box at g = 21 m, top at 2 m: shadow to g = 21 * 10 / 8 = 26.25 m.
  const auto slant_index = [&](double g) { return static_cast<int>(std::sqrt(g * g + static_cast<double>(a * a)) / 0.05); };
  const float noise = sc.noise_floor * sc.gain;
  for (int i = slant_index(21.3); i < slant_index(26.0); ++i) EXPECT_LE(stbd[static_cast<std::size_t>(i)], noise * 1.01f) << i;
  // Lit seabed just beyond the shadow, and the object's face is bright.
  EXPECT_GT(stbd[static_cast<std::size_t>(slant_index(27.0))], 3.0f * noise);
  float face = 0.0f;
  // The 2 m face at g = 19 m lies over (layover) to the slant range of flat seabed at g ~ 18 m.
  for (int i = slant_index(17.0); i < slant_index(19.5); ++i) face = std::max(face, stbd[static_cast<std::size_t>(i)]);
  EXPECT_GT(face, 3.0f * stbd[static_cast<std::size_t>(slant_index(15.0))]);
  // Port side (flat) has no shadow there.
  EXPECT_GT(port[static_cast<std::size_t>(slant_index(23.0))], 3.0f * noise);
  // Water column holds noise only.
  EXPECT_LE(stbd[100], noise * 1.01f);
}

TEST(SideScanSim, TrajectoryRepeatPassesForwardAndReverse) {
  TrajectoryConfig tc;
  ASSERT_TRUE(tc.waypoints_ne.push_back(Vec2d(0.0, 0.0)).is_ok());
  ASSERT_TRUE(tc.waypoints_ne.push_back(Vec2d(1000.0, 0.0)).is_ok());
  ASSERT_TRUE(tc.waypoints_ne.push_back(Vec2d(1000.0, 1000.0)).is_ok());
  tc.lateral_offset_m = 5.0;
  Trajectory fwd, rev;
  ASSERT_TRUE(fwd.init(tc).is_ok());
  tc.reverse = true;
  ASSERT_TRUE(rev.init(tc).is_ok());
  EXPECT_DOUBLE_EQ(fwd.route_length_m(), 2000.0);
  TrajectorySample s;
  ASSERT_TRUE(fwd.next(s));
  // Forward: starts at the first waypoint, 5 m right of a north-going route = 5 m east.
  EXPECT_NEAR(s.truth.x_m, 0.0, 1e-9);
  EXPECT_NEAR(s.truth.y_m, 5.0, 1e-9);
  EXPECT_NEAR(s.truth.heading_rad, 0.0, 1e-9);
  EXPECT_EQ(s.nav.x_m, s.truth.x_m);
  ASSERT_TRUE(rev.next(s));
  // Reverse: starts at the last waypoint heading west, still right of the route's forward direction (south).
  EXPECT_NEAR(s.truth.x_m, 995.0, 1e-9);
  EXPECT_NEAR(s.truth.y_m, 1000.0, 1e-9);
  EXPECT_NEAR(std::fabs(s.truth.heading_rad), kPi / 2.0, 1e-9);
  EXPECT_LT(s.truth.heading_rad, 0.0);
  std::uint32_t n = 1;
  while (rev.next(s)) ++n;
  EXPECT_EQ(n, rev.pings_total());
  EXPECT_NEAR(n, 2000.0 / 1.5 * 10.0, 2.0);
  EXPECT_NEAR(s.truth.x_m, 0.0, 0.2);
  EXPECT_NEAR(s.truth.y_m, 5.0, 1e-9);
  // Exact navigation without noise over 2 km.
  EXPECT_NEAR(s.nav.x_m, s.truth.x_m, 1e-6);
  EXPECT_NEAR(s.nav.y_m, s.truth.y_m, 1e-6);
}

TEST(SideScanSim, DeadReckoningDriftsWithHeadingBias) {
  TrajectoryConfig tc;
  ASSERT_TRUE(tc.waypoints_ne.push_back(Vec2d(0.0, 0.0)).is_ok());
  ASSERT_TRUE(tc.waypoints_ne.push_back(Vec2d(100.0, 0.0)).is_ok());
  tc.heading_bias_rad = deg_to_rad(1.0);
  tc.heading_noise_rad = deg_to_rad(0.5);
  tc.speed_scale_error = 0.02;
  Trajectory t;
  ASSERT_TRUE(t.init(tc).is_ok());
  TrajectorySample s;
  while (t.next(s)) {
  }
  // 1 deg bias over 100 m = 1.75 m cross-track; 2 % speed error = 2 m along.
  EXPECT_NEAR(s.nav.y_m - s.truth.y_m, 100.0 * std::sin(deg_to_rad(1.0)), 0.3);
  EXPECT_NEAR(s.nav.x_m - s.truth.x_m, 2.0, 0.3);
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

double tile_truth_correlation(bool speckle, int rad) {
  SimPipeline p;
  EXPECT_TRUE(p.init(flat_seabed(), speckle, 0.01f).is_ok());
  TrajectoryConfig trc;
  EXPECT_TRUE(trc.waypoints_ne.push_back(Vec2d(-20.0, 30.0)).is_ok());
  EXPECT_TRUE(trc.waypoints_ne.push_back(Vec2d(60.0, 50.0)).is_ok());
  trc.altitude_m = 5.0;
  EXPECT_TRUE(p.run(trc, 100));
  const double c = smoothed_correlation(p.tb.tile(), p.truth_raster(), rad);
  std::printf("[sim tile] correlation with ground-truth reflectivity (speckle %s, %dx%d px): %.3f (coverage %.2f)\n",
              speckle ? "on" : "off", 2 * rad + 1, 2 * rad + 1, c, static_cast<double>(p.tb.tile().coverage_fraction));
  return c;
}

TEST(SideScanSim, TileFromSimulatedPingsMatchesGroundTruthReflectivity) {
  // Without speckle the chain (sim -> bottom detection -> TVG -> ground range -> EGN -> tile) keeps
  // the reflectivity pattern; EGN's running mean removes part of the slow (patch) variation.
  EXPECT_GT(tile_truth_correlation(false, 0), 0.75);
  // Speckle (Rayleigh, std/mean 0.52) bounds the per-pixel value; 5x5 px means lift it.
  EXPECT_GT(tile_truth_correlation(true, 0), 0.3);
  EXPECT_GT(tile_truth_correlation(true, 2), 0.5);
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

TEST(SideScanSim, PingMakesNoHeapAllocation) {
  Seabed bed;
  ASSERT_TRUE(bed.init(SeabedConfig{}).is_ok());
  SideScanSimulator sim;
  SideScanSimConfig sc;
  sc.samples_per_side = 256;
  ASSERT_TRUE(sim.init(sc, &bed).is_ok());
  bool ok = true;
  QNAV_EXPECT_NO_ALLOC(for (std::uint32_t k = 0; k < 10; ++k) ok = ok && sim.ping(Pose2{k * 0.15, 0.0, 0.0}, 8.0f, k, 0).is_ok());
  EXPECT_TRUE(ok);
}

}  // namespace
}  // namespace qnav::sidescan
