#include "nav/route/route_localiser.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <memory>
#include <utility>
#include <vector>

#include "synthetic_route.hpp"
#include "test/support/alloc_guard.hpp"

namespace qnav::route {
namespace {

class MemorySource final : public NodeSource {
 public:
  std::vector<RouteNode> nodes;
  std::uint32_t corrupt = 0xFFFFFFFFu;  // this index fails to load
  std::uint32_t node_count() const noexcept override { return static_cast<std::uint32_t>(nodes.size()); }
  Status load(std::uint32_t i, RouteNode& out) noexcept override {
    if (i >= nodes.size()) return Status(StatusCode::kOutOfRange, "no such node");
    if (i == corrupt) return Status(StatusCode::kCorrupt, "route record CRC mismatch");
    out = nodes[i];
    return Status::ok();
  }
};

constexpr double kSpacing = 50.0;
constexpr double kHalfLen = 25.0;
constexpr double kHalfWidth = 50.0;

struct Scenario {
  testing::SyntheticWorld world{2200.0, 260.0, 0.012, 42};
  MemorySource source;
  std::vector<NodeMeta> meta;
  RouteParams params;
  Scenario() {
    params.sensor = SensorKind::kSideScan;
    params.node_spacing_m = static_cast<float>(kSpacing);
    params.tile_length_m = 50.0f;
    params.tile_width_m = 100.0f;
    params.pixel_m = 0.2f;
    for (std::uint32_t i = 0; i < 40; ++i) {
      RouteNode n = world.observe(Pose2{50.0 + kSpacing * i, 0.0, 0.0}, kHalfLen, kHalfWidth, 0.2, 0.85, 64, 1000 + i, 8);
      n.meta.index = i;
      n.meta.along_m = kSpacing * i;
      source.nodes.push_back(n);
      meta.push_back(n.meta);
    }
  }
};

LocaliserConfig config(RouteDirection d) {
  LocaliserConfig c;
  c.filter.max_nodes = 64;
  c.filter.direction = d;
  c.registration.robust.inlier_threshold_m = 1.0;
  return c;
}

struct RunStats {
  int within1 = 0, tiles = 0, side_ok = 0, side_n = 0;
};

RunStats repeat(Scenario& s, RouteDirection d, double lateral_m, int first_node, int tiles) {
  LocaliserConfig c = config(d);
  ArenaStorage arena(RouteLocaliser::arena_bytes(c));
  auto loc = std::make_unique<RouteLocaliser>();
  EXPECT_TRUE(loc->init(c, arena).is_ok());
  EXPECT_TRUE(loc->start(s.params, Span<const NodeMeta>(s.meta.data(), s.meta.size()), s.source).is_ok());
  RunStats r;
  const int dir = d == RouteDirection::kForward ? 1 : -1;
  const double heading = d == RouteDirection::kForward ? 0.0 : kPi;
  for (int k = 0; k < tiles; ++k) {
    // Tile centres fall between nodes (offset 0.3 spacing), as in the paper's Fig. 4.
    const double along = kSpacing * (first_node + dir * k) + 0.3 * kSpacing * dir;
    RouteNode sensed = s.world.observe(Pose2{50.0 + along, lateral_m, heading}, kHalfLen, kHalfWidth, 0.2, 0.85, 64, 5000 + static_cast<std::uint64_t>(k), 8);
    LocaliserStep st;
    EXPECT_TRUE(loc->step(sensed, k == 0 ? 0.0 : kSpacing, st).is_ok());
    const double truth = along / kSpacing;
    if (k >= 3) {
      ++r.tiles;
      r.within1 += std::abs(static_cast<double>(st.estimate) - truth) <= 1.0;
      if (st.guidance.status == GuidanceStatus::kTracking && std::abs(lateral_m) > 5.0) {
        ++r.side_n;
        // Vehicle to the east of a north-going route is to starboard; reversed for a south-going pass.
        const RouteSide want = (lateral_m > 0) == (d == RouteDirection::kForward) ? RouteSide::kStarboard : RouteSide::kPort;
        r.side_ok += st.guidance.side == want;
        EXPECT_NEAR(std::abs(st.guidance.cross_track_m), std::abs(lateral_m), 1.5);
      }
    }
  }
  return r;
}

TEST(RouteLocaliser, ForwardRepeatAtLateralOffsetTracksNodeAndSide) {
  Scenario s;
  RunStats r = repeat(s, RouteDirection::kForward, 20.0, 5, 14);
  EXPECT_GE(r.within1, r.tiles - 1) << r.within1 << "/" << r.tiles;
  EXPECT_GE(r.side_n, r.tiles - 2);
  EXPECT_EQ(r.side_ok, r.side_n);
}

TEST(RouteLocaliser, ReverseRepeatForEmergencyReturn) {
  Scenario s;
  RunStats r = repeat(s, RouteDirection::kReverse, -15.0, 34, 14);
  EXPECT_GE(r.within1, r.tiles - 1) << r.within1 << "/" << r.tiles;
  EXPECT_EQ(r.side_ok, r.side_n);
  EXPECT_GE(r.side_n, r.tiles - 2);
}

TEST(RouteLocaliser, SensorMismatchOneNodeRouteAndDamagedRecordAreClearErrors) {
  Scenario s;
  LocaliserConfig c = config(RouteDirection::kForward);
  ArenaStorage arena(RouteLocaliser::arena_bytes(c));
  auto loc = std::make_unique<RouteLocaliser>();
  ASSERT_TRUE(loc->init(c, arena).is_ok());
  RouteParams cam = s.params;
  cam.sensor = SensorKind::kCamera;
  EXPECT_EQ(loc->start(cam, Span<const NodeMeta>(s.meta.data(), s.meta.size()), s.source), StatusCode::kInvalidArgument);
  EXPECT_EQ(loc->counters().get(LocaliserCounter::kSensorMismatch), 1u);
  MemorySource one;
  one.nodes.push_back(s.source.nodes[0]);
  EXPECT_EQ(loc->start(s.params, Span<const NodeMeta>(s.meta.data(), 1), one), StatusCode::kInvalidArgument);
  std::vector<NodeMeta> shuffled = s.meta;
  std::swap(shuffled[3], shuffled[4]);
  EXPECT_EQ(loc->start(s.params, Span<const NodeMeta>(shuffled.data(), shuffled.size()), s.source), StatusCode::kInvalidArgument);
  shuffled = s.meta;
  shuffled[7].pose.x_m = std::nan("");
  EXPECT_EQ(loc->start(s.params, Span<const NodeMeta>(shuffled.data(), shuffled.size()), s.source), StatusCode::kInvalidArgument);
  LocaliserStep st;
  EXPECT_EQ(loc->step(s.source.nodes[0], 0.0, st), StatusCode::kNotReady);
  // A damaged record is reported per step and treated as "no similarity"; the run goes on.
  s.source.corrupt = 10;
  ASSERT_TRUE(loc->start(s.params, Span<const NodeMeta>(s.meta.data(), s.meta.size()), s.source).is_ok());
  int errors = 0;
  for (int k = 0; k < 9; ++k) {
    RouteNode sensed = s.world.observe(Pose2{50.0 + kSpacing * (4 + k), 5.0, 0.0}, kHalfLen, kHalfWidth, 0.2, 0.85, 64, 77 + static_cast<std::uint64_t>(k), 8);
    ASSERT_TRUE(loc->step(sensed, k == 0 ? 0.0 : kSpacing, st).is_ok());
    errors += static_cast<int>(st.load_errors);
    EXPECT_TRUE(std::isfinite(st.entropy));
  }
  EXPECT_GT(errors, 0);
  EXPECT_EQ(loc->counters().get(LocaliserCounter::kLoadError), static_cast<std::uint32_t>(errors));
  EXPECT_NEAR(static_cast<double>(st.estimate), 12.0, 1.0);
  // An empty sensed tile: counted, no registration, hold course.
  RouteNode empty;
  empty.meta.pose = Pose2{0, 0, 0.0};
  ASSERT_TRUE(loc->step(empty, kSpacing, st).is_ok());
  EXPECT_EQ(st.guidance.status, GuidanceStatus::kHoldCourse);
  EXPECT_EQ(loc->counters().get(LocaliserCounter::kEmptySensedTile), 1u);
  // A tile with keypoints but a non-finite compass heading: not registered (counted), the step still
  // succeeds on the distance travelled, guidance holds course with a finite command.
  RouteNode bad = s.world.observe(Pose2{50.0 + kSpacing * 13, 5.0, 0.0}, kHalfLen, kHalfWidth, 0.2, 0.85, 64, 91, 8);
  ASSERT_FALSE(bad.keypoints.empty());
  bad.meta.pose.heading_rad = std::nan("");
  ASSERT_TRUE(loc->step(bad, kSpacing, st).is_ok());
  EXPECT_FALSE(st.registration.ok);
  EXPECT_EQ(st.guidance.status, GuidanceStatus::kHoldCourse);
  EXPECT_TRUE(std::isfinite(st.guidance.commanded_heading_rad));
  EXPECT_EQ(loc->counters().get(LocaliserCounter::kBadSensedTile), 1u);
}

// A successful registration: the sensed tile at `sensed_to_node` in the node's frame, with the given
// cross-track (y) variance.
RegistrationResult registration(std::uint32_t inliers, const Pose2& sensed_to_node, double cross_track_var = 0.0) {
  RegistrationResult r;
  r.ok = true;
  r.inliers = inliers;
  r.sensed_to_node = sensed_to_node;
  r.covariance(1, 1) = cross_track_var;
  return r;
}

// A route node due north of the origin (the route runs north).
NodeMeta node_at(double north_m, std::uint32_t index) {
  NodeMeta m;
  m.pose = Pose2{north_m, 0.0, 0.0};
  m.index = index;
  return m;
}

TEST(Guidance, HoldsCourseOnARegistrationWithTooFewInliers) {
  GuidanceConfig gc;
  gc.min_inliers = 7;
  Guidance g(gc);
  const NodeMeta node = node_at(0.0, 0), ahead = node_at(100.0, 2);
  RegistrationResult r = registration(6, Pose2{2.0, 12.0, 0.01}, 0.09);  // cross-track sigma 0.3 m
  GuidanceOutput out = g.compute(true, RouteDirection::kForward, node, ahead, r, 0.0);
  EXPECT_EQ(out.status, GuidanceStatus::kHoldCourse);
  EXPECT_EQ(out.side, RouteSide::kUnknown);  // holding course says nothing about the side
  EXPECT_EQ(out.offsets, OffsetSource::kNone);
  EXPECT_NEAR(out.commanded_heading_rad, 0.0, 1e-12);
  r.inliers = 7;
  out = g.compute(true, RouteDirection::kForward, node, ahead, r, 0.0);
  EXPECT_EQ(out.status, GuidanceStatus::kTracking);
  EXPECT_EQ(out.side, RouteSide::kStarboard);
  EXPECT_NEAR(out.cross_track_m, 12.0, 1e-9);
  EXPECT_NEAR(out.cross_track_sigma_m, 0.3, 1e-9);
  const double steered = out.commanded_heading_rad;
  EXPECT_LT(steered, -0.05);  // back to port, towards the look-ahead waypoint
  // Not confident: hold course whatever the registration, with the last command (the unconfident
  // side is off by default).
  out = g.compute(false, RouteDirection::kForward, node, ahead, r, 0.3);
  EXPECT_EQ(out.status, GuidanceStatus::kHoldCourse);
  EXPECT_EQ(out.side, RouteSide::kUnknown);
  EXPECT_NEAR(out.commanded_heading_rad, steered, 1e-12);
}

TEST(Guidance, AStrongRegistrationGivesTheSideBeforeTheFilterIsConfident) {
  GuidanceConfig gc;
  gc.min_inliers = 7;
  gc.unconfident_min_inliers = 9;
  gc.side_deadband_m = 1.0;
  Guidance g(gc);
  const NodeMeta node = node_at(0.0, 0), ahead = node_at(100.0, 2);
  RegistrationResult r = registration(8, Pose2{-3.0, -9.0, 0.02}, 0.04);  // 9 m to port
  GuidanceOutput out = g.compute(false, RouteDirection::kForward, node, ahead, r, 0.4);
  EXPECT_EQ(out.status, GuidanceStatus::kHoldCourse);
  EXPECT_EQ(out.side, RouteSide::kUnknown);
  r.inliers = 9;
  out = g.compute(false, RouteDirection::kForward, node, ahead, r, 0.4);
  EXPECT_EQ(out.status, GuidanceStatus::kHoldCourse);  // not steered on: the node may still be wrong
  EXPECT_EQ(out.side, RouteSide::kPort);
  EXPECT_EQ(out.offsets, OffsetSource::kRegistration);
  EXPECT_NEAR(out.cross_track_m, -9.0, 1e-9);
  EXPECT_NEAR(out.cross_track_sigma_m, 0.2, 1e-9);
  EXPECT_NEAR(out.commanded_heading_rad, 0.4, 1e-12);  // the current heading: no command yet
  // In reverse the same offset is to starboard of the direction of travel.
  Guidance rev(gc);
  out = rev.compute(false, RouteDirection::kReverse, ahead, node, r, 0.4);
  EXPECT_EQ(out.side, RouteSide::kStarboard);
  // A non-finite or garbage registration gives no side.
  r.sensed_to_node.y_m = std::nan("");
  EXPECT_EQ(g.compute(false, RouteDirection::kForward, node, ahead, r, 0.4).side, RouteSide::kUnknown);
}

TEST(Guidance, ADeadReckonedSideIsReportedOnlyWhileItIsSignificant) {
  GuidanceConfig gc;
  gc.min_inliers = 7;
  gc.dead_reckon_max_m = 50.0;
  gc.dead_reckon_side_max_m = 500.0;
  gc.dead_reckon_heading_sigma_rad = 0.01;
  gc.side_deadband_m = 1.0;
  gc.side_n_sigma = 2.0;
  Guidance g(gc);
  const NodeMeta node = node_at(0.0, 0), ahead = node_at(500.0, 5);
  // 2 m to starboard, 1 m clear of the dead band; sigma 0.1 m.
  RegistrationResult fix = registration(12, Pose2{0.0, 2.0, 0.0}, 0.01);
  GuidanceOutput out = g.compute(true, RouteDirection::kForward, node, ahead, fix, 0.0, Pose2{0.0, 0.0, 0.0});
  EXPECT_EQ(out.side, RouteSide::kStarboard);
  RegistrationResult none;
  // 20 m on: sigma 0.1 + 0.2 m, 2 sigma = 0.6 m < 1 m clear: still starboard.
  out = g.compute(true, RouteDirection::kForward, node, ahead, none, 0.0, Pose2{20.0, 0.0, 0.0});
  EXPECT_EQ(out.status, GuidanceStatus::kDeadReckoned);
  EXPECT_NEAR(out.cross_track_sigma_m, 0.3, 1e-9);
  EXPECT_EQ(out.side, RouteSide::kStarboard);
  const double steered = out.commanded_heading_rad;
  // 80 m on: too far to steer on (hold course with the last command); sigma 0.9 m, 2 sigma = 1.8 m
  // > 1 m clear: the side is no longer known either.
  out = g.compute(true, RouteDirection::kForward, node, ahead, none, 0.0, Pose2{80.0, 0.0, 0.0});
  EXPECT_EQ(out.status, GuidanceStatus::kHoldCourse);
  EXPECT_NEAR(out.commanded_heading_rad, steered, 1e-12);
  EXPECT_NEAR(out.cross_track_sigma_m, 0.9, 1e-9);
  EXPECT_EQ(out.side, RouteSide::kUnknown);
  // A large offset stays known for longer: 10 m to starboard, 200 m on, sigma 2.1 m, 10 > 1 + 4.2.
  fix.sensed_to_node = Pose2{0.0, 10.0, 0.0};
  ASSERT_EQ(g.compute(true, RouteDirection::kForward, node, ahead, fix, 0.0, Pose2{0.0, 0.0, 0.0}).side, RouteSide::kStarboard);
  out = g.compute(true, RouteDirection::kForward, node, ahead, none, 0.0, Pose2{200.0, 0.0, 0.0});
  EXPECT_EQ(out.status, GuidanceStatus::kHoldCourse);
  EXPECT_NEAR(out.cross_track_sigma_m, 2.1, 1e-9);
  EXPECT_NEAR(out.cross_track_m, 10.0, 1e-9);
  EXPECT_EQ(out.offsets, OffsetSource::kDeadReckoning);
  EXPECT_EQ(out.side, RouteSide::kStarboard);
  // Beyond dead_reckon_side_max_m: nothing is known.
  out = g.compute(true, RouteDirection::kForward, node, ahead, none, 0.0, Pose2{501.0, 0.0, 0.0});
  EXPECT_EQ(out.status, GuidanceStatus::kHoldCourse);
  EXPECT_EQ(out.side, RouteSide::kUnknown);
  EXPECT_EQ(out.cross_track_sigma_m, 0.0);
  // Not confident: the node may be wrong, so no dead-reckoned side.
  EXPECT_EQ(g.compute(false, RouteDirection::kForward, node, ahead, none, 0.0, Pose2{100.0, 0.0, 0.0}).side, RouteSide::kUnknown);
  // On the route: on_route only when the whole 2-sigma interval lies inside the dead band.
  fix.sensed_to_node = Pose2{0.0, 0.2, 0.0};
  out = g.compute(true, RouteDirection::kForward, node, ahead, fix, 0.0, Pose2{100.0, 0.0, 0.0});
  EXPECT_EQ(out.side, RouteSide::kOnRoute);
  fix.covariance(1, 1) = 0.25;  // sigma 0.5 m: 0.2 + 1.0 > 1.0
  out = g.compute(true, RouteDirection::kForward, node, ahead, fix, 0.0, Pose2{100.0, 0.0, 0.0});
  EXPECT_EQ(out.side, RouteSide::kUnknown);
  fix.covariance(1, 1) = std::nan("");  // a broken covariance never decides a side
  out = g.compute(true, RouteDirection::kForward, node, ahead, fix, 0.0, Pose2{100.0, 0.0, 0.0});
  EXPECT_EQ(out.status, GuidanceStatus::kTracking);
  EXPECT_EQ(out.side, RouteSide::kUnknown);
}

TEST(Guidance, DeadReckonsFromTheLastFixForABoundedDistance) {
  GuidanceConfig gc;
  gc.min_inliers = 7;
  gc.dead_reckon_max_m = 100.0;
  Guidance g(gc);
  const NodeMeta node = node_at(0.0, 0), next = node_at(60.0, 1), ahead = node_at(180.0, 3);
  const RegistrationResult fix = registration(12, Pose2{5.0, 20.0, 0.0});  // 20 m to starboard (east)
  // The pass's dead-reckoned frame differs from the route frame by a shift and a rotation.
  const Pose2 nav0{1000.0, -300.0, 0.5};
  ASSERT_EQ(g.compute(true, RouteDirection::kForward, node, ahead, fix, 0.5, nav0).status, GuidanceStatus::kTracking);
  // 60 m further along the vehicle's own heading, 2 m drift to port, no registration.
  const Pose2 nav1 = nav0.compose(Pose2{60.0, -2.0, 0.0});
  RegistrationResult none;
  GuidanceOutput out = g.compute(true, RouteDirection::kForward, next, ahead, none, 0.5, nav1);
  EXPECT_EQ(out.status, GuidanceStatus::kDeadReckoned);
  EXPECT_EQ(out.side, RouteSide::kStarboard);
  EXPECT_NEAR(out.cross_track_m, 18.0, 1e-6);
  EXPECT_NEAR(out.along_track_m, 5.0, 1e-6);
  EXPECT_NEAR(out.cross_track_sigma_m, gc.dead_reckon_heading_sigma_rad * std::hypot(60.0, 2.0), 1e-9);  // the fix's sigma is 0 here
  // Beyond dead_reckon_max_m from the fix: hold course.
  const Pose2 nav2 = nav0.compose(Pose2{120.0, 0.0, 0.0});
  EXPECT_EQ(g.compute(true, RouteDirection::kForward, next, ahead, none, 0.5, nav2).status, GuidanceStatus::kHoldCourse);
  // Past the last node (the look-ahead node is the node itself): route end, no turn back.
  GuidanceOutput end = g.compute(true, RouteDirection::kForward, next, next, fix, 0.5, nav1);
  EXPECT_EQ(end.status, GuidanceStatus::kRouteEnd);
  EXPECT_EQ(end.side, RouteSide::kStarboard);
  EXPECT_NEAR(end.commanded_heading_rad, 0.5, 1e-12);
  // A reset forgets the fix.
  g.reset();
  EXPECT_EQ(g.compute(true, RouteDirection::kForward, next, ahead, none, 0.5, nav1).status, GuidanceStatus::kHoldCourse);
}

// The simulator's guidance settings with the registration check on (10 m + 3 sigma).
GuidanceConfig verifying_guidance() {
  GuidanceConfig gc;
  gc.min_inliers = 7;
  gc.dead_reckon_max_m = 150.0;
  gc.dead_reckon_side_max_m = 450.0;
  gc.dead_reckon_heading_sigma_rad = 0.025;
  gc.side_deadband_m = 1.0;
  gc.verify_gate_m = 10.0;
  gc.verify_n_sigma = 3.0;
  return gc;
}

// Issue 27 (2 pings/s, reverse at 20 % of the swath): a 7-inlier registration put the vehicle 55 m to
// starboard one tile after a fix 20 m to port; that and the two tiles dead-reckoned from it gave three
// wrong sides. The verification holds such a jump back until a second registration confirms it.
TEST(Guidance, ARegistrationThatJumpsAwayFromDeadReckoningNeedsConfirming) {
  GuidanceConfig gc = verifying_guidance();
  Guidance g(gc);
  const NodeMeta n0 = node_at(0.0, 0), n1 = node_at(60.0, 1), n2 = node_at(120.0, 2), ahead = node_at(240.0, 4);
  GuidanceOutput out = g.compute(true, RouteDirection::kForward, n0, ahead, registration(9, Pose2{0.0, -20.0, 0.0}, 0.04), 0.0, Pose2{0.0, 0.0, 0.0});
  ASSERT_EQ(out.side, RouteSide::kPort);
  EXPECT_FALSE(out.registration_rejected);
  // 60 m on, a 7-inlier registration 55 m to starboard: 75 m from dead reckoning, gate 10 m + 3 x
  // sqrt(0.2^2 + (0.2 + 0.025 x 60)^2) = 15.1 m. Not a fix: dead-reckoned from the last one, still port.
  out = g.compute(true, RouteDirection::kForward, n1, ahead, registration(7, Pose2{0.0, 55.0, 0.0}, 0.04), 0.0, Pose2{60.0, 0.0, 0.0});
  EXPECT_TRUE(out.registration_rejected);
  EXPECT_EQ(out.status, GuidanceStatus::kDeadReckoned);
  EXPECT_EQ(out.offsets, OffsetSource::kDeadReckoning);
  EXPECT_NEAR(out.cross_track_m, -20.0, 1e-9);
  EXPECT_EQ(out.side, RouteSide::kPort);
  // The next registration agrees with dead reckoning (1.5 m off it, inside the gate): a fix again.
  out = g.compute(true, RouteDirection::kForward, n2, ahead, registration(8, Pose2{0.0, -18.5, 0.0}, 0.04), 0.0, Pose2{120.0, 0.0, 0.0});
  EXPECT_FALSE(out.registration_rejected);
  EXPECT_EQ(out.status, GuidanceStatus::kTracking);
  EXPECT_NEAR(out.cross_track_m, -18.5, 1e-9);
  // Without the verification the jump is taken as it comes.
  gc.verify_gate_m = 0.0;
  Guidance off(gc);
  ASSERT_EQ(off.compute(true, RouteDirection::kForward, n0, ahead, registration(9, Pose2{0.0, -20.0, 0.0}, 0.04), 0.0, Pose2{0.0, 0.0, 0.0}).side,
            RouteSide::kPort);
  out = off.compute(true, RouteDirection::kForward, n1, ahead, registration(7, Pose2{0.0, 55.0, 0.0}, 0.04), 0.0, Pose2{60.0, 0.0, 0.0});
  EXPECT_EQ(out.status, GuidanceStatus::kTracking);
  EXPECT_EQ(out.side, RouteSide::kStarboard);
}

TEST(Guidance, TwoRegistrationsThatAgreeOverruleAWrongFix) {
  Guidance g(verifying_guidance());
  const NodeMeta n0 = node_at(0.0, 0), n1 = node_at(60.0, 1), n2 = node_at(120.0, 2), n3 = node_at(180.0, 3), ahead = node_at(300.0, 5);
  // The first fix is the wrong one (nothing to check it against): 55 m to starboard.
  ASSERT_EQ(g.compute(true, RouteDirection::kForward, n0, ahead, registration(8, Pose2{0.0, 55.0, 0.0}, 0.04), 0.0, Pose2{0.0, 0.0, 0.0}).side,
            RouteSide::kStarboard);
  // The truth, 20 m to port: rejected once (it disagrees with the wrong fix) ...
  GuidanceOutput out = g.compute(true, RouteDirection::kForward, n1, ahead, registration(9, Pose2{0.0, -20.0, 0.0}, 0.04), 0.0, Pose2{60.0, 0.0, 0.0});
  EXPECT_TRUE(out.registration_rejected);
  // ... a tile without registration (dead-reckoned from the wrong fix) ...
  out = g.compute(true, RouteDirection::kForward, n2, ahead, RegistrationResult{}, 0.0, Pose2{120.0, 0.0, 0.0});
  EXPECT_EQ(out.status, GuidanceStatus::kDeadReckoned);
  // ... and accepted when the next registration agrees with it (carried 120 m by dead reckoning).
  out = g.compute(true, RouteDirection::kForward, n3, ahead, registration(7, Pose2{0.0, -21.0, 0.0}, 0.04), 0.0, Pose2{180.0, 0.0, 0.0});
  EXPECT_FALSE(out.registration_rejected);
  EXPECT_EQ(out.status, GuidanceStatus::kTracking);
  EXPECT_EQ(out.side, RouteSide::kPort);
  // A fix older than dead_reckon_side_max_m is not checked against: the registration stands.
  out = g.compute(true, RouteDirection::kForward, n3, ahead, registration(7, Pose2{0.0, 40.0, 0.0}, 0.04), 0.0, Pose2{700.0, 0.0, 0.0});
  EXPECT_FALSE(out.registration_rejected);
  EXPECT_EQ(out.side, RouteSide::kStarboard);
}

TEST(RouteLocaliser, StepDoesNotAllocateAfterInit) {
  Scenario s;
  LocaliserConfig c = config(RouteDirection::kForward);
  ArenaStorage arena(RouteLocaliser::arena_bytes(c));
  auto loc = std::make_unique<RouteLocaliser>();
  ASSERT_TRUE(loc->init(c, arena).is_ok());
  ASSERT_TRUE(loc->start(s.params, Span<const NodeMeta>(s.meta.data(), s.meta.size()), s.source).is_ok());
  std::vector<RouteNode> tiles;
  for (int k = 0; k < 4; ++k)
    tiles.push_back(s.world.observe(Pose2{50.0 + kSpacing * (10 + k), 10.0, 0.0}, kHalfLen, kHalfWidth, 0.2, 0.85, 64, 300 + static_cast<std::uint64_t>(k), 8));
  LocaliserStep st;
  QNAV_EXPECT_NO_ALLOC({
    for (const RouteNode& t : tiles) loc->step(t, kSpacing, st).ignore();
  });
  EXPECT_GT(st.best_inliers, 10u);
}

}  // namespace
}  // namespace qnav::route
