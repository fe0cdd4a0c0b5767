// RouteAutopilot: the path-following law an autopilot flies on qnav's CAN guidance (docs/route.md,
// "Closed loop"). Frames are encoded with the qnavcan codec, as qnav sends them.
#include "firmware/pipeline/route_autopilot.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "firmware/pipeline/closed_loop.hpp"

namespace {

using namespace qnav;
using namespace qnav::pipeline;
namespace qc = qnav::drivers::qnavcan;

// A straight taught track due north, a pose every 10 m over 1000 m, a node every 60 m from 30 m.
struct Track {
  std::vector<Pose2> poses;
  std::vector<std::uint32_t> nodes;
  Track() {
    for (int i = 0; i <= 100; ++i) {
      if (i % 6 == 3) nodes.push_back(static_cast<std::uint32_t>(poses.size()));
      poses.push_back(Pose2{10.0 * i, 0.0, 0.0});
    }
  }
  Span<const Pose2> p() const { return Span<const Pose2>(poses.data(), poses.size()); }
  Span<const std::uint32_t> n() const { return Span<const std::uint32_t>(nodes.data(), nodes.size()); }
};

void send(RouteAutopilot& ap, const qc::RouteGuidance& g, const qc::RouteStatus& s, std::int64_t t_ns) {
  hal::CanFrame fg, fs;
  ASSERT_TRUE(qc::encode(g, fg).is_ok());
  ASSERT_TRUE(qc::encode(s, fs).is_ok());
  ASSERT_TRUE(ap.on_frame(fg, t_ns).is_ok());
  ASSERT_TRUE(ap.on_frame(fs, t_ns).is_ok());
}

qc::RouteStatus status(qc::GuidanceState st, std::uint16_t seq) {
  qc::RouteStatus s;
  s.status = st;
  s.side = qc::SideOfRoute::kUnknown;
  s.cross_track_sigma_m = 1.0;
  s.tile_seq = seq;
  return s;
}

TEST(RouteAutopilot, SteersTowardTheTrackWithTheLineOfSightAngle) {
  Track tr;
  RouteAutopilot ap;
  RouteAutopilotConfig c;  // look-ahead 25 m, gain 1, 30 deg limit
  ASSERT_TRUE(ap.reset(c, tr.p(), tr.n(), 0, Pose2{100.0, 10.0, 0.0}).is_ok());
  ap.set_frame(Pose2{});  // dead reckoning is the teach frame (the baseline)
  AutopilotCommand cmd = ap.command();
  EXPECT_EQ(cmd.mode, AutopilotMode::kFollowing);
  EXPECT_NEAR(cmd.cross_track_m, 10.0, 1e-9);                  // east of a northbound track = starboard
  EXPECT_NEAR(cmd.course_rad, -std::atan(10.0 / 25.0), 1e-9);  // turns to port, towards the track
  EXPECT_NEAR(cmd.speed_mps, c.cruise_speed_mps, 1e-12);
  // Far off: the intercept angle is limited.
  ap.on_nav(1000000000, Pose2{100.0, -300.0, 0.0}, 0.0);
  cmd = ap.command();
  EXPECT_NEAR(cmd.course_rad, c.max_intercept_rad, 1e-9);
  // Crab: a current from port gives a DVL sideslip; the heading is the course minus it.
  ap.on_nav(2000000000, Pose2{100.0, 0.0, 0.0}, 0.1);
  cmd = ap.command();
  EXPECT_NEAR(cmd.course_rad, 0.0, 1e-9);
  EXPECT_NEAR(cmd.heading_rad, -0.1, 1e-9);
}

TEST(RouteAutopilot, AnchorsQnavsFixFromCanFramesAndPropagatesOnDeadReckoning) {
  Track tr;
  RouteAutopilot ap;
  RouteAutopilotConfig c;
  // Its own dead-reckoned frame is rotated and shifted from the teach frame.
  ASSERT_TRUE(ap.reset(c, tr.p(), tr.n(), 0, Pose2{500.0, 200.0, 1.0}).is_ok());
  EXPECT_EQ(ap.command().mode, AutopilotMode::kHoldCourse);  // nothing from qnav yet
  EXPECT_NEAR(ap.command().course_rad, 1.0, 1e-12);
  qc::RouteGuidance g;
  g.cross_track_m = 8.0;
  g.heading_error_rad = 0.1;
  g.dist_to_next_m = 30.0;
  g.target_node = 3;
  send(ap, g, status(qc::GuidanceState::kTracking, 1), 1000000000);
  AutopilotCommand cmd = ap.command();
  EXPECT_EQ(cmd.mode, AutopilotMode::kFollowing);
  EXPECT_NEAR(cmd.cross_track_m, 8.0, 0.02);
  // The route runs at heading - heading error = 0.9 rad in its own frame.
  EXPECT_NEAR(cmd.course_rad, 0.9 - std::atan(8.0 / 25.0), 1e-3);
  EXPECT_EQ(ap.counters().get(AutopilotCounter::kSteerFixes), 1u);
  // 50 m along the route and 2 m to port, by its own dead reckoning: cross-track 6 m.
  const double r = 0.9;
  const Vec2d moved =
      Vec2d(500.0, 200.0) + 50.0 * Vec2d(std::cos(r), std::sin(r)) - 2.0 * Vec2d(-std::sin(r), std::cos(r));
  ap.on_nav(30000000000, Pose2{moved.x(), moved.y(), 1.0}, 0.0);
  EXPECT_NEAR(ap.command().cross_track_m, 6.0, 0.02);
  // The same tile repeated at the DBC period does not re-anchor the track.
  send(ap, g, status(qc::GuidanceState::kTracking, 1), 30100000000);
  EXPECT_NEAR(ap.command().cross_track_m, 6.0, 0.02);
  EXPECT_EQ(ap.counters().get(AutopilotCounter::kSteerFixes), 1u);
}

TEST(RouteAutopilot, AnchorsAFixHalfATileOfOwnTravelBackWhateverTheSpeed) {
  // Tiles in metres: the fix describes the vehicle guidance_age_m of its own travel ago, however long
  // that took (a current ahead or astern changes the time, not the distance).
  Track tr;
  RouteAutopilot ap;
  RouteAutopilotConfig c;
  c.guidance_age_m = 45.0;
  c.guidance_age_s = 5.0;  // not used when guidance_age_m is set
  ASSERT_TRUE(ap.reset(c, tr.p(), tr.n(), 0, Pose2{0.0, 0.0, 0.0}).is_ok());
  // Along the track: 1 m per 0.5 s up to 40 m, then 0.25 m per 0.5 s (slowed down) up to 75 m.
  std::int64_t t = 0;
  for (double x = 1.0; x <= 40.0; x += 1.0) ap.on_nav(t += 500000000, Pose2{x, 0.0, 0.0}, 0.0);
  for (double x = 40.25; x <= 75.0; x += 0.25) ap.on_nav(t += 500000000, Pose2{x, 0.0, 0.0}, 0.0);
  // qnav: at node 0 (30 m), on it (DistToNext = the spacing), 2 m to starboard.
  qc::RouteGuidance g;
  g.cross_track_m = 2.0;
  g.dist_to_next_m = 60.0;
  g.target_node = 0;
  send(ap, g, status(qc::GuidanceState::kTracking, 1), t);
  const AutopilotCommand cmd = ap.command();
  EXPECT_EQ(cmd.mode, AutopilotMode::kFollowing);
  EXPECT_NEAR(cmd.along_m, 75.0, 0.5);  // anchored at its pose 45 m back (at 30 m); 5 s back: 32.5 m
  EXPECT_NEAR(cmd.cross_track_m, 2.0, 1e-6);
}

TEST(RouteAutopilot, HoldsCourseOnHoldCourseAndStopsOnRouteEnd) {
  Track tr;
  RouteAutopilot ap;
  ASSERT_TRUE(ap.reset(RouteAutopilotConfig{}, tr.p(), tr.n(), 0, Pose2{100.0, 10.0, 0.0}).is_ok());
  ap.set_frame(Pose2{});
  const double following = ap.command().course_rad;
  qc::RouteGuidance g;
  send(ap, g, status(qc::GuidanceState::kHoldCourse, 7), 1000000000);
  AutopilotCommand cmd = ap.command();
  EXPECT_EQ(cmd.mode, AutopilotMode::kHoldCourse);
  EXPECT_NEAR(cmd.course_rad, following, 1e-12);
  ap.on_nav(2000000000, Pose2{200.0, -40.0, 0.3}, 0.05);  // wherever it drifts, the course is held
  cmd = ap.command();
  EXPECT_NEAR(cmd.course_rad, following, 1e-12);
  EXPECT_NEAR(cmd.heading_rad, following - 0.05, 1e-12);
  EXPECT_GT(cmd.speed_mps, 0.0);
  // RouteEnd with a frame: on along the taught track (the last frame) to its end, not stopped where
  // the status arrives (qnav's last node is half a tile before the track's end).
  send(ap, g, status(qc::GuidanceState::kRouteEnd, 8), 3000000000);
  cmd = ap.command();
  EXPECT_EQ(cmd.mode, AutopilotMode::kFollowing);
  EXPECT_GT(cmd.speed_mps, 0.0);
  EXPECT_NEAR(cmd.cross_track_m, -40.0, 1e-9);
  EXPECT_NEAR(cmd.course_rad, RouteAutopilotConfig{}.max_intercept_rad, 1e-9);  // back towards the track, steepest intercept
  send(ap, g, status(qc::GuidanceState::kHoldCourse, 9), 3500000000);  // a later HoldCourse does not stop it
  std::int64_t t = 4000000000;
  for (double x = 205.0; x <= 995.0; x += 5.0) {  // on along the track (the foot point is searched step by step)
    ap.on_nav(t += 1000000000, Pose2{x, 1.0, 0.0}, 0.0);
    ASSERT_EQ(ap.command().mode, AutopilotMode::kFollowing) << "at " << x << " m, before the track's end (1000 m)";
  }
  ap.on_nav(t += 1000000000, Pose2{1000.5, 0.5, 0.0}, 0.0);  // past it: stopped there
  cmd = ap.command();
  EXPECT_EQ(cmd.mode, AutopilotMode::kStopped);
  EXPECT_EQ(cmd.speed_mps, 0.0);
  // Stopped stays stopped, whatever comes next.
  send(ap, g, status(qc::GuidanceState::kTracking, 10), t + 1000000000);
  EXPECT_EQ(ap.command().mode, AutopilotMode::kStopped);
}

TEST(RouteAutopilot, StopsAtOnceOnRouteEndWithoutAFrame) {
  Track tr;
  RouteAutopilot ap;
  ASSERT_TRUE(ap.reset(RouteAutopilotConfig{}, tr.p(), tr.n(), 0, Pose2{100.0, 10.0, 0.3}).is_ok());
  qc::RouteGuidance g;
  send(ap, g, status(qc::GuidanceState::kRouteEnd, 1), 1000000000);  // no fix, no set_frame: no track to follow
  const AutopilotCommand cmd = ap.command();
  EXPECT_EQ(cmd.mode, AutopilotMode::kStopped);
  EXPECT_EQ(cmd.speed_mps, 0.0);
  EXPECT_NEAR(cmd.heading_rad, 0.3, 1e-12);
}

TEST(RouteAutopilot, WithFollowTrackOnHoldKeepsFollowingTheTrackOnDeadReckoning) {
  Track tr;
  RouteAutopilot ap;
  RouteAutopilotConfig c;
  c.follow_track_on_hold = true;
  ASSERT_TRUE(ap.reset(c, tr.p(), tr.n(), 0, Pose2{100.0, 10.0, 0.0}).is_ok());
  ap.set_frame(Pose2{});
  qc::RouteGuidance g;
  send(ap, g, status(qc::GuidanceState::kHoldCourse, 7), 1000000000);
  ap.on_nav(2000000000, Pose2{200.0, -10.0, 0.0}, 0.0);  // 10 m to port: steer back to starboard
  const AutopilotCommand cmd = ap.command();
  EXPECT_EQ(cmd.mode, AutopilotMode::kFollowing);
  EXPECT_NEAR(cmd.course_rad, std::atan(10.0 / 25.0), 1e-9);
}

TEST(RouteAutopilot, StopsPastTheTaughtTracksEnd) {
  Track tr;
  RouteAutopilot ap;
  ASSERT_TRUE(ap.reset(RouteAutopilotConfig{}, tr.p(), tr.n(), 0, Pose2{990.0, 0.0, 0.0}).is_ok());
  ap.set_frame(Pose2{});
  for (int i = 0; i < 100; ++i) (void)ap.command();  // walks the foot-point search up to the end
  EXPECT_EQ(ap.command().mode, AutopilotMode::kFollowing);
  ap.on_nav(1000000000, Pose2{1001.0, 0.0, 0.0}, 0.0);
  EXPECT_EQ(ap.command().mode, AutopilotMode::kStopped);
}

TEST(RouteAutopilot, FollowsInReverseFromAFix) {
  Track tr;
  RouteAutopilot ap;
  RouteAutopilotConfig c;
  c.reverse = true;
  ASSERT_TRUE(ap.reset(c, tr.p(), tr.n(), 0, Pose2{0.0, 0.0, 0.0}).is_ok());
  // On node 5 (north 330 m), 4 m to starboard of the SOUTHBOUND direction (= west), heading south.
  qc::RouteGuidance g;
  g.cross_track_m = 4.0;
  g.heading_error_rad = 0.0;
  g.dist_to_next_m = 60.0;
  g.target_node = 5;
  send(ap, g, status(qc::GuidanceState::kTracking, 1), 0);
  const AutopilotCommand cmd = ap.command();
  EXPECT_EQ(cmd.mode, AutopilotMode::kFollowing);
  EXPECT_NEAR(cmd.cross_track_m, 4.0, 0.02);
  EXPECT_NEAR(cmd.along_m, 1000.0 - 330.0, 0.1);
  // Its own frame's heading 0 is the route's southbound direction: steer to port of it.
  EXPECT_NEAR(cmd.course_rad, -std::atan(4.0 / 25.0), 1e-3);
}

TEST(RouteAutopilot, RefusesBadFramesAndBadTracksByName) {
  Track tr;
  RouteAutopilot ap;
  EXPECT_EQ(ap.reset(RouteAutopilotConfig{}, Span<const Pose2>(tr.poses.data(), 1), tr.n(), 0, Pose2{}).code(),
            StatusCode::kInvalidArgument);
  std::vector<std::uint32_t> bad = {5, 3};
  EXPECT_EQ(
      ap.reset(RouteAutopilotConfig{}, tr.p(), Span<const std::uint32_t>(bad.data(), bad.size()), 0, Pose2{}).code(),
      StatusCode::kInvalidArgument);
  ASSERT_TRUE(ap.reset(RouteAutopilotConfig{}, tr.p(), tr.n(), 0, Pose2{}).is_ok());
  hal::CanFrame f;
  ASSERT_TRUE(qc::encode(status(qc::GuidanceState::kTracking, 1), f).is_ok());
  EXPECT_TRUE(ap.on_frame(f, 0).is_ok());  // a status without its guidance: counted, not steered on
  EXPECT_EQ(ap.counters().get(AutopilotCounter::kUnpairedStatus), 1u);
  f.len = 2;  // truncated
  EXPECT_FALSE(ap.on_frame(f, 0).is_ok());
  EXPECT_EQ(ap.counters().get(AutopilotCounter::kDecodeErrors), 1u);
  qc::RouteGuidance g;
  g.target_node = 60000;  // no such node: ignored
  send(ap, g, status(qc::GuidanceState::kTracking, 2), 0);
  EXPECT_EQ(ap.command().mode, AutopilotMode::kHoldCourse);
  EXPECT_EQ(ap.counters().get(AutopilotCounter::kSteerFixes), 0u);
  hal::CanFrame other;
  other.id = 0x123;
  EXPECT_TRUE(ap.on_frame(other, 0).is_ok());  // not ours
}

TEST(ClosedLoop, PolylineOffsetsAreSignedRightOfTravelAndExtendPastTheEnds) {
  const std::vector<Vec2d> poly = {Vec2d(0, 0), Vec2d(100, 0), Vec2d(100, 100)};
  double a, e, h;
  polyline_offsets(poly, Vec2d(50, 5), a, e, h);
  EXPECT_NEAR(a, 50.0, 1e-9);
  EXPECT_NEAR(e, 5.0, 1e-9);  // east of a northbound leg: right
  polyline_offsets(poly, Vec2d(110, 150), a, e, h);
  EXPECT_NEAR(a, 250.0, 1e-9);  // past the end, on the last leg's extension
  EXPECT_NEAR(e, -10.0, 1e-9);
  EXPECT_NEAR(h, kPi / 2, 1e-9);
}

// qnavd's sim vehicle (and any autopilot that logs the teach): the node poses go into the log where
// the log passed their along-track distance, and node_at points at them.
TEST(ClosedLoop, TaughtTrackFromLogInsertsEachNodeWhereTheLogPassedIt) {
  const std::vector<Pose2> log = {Pose2{0, 0, 0}, Pose2{10, 0, 0}, Pose2{20, 0, 0}, Pose2{30, 0, 0}};
  const std::vector<double> dist = {0.0, 10.0, 20.0, 30.0};
  std::vector<route::NodeMeta> nodes(3);
  nodes[0].pose = Pose2{5, 0.5, 0};
  nodes[0].along_m = 5.0;
  nodes[1].pose = Pose2{15, 0.5, 0};
  nodes[1].along_m = 15.0;
  nodes[2].pose = Pose2{35, 0.5, 0};  // past the log's end: appended
  nodes[2].along_m = 35.0;
  std::vector<Pose2> track;
  std::vector<std::uint32_t> node_at;
  taught_track_from_log(log, dist, nodes, track, node_at);
  ASSERT_EQ(track.size(), 7u);
  ASSERT_EQ(node_at.size(), 3u);
  EXPECT_EQ(node_at[0], 1u);
  EXPECT_EQ(node_at[1], 3u);
  EXPECT_EQ(node_at[2], 6u);
  for (std::size_t j = 0; j < 3; ++j) EXPECT_DOUBLE_EQ(track[node_at[j]].x_m, nodes[j].pose.x_m);
  EXPECT_DOUBLE_EQ(track[2].x_m, 10.0);
  // The result is a track the autopilot takes.
  RouteAutopilot ap;
  EXPECT_TRUE(ap.reset(RouteAutopilotConfig{}, Span<const Pose2>(track.data(), track.size()),
                       Span<const std::uint32_t>(node_at.data(), node_at.size()), 0, Pose2{})
                  .is_ok());
}

}  // namespace
