// Known-answer frames (hand-computed from docs/qnav.dbc, written in candump log form) and round trips.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "drivers/qnavcan/messages.hpp"
#include "hal/core/candump.hpp"
#include "test/support/alloc_guard.hpp"

using namespace qnav;
using namespace qnav::drivers::qnavcan;

namespace {
hal::CanFrame frame(const char* line) {
  hal::CanLogRecord r;
  const Status s = hal::parse_can_log_line(line, std::strlen(line), r);
  EXPECT_TRUE(s.is_ok()) << line << ": " << s.message();
  return r.frame;
}
void expect_bytes(const hal::CanFrame& f, const char* line) {
  const hal::CanFrame want = frame(line);
  ASSERT_EQ(f.id, want.id);
  ASSERT_EQ(f.len, want.len);
  for (int i = 0; i < f.len; ++i) EXPECT_EQ(f.data[i], want.data[i]) << "byte " << i;
}
}  // namespace

TEST(QnavCanCodec, AttitudeKnownAnswerLittleEndianSigned) {
  // roll -0.1 rad -> -1000 = 0xFC18; pitch 0.05 -> 500 = 0x01F4; heading 3.0 -> 30000 = 0x7530.
  AttitudeIn a;
  QNAV_EXPECT_NO_ALLOC(ASSERT_TRUE(decode(frame("(1.000000) can0 100#18FCF40130752A01"), a).is_ok()));
  EXPECT_NEAR(a.roll_rad, -0.1, 1e-9);
  EXPECT_NEAR(a.pitch_rad, 0.05, 1e-9);
  EXPECT_NEAR(a.heading_rad, 3.0, 1e-9);
  EXPECT_EQ(a.counter, 0x2A);
  EXPECT_TRUE(a.valid);
  hal::CanFrame f;
  ASSERT_TRUE(encode(a, f).is_ok());
  expect_bytes(f, "100#18FCF40130752A01");
}

TEST(QnavCanCodec, DepthKnownAnswerBigEndian) {
  // depth 1234.567 m -> 1234567 = 0x12D687 (MSB first); altitude 12.34 -> 0x04D2; both valid -> 0xC0.
  DepthIn d;
  ASSERT_TRUE(decode(frame("102#12D68704D207C000"), d).is_ok());
  EXPECT_NEAR(d.depth_m, 1234.567, 1e-9);
  EXPECT_NEAR(d.altitude_m, 12.34, 1e-9);
  EXPECT_EQ(d.counter, 7);
  EXPECT_TRUE(d.depth_valid);
  EXPECT_TRUE(d.altitude_valid);
  d.altitude_valid = false;
  hal::CanFrame f;
  ASSERT_TRUE(encode(d, f).is_ok());
  expect_bytes(f, "102#12D68704D2078000");
}

