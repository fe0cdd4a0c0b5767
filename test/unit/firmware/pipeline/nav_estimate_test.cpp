// NavEstimate: dead-reckoned motion moves the estimate, a fix jumps it with reset_counter.
#include "firmware/pipeline/nav_estimate.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace qnav::pipeline {
namespace {

TEST(NavEstimate, TracksDeadReckoningFromItsFirstPose) {
  NavEstimate e;
  e.track(Pose2{100.0, 50.0, 0.0});  // baseline only
  EXPECT_DOUBLE_EQ(e.north_m(), 0.0);
  e.track(Pose2{103.0, 54.0, 0.0});
  EXPECT_DOUBLE_EQ(e.north_m(), 3.0);
  EXPECT_DOUBLE_EQ(e.east_m(), 4.0);
  e.rebase();                        // the dead reckoner restarted at its origin
  e.track(Pose2{0.0, 0.0, 0.0});
  e.track(Pose2{1.0, 0.0, 0.0});
  EXPECT_DOUBLE_EQ(e.north_m(), 4.0);
  EXPECT_EQ(e.reset_counter(), 0);
}

TEST(NavEstimate, AFixThatMovesThePositionChangesResetCounter) {
  NavEstimate e(0.05);
  e.add_increment(10.0, 0.0, 0.0);
  EXPECT_FALSE(e.apply_fix(10.01, 0.0));  // within the threshold: no jump
  EXPECT_EQ(e.reset_counter(), 0);
  EXPECT_TRUE(e.apply_fix(12.0, -1.0));
  EXPECT_EQ(e.reset_counter(), 1);
  EXPECT_DOUBLE_EQ(e.north_m(), 12.0);
  EXPECT_DOUBLE_EQ(e.east_m(), -1.0);
  EXPECT_FALSE(e.apply_fix(std::numeric_limits<double>::quiet_NaN(), 0.0));
  EXPECT_EQ(e.rejected_fixes(), 1u);
  EXPECT_EQ(e.fixes(), 2u);
}

TEST(NavEstimate, RouteFixIsTheNodePlusAlongAndCrossTrackOffsets) {
  route::NodeMeta node;
  node.pose = Pose2{100.0, 200.0, 0.5 * 3.14159265358979323846};  // taught heading east
  Vec2d p = NavEstimate::route_fix_position(node, false, 2.0, 3.0);  // 2 m further east, 3 m to starboard (south)
  EXPECT_NEAR(p.x(), 97.0, 1e-9);
  EXPECT_NEAR(p.y(), 202.0, 1e-9);
  p = NavEstimate::route_fix_position(node, true, 2.0, 3.0);  // travelling west: ahead = west, starboard = north
  EXPECT_NEAR(p.x(), 103.0, 1e-9);
  EXPECT_NEAR(p.y(), 198.0, 1e-9);
}

}  // namespace
}  // namespace qnav::pipeline
