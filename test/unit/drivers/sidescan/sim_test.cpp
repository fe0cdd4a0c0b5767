// Side-scan simulator: determinism, shadows, trajectories (repeat passes, reverse, DR noise), and
// the end-to-end check the route work relies on: a tile built from simulated scanlines with exact
// navigation matches the ground-truth reflectivity and is georeferenced to better than a pixel.
#include <gtest/gtest.h>

#include <algorithm>
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

TEST(SideScanSim, SeabedCacheGivesBitIdenticalSamples) {
  SeabedConfig bc;
  bc.rock_probability = 0.9f;
  Seabed bed;
  ASSERT_TRUE(bed.init(bc).is_ok());
  SeabedCache cache;
  int rocks = 0;
  for (int k = 0; k < 20000; ++k) {
    const double n = -50.0 + 0.013 * k, e = 17.0 - 0.007 * k;  // a march crossing many cells
    const SeabedSample a = bed.sample(n, e), b = bed.sample(n, e, cache);
    ASSERT_EQ(a.reflectivity, b.reflectivity) << k;
    ASSERT_EQ(a.height_m, b.height_m) << k;
    rocks += a.height_m > 0.2f ? 1 : 0;
  }
  EXPECT_GT(rocks, 0);  // the march crossed rocks
}

// A changed seabed (issue 29): unchanged where the change parameters are zero (bit for bit), and
// with change_fraction f about f of the rock cells flipped and a share of the ground brighter or darker.
TEST(SideScanSim, AChangedSeabedDiffersByAboutItsFractionAndZeroChangeIsTheSameSeabed) {
  SeabedConfig bc;
  Seabed bed, same, changed;
  ASSERT_TRUE(bed.init(bc).is_ok());
  SeabedConfig zero = bc;
  zero.change_seed = 99;  // a seed alone changes nothing
  ASSERT_TRUE(same.init(zero).is_ok());
  SeabedConfig cc = bc;
  cc.change_fraction = 0.3f;
  cc.change_ripple_shift_m = 0.3f;
  ASSERT_TRUE(changed.init(cc).is_ok());
  int differ = 0, rock_cells = 0, rock_flips = 0;
  const int n_pts = 20000;
  for (int k = 0; k < n_pts; ++k) {
    const double n = -300.0 + 0.031 * k, e = 40.0 - 0.017 * k;
    const SeabedSample a = bed.sample(n, e), z = same.sample(n, e), c = changed.sample(n, e);
    ASSERT_EQ(a.reflectivity, z.reflectivity) << k;
    ASSERT_EQ(a.height_m, z.height_m) << k;
    differ += std::fabs(a.reflectivity - c.reflectivity) > 0.05f;
  }
  // Rock cells: sample every cell centre's 5 x 5 grid for any height above the ripples.
  for (int cn = 0; cn < 40; ++cn)
    for (int ce = 0; ce < 40; ++ce) {
      bool ra = false, rc = false;
      for (int i = 0; i < 15; ++i)
        for (int j = 0; j < 15; ++j) {
          const double n = cn * 15.0 + i + 0.5, e = ce * 15.0 + j + 0.5;
          ra = ra || bed.sample(n, e).height_m > 0.2f;
          rc = rc || changed.sample(n, e).height_m > 0.2f;
        }
      rock_cells += ra;
      rock_flips += ra != rc;
    }
  EXPECT_GT(rock_cells, 200);
  EXPECT_NEAR(static_cast<double>(rock_flips) / 1600.0, 0.3, 0.06) << rock_flips << " of 1600 cells flipped";
  EXPECT_GT(differ, n_pts / 10) << "moved ripples and changed patches";
  EXPECT_LT(differ, n_pts * 9 / 10);
}