TEST(QnavCanCodec, EveryOutputRoundTripsWithinHalfAStep) {
  hal::CanFrame f;
  NavStatus ns{Mode::kRepeat, true, 87.5, 1234, fault::kLeak | fault::kBusOff, 9};
  ASSERT_TRUE(encode(ns, f).is_ok());
  NavStatus ns2;
  ASSERT_TRUE(decode(f, ns2).is_ok());
  EXPECT_EQ(ns2.state, Mode::kRepeat);
  EXPECT_TRUE(ns2.localised);
  EXPECT_DOUBLE_EQ(ns2.confidence_pct, 87.5);
  EXPECT_EQ(ns2.node_index, 1234);
  EXPECT_EQ(ns2.fault_flags, fault::kLeak | fault::kBusOff);
  RouteGuidance g{-12.345, 0.7854, 456.78, 65535};
  ASSERT_TRUE(encode(g, f).is_ok());
  RouteGuidance g2;
  ASSERT_TRUE(decode(f, g2).is_ok());
  EXPECT_NEAR(g2.cross_track_m, -12.345, 0.005 + 1e-12);
  EXPECT_NEAR(g2.heading_error_rad, 0.7854, 0.00005 + 1e-12);
  EXPECT_NEAR(g2.dist_to_next_m, 456.78, 0.05 + 1e-12);
  EXPECT_EQ(g2.target_node, 65535);
  VoStep v{0.0123, -0.0456, -0.01, 200, 255};
  ASSERT_TRUE(encode(v, f).is_ok());
  VoStep v2;
  ASSERT_TRUE(decode(f, v2).is_ok());
  EXPECT_NEAR(v2.dx_m, 0.0123, 0.0005);
  EXPECT_NEAR(v2.dy_m, -0.0456, 0.0005);
  EXPECT_NEAR(v2.dyaw_rad, -0.01, 0.00005);
  EXPECT_EQ(v2.inliers, 200);
  Health h{0x0011, 65535, 3, 42.5, true, false};
  ASSERT_TRUE(encode(h, f).is_ok());
  Health h2;
  ASSERT_TRUE(decode(f, h2).is_ok());
  EXPECT_EQ(h2.rejected_inputs, 65535);
  EXPECT_DOUBLE_EQ(h2.cpu_load_pct, 42.5);
  EXPECT_TRUE(h2.leak);
  EXPECT_FALSE(h2.bus_off);
  Heartbeat hb{4000000000u, Mode::kTeach, 0, 1, 17};
  ASSERT_TRUE(encode(hb, f).is_ok());
  Heartbeat hb2;
  ASSERT_TRUE(decode(f, hb2).is_ok());
  EXPECT_EQ(hb2.uptime_s, 4000000000u);
  EXPECT_EQ(hb2.state, Mode::kTeach);
  EXPECT_EQ(hb2.sw_minor, 1);
  ModeCmd mc{Mode::kMap, true, 513, 3};
  ASSERT_TRUE(encode(mc, f).is_ok());
  EXPECT_EQ(f.len, 4);
  ModeCmd mc2;
  ASSERT_TRUE(decode(f, mc2).is_ok());
  EXPECT_EQ(mc2.mode, Mode::kMap);
  EXPECT_TRUE(mc2.reset_nav);
  EXPECT_EQ(mc2.route_id, 513);
  RatesIn r{-15.9, 0.0005, 1.2345, 1};
  ASSERT_TRUE(encode(r, f).is_ok());
  RatesIn r2;
  ASSERT_TRUE(decode(f, r2).is_ok());
  EXPECT_NEAR(r2.roll_rate_radps, -15.9, 0.00025 + 1e-12);
  EXPECT_NEAR(r2.yaw_rate_radps, 1.2345, 0.00025 + 1e-12);
}

TEST(QnavCanCodec, RejectsOutOfRangeTruncatedAndWrongFormat) {
  AttitudeIn a;
  // Roll raw 32000 = 3.2 rad > 3.1416: outside the DBC range.
  EXPECT_EQ(decode(frame("100#007DF40130752A01"), a), StatusCode::kOutOfRange);
  EXPECT_EQ(decode(frame("100#18FCF401"), a), StatusCode::kTruncated);
  EXPECT_EQ(decode(frame("101#0000000000000000"), a), StatusCode::kNotFound);
  EXPECT_EQ(decode(frame("00000100#18FCF40130752A01"), a), StatusCode::kUnsupported);
  hal::CanFrame f;
  AttitudeIn bad{std::numeric_limits<double>::quiet_NaN(), 0, 0, 0, true};
  EXPECT_EQ(encode(bad, f), StatusCode::kInvalidArgument);
  AttitudeIn big{0, 2.0, 0, 0, true};  // pitch beyond +-pi/2
  EXPECT_EQ(encode(big, f), StatusCode::kOutOfRange);
  DepthIn deep{11000.6, 0, 0, true, true};
  EXPECT_EQ(encode(deep, f), StatusCode::kOutOfRange);
}

TEST(QnavCanCodec, SignedExtremesAndUnsignedTop) {
  hal::CanFrame f;
  VoStep v{-32.0, 32.0, 0, 0, 0};  // -32000 and +32000 raw
  ASSERT_TRUE(encode(v, f).is_ok());
  VoStep v2;
  ASSERT_TRUE(decode(f, v2).is_ok());
  EXPECT_DOUBLE_EQ(v2.dx_m, -32.0);
  EXPECT_DOUBLE_EQ(v2.dy_m, 32.0);
  EXPECT_EQ(f.data[0], 0x00);  // -32000 = 0x8300
  EXPECT_EQ(f.data[1], 0x83);
}
