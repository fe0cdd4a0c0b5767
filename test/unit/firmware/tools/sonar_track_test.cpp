// build_track (firmware/tools/sonar_file.hpp): the local track of a side-scan file's pings from its
// position fixes. Regression for issue #19: one damaged fix (a flipped bit: 70,710 km away) made
// node spacing absurd; such fixes are rejected and counted, and a run of consistent fixes that
// contradicts a lone first fix re-anchors the track.
#include "firmware/tools/sonar_file.hpp"

#include <gtest/gtest.h>

namespace qnav::tools {
namespace {

// A straight survey line north at 2 m/s, one ping per second, projected metres (nav_units 0).
FileData line(std::size_t n) {
  FileData fd;
  fd.header.nav_units = 0;
  fd.pings.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    XtfPing& p = fd.pings[i].ping;
    p.sensor_y = 5000000.0 + 2.0 * static_cast<double>(i);
    p.sensor_x = 400000.0;
    p.heading_deg = 0.0f;
    p.stamp_ns = 1700000000000000000ull + i * 1000000000ull;
    p.nav_valid = true;
  }
  return fd;
}

TEST(SonarTrack, ADamagedFixIsRejectedAndCounted) {
  FileData fd = line(50);
  fd.pings[20].ping.sensor_y += 7.071e7;  // 70,710 km
  const NavTrack t = build_track(fd, false, 0.0);
  EXPECT_EQ(t.nav_outliers, 1u);
  EXPECT_EQ(t.nav_reanchors, 0u);
  for (std::size_t i = 0; i < 50; ++i) {
    ASSERT_TRUE(t.ok[i]) << i;
    EXPECT_NEAR(t.pose[i].x_m, 2.0 * static_cast<double>(i), 1e-6) << i;  // north, interpolated over ping 20
    EXPECT_NEAR(t.pose[i].y_m, 0.0, 1e-6) << i;
  }
}

TEST(SonarTrack, ALoneWrongFirstFixIsDroppedByTheFixesThatFollow) {
  FileData fd = line(30);
  fd.pings[0].ping.sensor_x += 5.0e6;
  const NavTrack t = build_track(fd, false, 0.0);
  EXPECT_EQ(t.nav_reanchors, 1u);
  EXPECT_EQ(t.nav_outliers, 0u);
  // Every later ping 2 m after the one before: the track is the survey line, not a 5,000 km jump.
  for (std::size_t i = 2; i < 30; ++i) EXPECT_NEAR(t.pose[i].x_m - t.pose[i - 1].x_m, 2.0, 1e-6) << i;
}

TEST(SonarTrack, AFastButRealTrackIsKept) {
  FileData fd = line(30);
  for (std::size_t i = 0; i < 30; ++i) fd.pings[i].ping.sensor_y = 5000000.0 + 12.0 * static_cast<double>(i);  // 12 m/s
  const NavTrack t = build_track(fd, false, 0.0);
  EXPECT_EQ(t.nav_outliers, 0u);
  EXPECT_NEAR(t.pose[29].x_m, 12.0 * 29.0, 1e-6);
}

}  // namespace
}  // namespace qnav::tools
