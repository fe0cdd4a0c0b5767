#include "nav/route/route_filter.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "nav/core/arena.hpp"
#include "test/support/alloc_guard.hpp"

namespace qnav::route {
namespace {

struct F {
  RouteFilterConfig cfg;
  ArenaStorage arena;
  RouteFilter f;
  explicit F(RouteFilterConfig c) : cfg(c), arena(RouteFilter::arena_bytes(c)) { EXPECT_TRUE(f.init(cfg, arena).is_ok()); }
};

RouteFilterConfig small(MotionModel m, RouteDirection d = RouteDirection::kForward) {
  RouteFilterConfig c;
  c.max_nodes = 200;
  c.motion = m;
  c.direction = d;
  c.kidnap_floor = 0.0;
  return c;
}

double sum(Span<const float> b) {
  double s = 0;
  for (float v : b) s += static_cast<double>(v);
  return s;
}

TEST(RouteFilter, StartsUniformWithMaximumEntropy) {
  F t(small(MotionModel::kOdometry));
  ASSERT_TRUE(t.f.reset(15, 50.0).is_ok());
  EXPECT_NEAR(t.f.entropy(), std::log(15.0), 1e-5);
  EXPECT_NEAR(t.f.probability(3), 1.0 / 15.0, 1e-6);
  EXPECT_FALSE(t.f.confident());
}

TEST(RouteFilter, TheEntryPriorLeansOnTheEntryEndWithoutBeingConfidentAndAStrongMatchElsewhereWins) {
  for (RouteDirection d : {RouteDirection::kForward, RouteDirection::kReverse}) {
    F t(small(MotionModel::kOdometry, d));
    ASSERT_TRUE(t.f.reset(34, 60.0).is_ok());
    ASSERT_TRUE(t.f.apply_entry_prior(0.5, 1.0).is_ok());
    const std::uint32_t entry = d == RouteDirection::kForward ? 0 : 33;
    EXPECT_NEAR(sum(t.f.belief()), 1.0, 1e-5);
    EXPECT_EQ(t.f.argmax(), entry);
    // Half-Gaussian over 0..4 nodes: 0.5 * 1 / 1.7533 on the entry node, + the uniform 0.5 / 34.
    EXPECT_NEAR(t.f.probability(entry), 0.5 / 1.75331 + 0.5 / 34.0, 1e-4);
    EXPECT_NEAR(t.f.probability(16), 0.5 / 34.0, 1e-6);  // far from the entry: the uniform share
    EXPECT_FALSE(t.f.confident());                        // a prior, not a fix
    EXPECT_NEAR(t.f.mass_near_argmax(), 0.5 * (1.0 + std::exp(-0.5)) / 1.75331 + 1.0 / 34.0, 1e-3);
    // A vehicle that joined the route elsewhere: two strong matches there (20 inliers) outweigh the
    // prior (the entry node starts 20 x as probable as node 16).
    const NodeMeasurement m[] = {{entry, 0.0f}, {16, 20.0f}};
    for (int k = 0; k < 2; ++k) {
      ASSERT_TRUE(t.f.predict(0.0).is_ok());
      ASSERT_TRUE(t.f.update(Span<const NodeMeasurement>(m, 2)).is_ok());
    }
    EXPECT_EQ(t.f.argmax(), 16u);
  }
  F t(small(MotionModel::kOdometry));
  EXPECT_EQ(t.f.apply_entry_prior(0.5, 1.0).code(), StatusCode::kNotReady);  // before reset()
  ASSERT_TRUE(t.f.reset(10, 60.0).is_ok());
  EXPECT_EQ(t.f.apply_entry_prior(1.0, 1.0).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(t.f.apply_entry_prior(0.5, 0.0).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(t.f.apply_entry_prior(std::nan(""), 1.0).code(), StatusCode::kInvalidArgument);
  ASSERT_TRUE(t.f.apply_entry_prior(0.0, 1.0).is_ok());  // 0: the paper's uniform start, unchanged
  EXPECT_NEAR(t.f.probability(0), 0.1, 1e-6);
}

TEST(RouteFilter, PaperEq5KernelMatchesTheFormula) {
  RouteFilterConfig c = small(MotionModel::kPaperEq5);
  c.sigma_w2 = 1.0;
  c.max_advance_nodes = 3;
  F t(c);
  ASSERT_TRUE(t.f.reset(20, 50.0).is_ok());
  NodeMeasurement m[1] = {{5, 1e6f}};  // pin the belief on node 5
  ASSERT_TRUE(t.f.update(Span<const NodeMeasurement>(m)).is_ok());
  ASSERT_GT(t.f.probability(5), 0.999f);
  ASSERT_TRUE(t.f.predict(0.0).is_ok());
  // p(n) ~ exp(-n / sigma^2), n = 0..3 transitions forward; none backward.
  const double beta = 1 + std::exp(-1.0) + std::exp(-2.0) + std::exp(-3.0);
  EXPECT_NEAR(t.f.probability(5), 1 / beta, 2e-3);
  EXPECT_NEAR(t.f.probability(6), std::exp(-1.0) / beta, 2e-3);
  EXPECT_NEAR(t.f.probability(8), std::exp(-3.0) / beta, 2e-3);
  EXPECT_LT(t.f.probability(4), 1e-3f);
  EXPECT_LT(t.f.probability(9), 1e-3f);
}

TEST(RouteFilter, OdometryModelMovesTheBeliefByDistanceOverSpacingInEitherDirection) {
  for (RouteDirection d : {RouteDirection::kForward, RouteDirection::kReverse}) {
    F t(small(MotionModel::kOdometry, d));
    ASSERT_TRUE(t.f.reset(50, 40.0).is_ok());
    NodeMeasurement m[1] = {{20, 1e6f}};
    ASSERT_TRUE(t.f.update(Span<const NodeMeasurement>(m)).is_ok());
    ASSERT_TRUE(t.f.predict(120.0).is_ok());  // 3 node spacings
    EXPECT_EQ(t.f.argmax(), d == RouteDirection::kForward ? 23u : 17u);
    EXPECT_NEAR(sum(t.f.belief()), 1.0, 1e-5);
  }
}

TEST(RouteFilter, TheEntryEndIsOpenAndMassPastTheExitLeavesTheRoute) {
  for (RouteDirection d : {RouteDirection::kForward, RouteDirection::kReverse}) {
    F t(small(MotionModel::kOdometry, d));
    ASSERT_TRUE(t.f.reset(20, 40.0).is_ok());
    // No information: a uniform belief stays uniform however far the vehicle goes (it may have
    // joined the route at its entry end).
    for (int k = 0; k < 5; ++k) ASSERT_TRUE(t.f.predict(40.0).is_ok());
    for (float v : t.f.belief()) EXPECT_NEAR(v, 1.0f / 20.0f, 1e-5f);
    // A peak at the exit end moves off the route: what is left renormalises onto the other nodes.
    const std::uint32_t exit_node = d == RouteDirection::kForward ? 19u : 0u;
    NodeMeasurement m[1] = {{exit_node, 1e4f}};
    ASSERT_TRUE(t.f.update(Span<const NodeMeasurement>(m)).is_ok());
    ASSERT_GT(t.f.probability(exit_node), 0.99f);
    ASSERT_TRUE(t.f.predict(80.0).is_ok());
    EXPECT_LT(t.f.probability(exit_node), 0.5f);
    EXPECT_NEAR(sum(t.f.belief()), 1.0, 1e-5);
    // A peak on the entry node moves on with the vehicle: the open entry does not keep feeding it
    // (found in review: virtual nodes carrying the entry's own belief held the argmax at the entry).
    const std::uint32_t entry_node = d == RouteDirection::kForward ? 0u : 19u;
    NodeMeasurement e[1] = {{entry_node, 1e4f}};
    ASSERT_TRUE(t.f.update(Span<const NodeMeasurement>(e)).is_ok());
    ASSERT_GT(t.f.probability(entry_node), 0.99f);
    for (int k = 1; k <= 3; ++k) {
      ASSERT_TRUE(t.f.predict(40.0).is_ok());
      const std::uint32_t want = d == RouteDirection::kForward ? static_cast<std::uint32_t>(k) : static_cast<std::uint32_t>(19 - k);
      EXPECT_EQ(t.f.argmax(), want) << "step " << k;
      EXPECT_GT(t.f.probability(want), 0.6f) << "step " << k;
      EXPECT_LT(t.f.probability(entry_node), 0.1f) << "step " << k;
    }
  }
}

TEST(RouteFilter, InlierCountsLocaliseAndOneBadTileDoesNotZeroTheTruth) {
  F t(small(MotionModel::kOdometry));
  ASSERT_TRUE(t.f.reset(30, 40.0).is_ok());
  // Five tiles along the route: strong similarity at the true node, chance counts elsewhere.
  for (std::uint32_t k = 0; k < 5; ++k) {
    ASSERT_TRUE(t.f.predict(k == 0 ? 0.0 : 40.0).is_ok());
    NodeMeasurement m[3] = {{10 + k, 25.0f}, {2, 3.0f}, {25, 4.0f}};
    ASSERT_TRUE(t.f.update(Span<const NodeMeasurement>(m)).is_ok());
  }
  EXPECT_EQ(t.f.argmax(), 14u);
  EXPECT_TRUE(t.f.confident());
  const double h_good = t.f.entropy();
  // A bad tile: a wrong node gets a spurious count, the truth gets nothing.
  ASSERT_TRUE(t.f.predict(40.0).is_ok());
  NodeMeasurement bad[2] = {{3, 12.0f}, {15, 0.0f}};
  ASSERT_TRUE(t.f.update(Span<const NodeMeasurement>(bad)).is_ok());
  EXPECT_EQ(t.f.argmax(), 15u);
  EXPECT_GT(t.f.probability(15), 0.2f);
  EXPECT_GT(t.f.entropy(), h_good - 1.0);
}

TEST(RouteFilter, MeasurementProbabilityIsEq9Normalised) {
  F t(small(MotionModel::kOdometry));
  ASSERT_TRUE(t.f.reset(10, 40.0).is_ok());
  NodeMeasurement m[2] = {{4, 23.0f}, {5, 13.0f}};
  ASSERT_TRUE(t.f.update(Span<const NodeMeasurement>(m)).is_ok());
  std::vector<float> p(10);
  ASSERT_TRUE(t.f.measurement_probability(Span<float>(p.data(), p.size())).is_ok());
  // L = floor + max(0, S - chance): 21, 11, and 1 for the other 8 nodes; sum 40.
  EXPECT_NEAR(p[4], 21.0 / 40.0, 1e-6);
  EXPECT_NEAR(p[5], 11.0 / 40.0, 1e-6);
  EXPECT_NEAR(p[0], 1.0 / 40.0, 1e-6);
}

TEST(RouteFilter, SelectsBeliefNodesPlusAWideSearchWithoutDuplicates) {
  RouteFilterConfig c = small(MotionModel::kOdometry);
  c.belief_registrations = 3;
  c.wide_search_registrations = 10;
  F t(c);
  ASSERT_TRUE(t.f.reset(100, 40.0).is_ok());
  NodeMeasurement m[1] = {{50, 1e4f}};
  ASSERT_TRUE(t.f.update(Span<const NodeMeasurement>(m)).is_ok());
  std::uint32_t sel[13];
  const std::size_t n = t.f.select_nodes(Span<std::uint32_t>(sel));
  ASSERT_GE(n, 3u);
  EXPECT_EQ(sel[0], 50u);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j) EXPECT_NE(sel[i], sel[j]);
  // Repeated wide searches visit the whole route.
  std::vector<int> seen(100, 0);
  for (int k = 0; k < 40; ++k) {
    const std::size_t nn = t.f.select_nodes(Span<std::uint32_t>(sel));
    for (std::size_t i = 0; i < nn; ++i) seen[sel[i]] = 1;
  }
  int covered = 0;
  for (int v : seen) covered += v;
  EXPECT_GT(covered, 90);
}

TEST(RouteFilter, KidnapFloorLetsAStrongMeasurementElsewhereWin) {
  RouteFilterConfig c = small(MotionModel::kOdometry);
  c.kidnap_floor = 1e-3;
  F t(c);
  ASSERT_TRUE(t.f.reset(60, 40.0).is_ok());
  for (int k = 0; k < 6; ++k) {
    ASSERT_TRUE(t.f.predict(40.0).is_ok());
    NodeMeasurement m[1] = {{static_cast<std::uint32_t>(10 + k), 30.0f}};
    ASSERT_TRUE(t.f.update(Span<const NodeMeasurement>(m)).is_ok());
  }
  ASSERT_EQ(t.f.argmax(), 15u);
  int steps = 0;
  for (int k = 0; k < 10 && t.f.argmax() != static_cast<std::uint32_t>(40 + k - 1); ++k, ++steps) {
    ASSERT_TRUE(t.f.predict(40.0).is_ok());
    NodeMeasurement m[1] = {{static_cast<std::uint32_t>(40 + k), 30.0f}};
    ASSERT_TRUE(t.f.update(Span<const NodeMeasurement>(m)).is_ok());
  }
  EXPECT_LE(steps, 4);
}

// Localises the filter on node `at` (odometry model, one node per update).
void localise(RouteFilter& f, std::uint32_t at) {
  for (int k = 0; k < 4; ++k) {
    ASSERT_TRUE(f.predict(40.0).is_ok());
    NodeMeasurement m[1] = {{at - 3 + static_cast<std::uint32_t>(k), 30.0f}};
    ASSERT_TRUE(f.update(Span<const NodeMeasurement>(m)).is_ok());
  }
  ASSERT_EQ(f.argmax(), at);
  ASSERT_TRUE(f.confident());
}

TEST(RouteFilter, NoSimilarityAnywhereIsNotLostTheBeliefRunsOnOdometry) {
  RouteFilterConfig c = small(MotionModel::kOdometry);
  c.kidnap_floor = 0.01;
  c.chance_inliers = 5.0f;
  c.lost_after_updates = 1;
  c.lost_evidence_inliers = 8.0f;
  c.lost_reset_mass = 0.9;
  F t(c);
  ASSERT_TRUE(t.f.reset(60, 40.0).is_ok());
  localise(t.f, 20);
  // Ten featureless tiles: every registration returns nothing.
  for (int k = 1; k <= 10; ++k) {
    ASSERT_TRUE(t.f.predict(40.0).is_ok());
    NodeMeasurement m[3] = {{static_cast<std::uint32_t>(20 + k), 0.0f}, {5, 0.0f}, {50, 3.0f}};
    ASSERT_TRUE(t.f.update(Span<const NodeMeasurement>(m)).is_ok());
    EXPECT_EQ(t.f.argmax(), static_cast<std::uint32_t>(20 + k));
  }
  EXPECT_FALSE(t.f.lost());
  EXPECT_EQ(t.f.counters().get(FilterCounter::kLostResets), 0u);
  // Weak similarity elsewhere (above chance, below the lost evidence) is not enough either.
  ASSERT_TRUE(t.f.predict(40.0).is_ok());
  NodeMeasurement weak[1] = {{50, 7.0f}};
  ASSERT_TRUE(t.f.update(Span<const NodeMeasurement>(weak)).is_ok());
  EXPECT_FALSE(t.f.lost());
  EXPECT_EQ(t.f.argmax(), 31u);
  // Strong similarity elsewhere and none near the estimate: lost, mass spread, then the new place wins.
  ASSERT_TRUE(t.f.predict(40.0).is_ok());
  NodeMeasurement strong[2] = {{32, 0.0f}, {50, 20.0f}};
  ASSERT_TRUE(t.f.update(Span<const NodeMeasurement>(strong)).is_ok());
  EXPECT_TRUE(t.f.lost());
  EXPECT_EQ(t.f.counters().get(FilterCounter::kLostResets), 1u);
  EXPECT_EQ(t.f.argmax(), 50u);
}

TEST(RouteFilter, WhileSearchingMostOfTheBudgetGoesToTheWideSearch) {
  RouteFilterConfig c = small(MotionModel::kOdometry);
  c.belief_registrations = 4;
  c.wide_search_registrations = 6;
  c.searching_registrations = 16;
  c.searching_belief_registrations = 2;
  c.chance_inliers = 5.0f;
  F t(c);
  ASSERT_EQ(c.max_registrations(), 16u);
  ASSERT_TRUE(t.f.reset(100, 40.0).is_ok());
  std::uint32_t sel[17];
  EXPECT_FALSE(t.f.confident());
  const std::size_t searching = t.f.select_nodes(Span<std::uint32_t>(sel));  // uniform belief: searching
  EXPECT_GE(searching, 15u);  // 16 less a wide node that may coincide with a belief node
  EXPECT_LE(searching, 16u);
  localise(t.f, 40);
  // Confident and supported: 4 belief nodes, the wide search only every wide_search_period updates.
  std::size_t sizes[4];
  for (std::size_t& n : sizes) n = t.f.select_nodes(Span<std::uint32_t>(sel));
  int wide = 0;
  for (std::size_t n : sizes) {
    EXPECT_TRUE(n == 4u || n == 10u) << n;
    wide += n == 10u;
  }
  EXPECT_EQ(wide, 1);
}

// A wide-search grid fixed to the route can step in step with a vehicle moving one node per update
// and miss it every time; the grid moves with the predicted advance, so it cannot.
TEST(RouteFilter, WideSearchFindsAVehicleMovingInStepWithTheGrid) {
  for (RouteDirection d : {RouteDirection::kForward, RouteDirection::kReverse})
    for (std::uint32_t wide : {12u, 14u, 16u, 17u}) {
      RouteFilterConfig c = small(MotionModel::kOdometry, d);
      c.belief_registrations = 1;
      c.wide_search_registrations = wide;
      F t(c);
      ASSERT_TRUE(t.f.reset(34, 40.0).is_ok());
      std::uint32_t sel[20];
      std::int64_t truth = d == RouteDirection::kForward ? 0 : 33;
      int hits = 0;
      for (int k = 0; k < 12; ++k) {
        ASSERT_TRUE(t.f.predict(k == 0 ? 0.0 : 40.0).is_ok());
        if (k > 0) truth += d == RouteDirection::kForward ? 1 : -1;
        const std::size_t n = t.f.select_nodes(Span<std::uint32_t>(sel));
        for (std::size_t i = 0; i < n; ++i) hits += sel[i] == truth;
        NodeMeasurement none[1] = {{0, 0.0f}};
        ASSERT_TRUE(t.f.update(Span<const NodeMeasurement>(none)).is_ok());
      }
      EXPECT_GE(hits, 3) << "wide " << wide << (d == RouteDirection::kForward ? " forward" : " reverse");
    }
}

TEST(RouteFilter, BadInputIsRejectedAndCounted) {
  F t(small(MotionModel::kOdometry));
  EXPECT_EQ(t.f.predict(1.0), StatusCode::kNotReady);
  EXPECT_EQ(t.f.reset(1, 40.0), StatusCode::kInvalidArgument);  // a route of one node
  EXPECT_EQ(t.f.reset(201, 40.0), StatusCode::kCapacityExceeded);
  ASSERT_TRUE(t.f.reset(10, 40.0).is_ok());
  EXPECT_EQ(t.f.predict(std::nan("")), StatusCode::kInvalidArgument);
  EXPECT_EQ(t.f.predict(-1.0), StatusCode::kInvalidArgument);
  NodeMeasurement m[2] = {{99, 10.0f}, {3, std::nanf("")}};
  ASSERT_TRUE(t.f.update(Span<const NodeMeasurement>(m)).is_ok());
  EXPECT_EQ(t.f.counters().get(FilterCounter::kBadDistance), 2u);
  EXPECT_EQ(t.f.counters().get(FilterCounter::kBadMeasurement), 2u);
  EXPECT_NEAR(t.f.probability(3), 0.1f, 1e-6f);
  for (float v : t.f.belief()) EXPECT_TRUE(std::isfinite(v));
}

TEST(RouteFilter, AHugeOrInfiniteAdvanceIsClampedOrRejectedNotACrash) {
  // Review finding: the kernel's lower bound was not capped at max_advance_nodes, so predict(1e12)
  // cast ~4e9 to int (undefined) and wrote past the 129-tap kernel; 1e308 / 0.5 m made it NaN.
  RouteFilterConfig c = small(MotionModel::kOdometry);
  F t(c);
  ASSERT_TRUE(t.f.reset(100, 60.0).is_ok());
  NodeMeasurement m[1] = {{10, 1e4f}};
  ASSERT_TRUE(t.f.update(Span<const NodeMeasurement>(m)).is_ok());
  ASSERT_TRUE(t.f.predict(1e12).is_ok());  // clamped to max_advance_nodes, counted
  EXPECT_EQ(t.f.counters().get(FilterCounter::kBadDistance), 1u);
  EXPECT_EQ(t.f.argmax(), 10u + static_cast<std::uint32_t>(c.max_advance_nodes));
  EXPECT_NEAR(sum(t.f.belief()), 1.0, 1e-5);
  // 100 nodes: also clamped (it was a 25-node rigid shift); the clamped kernel is cut at +m, so the
  // belief moves on by at most m per step.
  ASSERT_TRUE(t.f.predict(100.0 * 60.0).is_ok());
  EXPECT_GT(t.f.argmax(), 10u + static_cast<std::uint32_t>(c.max_advance_nodes));
  EXPECT_LE(t.f.argmax(), 10u + 2u * static_cast<std::uint32_t>(c.max_advance_nodes));
  ASSERT_TRUE(t.f.reset(100, 0.5).is_ok());
  EXPECT_EQ(t.f.predict(1e308), StatusCode::kInvalidArgument);  // distance / spacing overflows
  // A zero odometry sigma fraction still leaves the floor: the belief does not vanish on a long jump.
  c.odometry_sigma_frac = 0.0;
  F z(c);
  ASSERT_TRUE(z.f.reset(100, 60.0).is_ok());
  ASSERT_TRUE(z.f.update(Span<const NodeMeasurement>(m)).is_ok());
  EXPECT_TRUE(z.f.predict(20.0 * 60.0).is_ok());
  EXPECT_EQ(z.f.argmax(), 10u + static_cast<std::uint32_t>(c.max_advance_nodes));
  for (float v : z.f.belief()) EXPECT_TRUE(std::isfinite(v));
}

TEST(RouteFilter, PredictAndUpdateDoNotAllocate) {
  RouteFilterConfig c = small(MotionModel::kOdometry);
  c.max_nodes = 10000;
  F t(c);
  ASSERT_TRUE(t.f.reset(10000, 40.0).is_ok());
  NodeMeasurement m[2] = {{500, 20.0f}, {501, 10.0f}};
  std::uint32_t sel[16];
  QNAV_EXPECT_NO_ALLOC({
    for (int k = 0; k < 3; ++k) {
      t.f.predict(40.0).ignore();
      t.f.update(Span<const NodeMeasurement>(m)).ignore();
      static_cast<void>(t.f.select_nodes(Span<std::uint32_t>(sel)));
    }
  });
}

}  // namespace
}  // namespace qnav::route