// change_irregular: the changed discs are no longer a lattice (centred in their 12 m cell, one radius):
// per changed cell, the centroid of the change moves off the cell centre and its area varies; with
// change_fraction 0 the flag changes nothing.
TEST(SideScanSim, IrregularChangedDiscsAreNoLatticeAndZeroChangeStaysTheSame) {
  SeabedConfig bc;
  bc.rock_cell_m = 0.0f;  // the discs alone change the seabed here
  Seabed bed, zero_irr, lattice, irregular;
  ASSERT_TRUE(bed.init(bc).is_ok());
  SeabedConfig z = bc;
  z.change_irregular = true;
  ASSERT_TRUE(zero_irr.init(z).is_ok());
  SeabedConfig lc = bc;
  lc.change_fraction = 0.6f;
  ASSERT_TRUE(lattice.init(lc).is_ok());
  SeabedConfig ic = lc;
  ic.change_irregular = true;
  ASSERT_TRUE(irregular.init(ic).is_ok());
  const double cs = static_cast<double>(lc.change_scale_m);
  double lat_max_off = 0.0, irr_sum_off = 0.0;
  int lat_cells = 0, irr_cells = 0, irr_area_min = 1 << 30, irr_area_max = 0;
  for (int cn = 0; cn < 12; ++cn)
    for (int ce = 0; ce < 12; ++ce) {
      double ln = 0, le = 0, in = 0, ie = 0;
      int la = 0, ia = 0;
      for (int i = 0; i < 24; ++i)
        for (int j = 0; j < 24; ++j) {
          const double n = cn * cs + (i + 0.5) * cs / 24.0, e = ce * cs + (j + 0.5) * cs / 24.0;
          const SeabedSample a = bed.sample(n, e);
          ASSERT_EQ(a.reflectivity, zero_irr.sample(n, e).reflectivity);
          if (std::fabs(lattice.sample(n, e).reflectivity - a.reflectivity) > 0.05f) ln += n, le += e, ++la;
          if (std::fabs(irregular.sample(n, e).reflectivity - a.reflectivity) > 0.05f) in += n, ie += e, ++ia;
        }
      const double mn = (cn + 0.5) * cs, me = (ce + 0.5) * cs;
      if (la > 20) {
        lat_max_off = std::max(lat_max_off, std::hypot(ln / la - mn, le / la - me));
        ++lat_cells;
      }
      if (ia > 20) {
        irr_sum_off += std::hypot(in / ia - mn, ie / ia - me);
        ++irr_cells;
        irr_area_min = std::min(irr_area_min, ia);
        irr_area_max = std::max(irr_area_max, ia);
      }
    }
  ASSERT_GT(lat_cells, 40);
  ASSERT_GT(irr_cells, 40);
  EXPECT_LT(lat_max_off, 0.3) << "lattice: every disc centred in its cell";
  EXPECT_GT(irr_sum_off / irr_cells, 0.8) << "irregular: discs off their cell centres (m, mean)";
  EXPECT_GT(irr_area_max, 2 * irr_area_min) << "irregular: radii differ";
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

// Speckle coherence between pings (speckle_coherence_m): the intensity correlation of the speckle of
// two pings d apart is (1 - d / L)^2 for d < L, the speckle stays unit-mean Rayleigh, and pings at
// least L apart are bit-identical to the simulator without coherence (so the route's 0.3 m between
// pings renders as before).
struct SpeckleRun {
  std::vector<std::vector<float>> speckle;  // per ping: both sides' output / the speckle-free output
};
SpeckleRun speckle_run(const Seabed& bed, float coherence_m, double step_m, int pings, std::vector<std::vector<float>>* raw = nullptr) {
  constexpr int kN = 512;
  SideScanSimConfig sc;
  sc.samples_per_side = kN;
  sc.noise_floor = 0.0f;
  sc.speckle_coherence_m = coherence_m;
  SideScanSimConfig flat = sc;
  flat.speckle = false;
  SideScanSimulator sim, clean;
  EXPECT_TRUE(sim.init(sc, &bed).is_ok());
  EXPECT_TRUE(clean.init(flat, &bed).is_ok());
  SpeckleRun r;
  std::vector<float> p(kN), s(kN), cp(kN), cs(kN);
  for (int k = 0; k < pings; ++k) {
    const Pose2 pose{k * step_m, 0.0, 0.0};
    EXPECT_TRUE(sim.ping(pose, 8.0f, static_cast<std::uint32_t>(k), Span<float>(p.data(), kN), Span<float>(s.data(), kN)).is_ok());
    EXPECT_TRUE(clean.ping(pose, 8.0f, static_cast<std::uint32_t>(k), Span<float>(cp.data(), kN), Span<float>(cs.data(), kN)).is_ok());
    std::vector<float> ratio;
    for (int i = 0; i < kN; ++i) {
      ratio.push_back(cp[static_cast<std::size_t>(i)] > 1e-3f ? p[static_cast<std::size_t>(i)] / cp[static_cast<std::size_t>(i)] : -1.0f);
      ratio.push_back(cs[static_cast<std::size_t>(i)] > 1e-3f ? s[static_cast<std::size_t>(i)] / cs[static_cast<std::size_t>(i)] : -1.0f);
    }
    r.speckle.push_back(ratio);
    if (raw != nullptr) {
      std::vector<float> both(p);
      both.insert(both.end(), s.begin(), s.end());
      raw->push_back(both);
    }
  }
  return r;
}
struct SpeckleStats {
  double mean_amplitude, neighbour_intensity_corr;
};
SpeckleStats speckle_stats(const SpeckleRun& r) {
  double sum = 0.0, n = 0.0;
  for (const auto& v : r.speckle)
    for (float xf : v)
      if (xf >= 0.0f) {
        const double x = static_cast<double>(xf);
        sum += x * x;
        n += 1.0;
      }
  const double mean_i = sum / n;  // intensity mean
  double a_sum = 0.0, cov = 0.0, va = 0.0, vb = 0.0;
  for (std::size_t k = 0; k + 1 < r.speckle.size(); ++k)
    for (std::size_t i = 0; i < r.speckle[k].size(); ++i) {
      const double a = static_cast<double>(r.speckle[k][i]), b = static_cast<double>(r.speckle[k + 1][i]);
      if (a < 0.0 || b < 0.0) continue;
      const double da = a * a - mean_i, db = b * b - mean_i;
      cov += da * db;
      va += da * da;
      vb += db * db;
    }
  for (const auto& v : r.speckle)
    for (float x : v)
      if (x >= 0.0f) a_sum += static_cast<double>(x);
  return {a_sum / n, cov / std::sqrt(va * vb)};
}

TEST(SideScanSim, SpeckleStaysCoherentBetweenPingsCloserThanTheCoherenceLength) {
  Seabed bed;
  ASSERT_TRUE(bed.init(flat_seabed()).is_ok());
  const SpeckleStats half = speckle_stats(speckle_run(bed, 0.2f, 0.1, 24));   // rho 0.5: intensity correlation 0.25
  const SpeckleStats three_quarters = speckle_stats(speckle_run(bed, 0.2f, 0.05, 24));  // rho 0.75: 0.5625
  const SpeckleStats indep = speckle_stats(speckle_run(bed, 0.0f, 0.1, 24));
  EXPECT_NEAR(half.neighbour_intensity_corr, 0.25, 0.05);
  EXPECT_NEAR(three_quarters.neighbour_intensity_corr, 0.5625, 0.05);
  EXPECT_NEAR(indep.neighbour_intensity_corr, 0.0, 0.04);
  for (const SpeckleStats& s : {half, three_quarters, indep}) EXPECT_NEAR(s.mean_amplitude, 1.0, 0.03);  // unit-mean Rayleigh kept
}

TEST(SideScanSim, PingsAtLeastTheCoherenceLengthApartAreUnchanged) {
  Seabed bed;
  ASSERT_TRUE(bed.init(SeabedConfig{}).is_ok());
  std::vector<std::vector<float>> with, without;
  (void)speckle_run(bed, 0.2f, 0.3, 6, &with);
  (void)speckle_run(bed, 0.0f, 0.3, 6, &without);
  EXPECT_EQ(with, without);
  SideScanSimConfig bad;
  bad.speckle_coherence_m = -0.1f;
  SideScanSimulator sim;
  EXPECT_EQ(sim.init(bad, &bed).code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace qnav::sidescan
