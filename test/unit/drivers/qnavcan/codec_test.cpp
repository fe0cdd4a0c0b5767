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

TEST(QnavCanCodec, ModeCmdReverseBitKnownAnswerAndRoundTrip) {
  // Mode Repeat (2) in bits 0..3, ResetNav 0 (bit 4), Reverse 1 (bit 5) -> 0x22; RouteId 513 = 0x0201; Counter 5.
  ModeCmd m;
  ASSERT_TRUE(decode(frame("110#22010205"), m).is_ok());
  EXPECT_EQ(m.mode, Mode::kRepeat);
  EXPECT_FALSE(m.reset_nav);
  EXPECT_TRUE(m.reverse);
  EXPECT_EQ(m.route_id, 513);
  EXPECT_EQ(m.counter, 5);
  hal::CanFrame f;
  ASSERT_TRUE(encode(m, f).is_ok());
  expect_bytes(f, "110#22010205");
  m.reverse = false;
  m.reset_nav = true;
  ASSERT_TRUE(encode(m, f).is_ok());
  expect_bytes(f, "110#12010205");
  ModeCmd back;
  ASSERT_TRUE(decode(f, back).is_ok());
  EXPECT_FALSE(back.reverse);
  EXPECT_TRUE(back.reset_nav);
  ModeCmd old_sender;  // a sender that predates the bit leaves it 0: forwards
  ASSERT_TRUE(decode(frame("110#02010205"), old_sender).is_ok());
  EXPECT_FALSE(old_sender.reverse);
}

TEST(QnavCanCodec, RouteStatusKnownAnswerAndRoundTrip) {
  // GuidanceStatus DeadReckoned (2) bits 0..3, Side Starboard (2) bits 4..6 -> 0x22; sigma 1.23 m -> 123
  // = 0x007B; EstimateNode 0x1234; TileSeq 0xFFFF; Counter 0x2A.
  RouteStatus r;
  QNAV_EXPECT_NO_ALLOC(ASSERT_TRUE(decode(frame("203#227B003412FFFF2A"), r).is_ok()));
  EXPECT_EQ(r.status, GuidanceState::kDeadReckoned);
  EXPECT_EQ(r.side, SideOfRoute::kStarboard);
  EXPECT_NEAR(r.cross_track_sigma_m, 1.23, 1e-9);
  EXPECT_EQ(r.estimate_node, 0x1234);
  EXPECT_EQ(r.tile_seq, 0xFFFF);
  EXPECT_EQ(r.counter, 0x2A);
  hal::CanFrame f;
  ASSERT_TRUE(encode(r, f).is_ok());
  expect_bytes(f, "203#227B003412FFFF2A");
  EXPECT_EQ(f.data[0] & 0x80, 0) << "bit 7 is unused";
  const GuidanceState states[] = {GuidanceState::kTracking, GuidanceState::kHoldCourse, GuidanceState::kDeadReckoned,
                                  GuidanceState::kRouteEnd, GuidanceState::kNotRepeating};
  const SideOfRoute sides[] = {SideOfRoute::kOnRoute, SideOfRoute::kPort, SideOfRoute::kStarboard,
                               SideOfRoute::kUnknown};
  for (GuidanceState st : states)
    for (SideOfRoute sd : sides) {
      const RouteStatus m{st, sd, 12.34, 7, 65000, 200};
      ASSERT_TRUE(encode(m, f).is_ok());
      RouteStatus b;
      ASSERT_TRUE(decode(f, b).is_ok());
      EXPECT_EQ(b.status, st);
      EXPECT_EQ(b.side, sd);
      EXPECT_NEAR(b.cross_track_sigma_m, 12.34, 0.005 + 1e-12);
      EXPECT_EQ(b.estimate_node, 7);
      EXPECT_EQ(b.tile_seq, 65000);
      EXPECT_EQ(b.counter, 200);
    }
  // Values outside the value tables are refused both ways.
  EXPECT_EQ(decode(frame("203#057B003412FFFF2A"), r), StatusCode::kOutOfRange);  // GuidanceStatus 5
  EXPECT_EQ(decode(frame("203#407B003412FFFF2A"), r), StatusCode::kOutOfRange);  // Side 4
  EXPECT_EQ(decode(frame("203#227B003412FF"), r), StatusCode::kTruncated);
  EXPECT_EQ(encode(RouteStatus{static_cast<GuidanceState>(5), SideOfRoute::kOnRoute, 0, 0, 0, 0}, f),
            StatusCode::kOutOfRange);
  EXPECT_EQ(encode(RouteStatus{GuidanceState::kTracking, static_cast<SideOfRoute>(4), 0, 0, 0, 0}, f),
            StatusCode::kOutOfRange);
}

TEST(QnavCanCodec, RouteStatusDefaultSaysNotRepeatingAndUnknown) {
  const RouteStatus r;
  EXPECT_EQ(r.status, GuidanceState::kNotRepeating);
  EXPECT_EQ(r.side, SideOfRoute::kUnknown);
  EXPECT_DOUBLE_EQ(r.cross_track_sigma_m, kCrossTrackSigmaMaxM);
}

TEST(QnavCanCodec, CrossTrackSigmaSaturatesInsteadOfFailing) {
  hal::CanFrame f;
  RouteStatus back;
  for (double huge : {655.35, 655.36, 1000.0, 1e12, std::numeric_limits<double>::infinity()}) {
    SCOPED_TRACE(huge);
    RouteStatus r{GuidanceState::kHoldCourse, SideOfRoute::kUnknown, huge, 1, 2, 3};
    ASSERT_TRUE(encode(r, f).is_ok());
    EXPECT_EQ(f.data[1], 0xFF);
    EXPECT_EQ(f.data[2], 0xFF);
    ASSERT_TRUE(decode(f, back).is_ok());
    EXPECT_DOUBLE_EQ(back.cross_track_sigma_m, kCrossTrackSigmaMaxM);
  }
  RouteStatus neg{GuidanceState::kTracking, SideOfRoute::kOnRoute, -1.0, 0, 0, 0};
  EXPECT_EQ(encode(neg, f), StatusCode::kOutOfRange);
  RouteStatus nan{GuidanceState::kTracking, SideOfRoute::kOnRoute, std::numeric_limits<double>::quiet_NaN(), 0, 0, 0};
  EXPECT_EQ(encode(nan, f), StatusCode::kInvalidArgument);
}

TEST(QnavCanCodec, GuidanceAndSideNamesAreTheDbcValueNames) {
  EXPECT_STREQ(to_string(GuidanceState::kTracking), "Tracking");
  EXPECT_STREQ(to_string(GuidanceState::kHoldCourse), "HoldCourse");
  EXPECT_STREQ(to_string(GuidanceState::kDeadReckoned), "DeadReckoned");
  EXPECT_STREQ(to_string(GuidanceState::kRouteEnd), "RouteEnd");
  EXPECT_STREQ(to_string(GuidanceState::kNotRepeating), "NotRepeating");
  EXPECT_STREQ(to_string(static_cast<GuidanceState>(9)), "?");
  EXPECT_STREQ(to_string(SideOfRoute::kOnRoute), "OnRoute");
  EXPECT_STREQ(to_string(SideOfRoute::kPort), "Port");
  EXPECT_STREQ(to_string(SideOfRoute::kStarboard), "Starboard");
  EXPECT_STREQ(to_string(SideOfRoute::kUnknown), "Unknown");
  EXPECT_STREQ(to_string(static_cast<SideOfRoute>(9)), "?");
}

TEST(QnavCanCodec, FaultWordKeepsItsWireFormatAsPerBitSignals) {
  // Leak (bit 0), AttitudeLost (7), CameraLost (9) = 0x0281: NAV_STATUS bytes 4..5, HEALTH bytes 0..1,
  // little-endian, exactly where the 16-bit FaultFlags signal used to put them.
  const std::uint16_t word = fault::kLeak | fault::kAttitudeLost | fault::kCameraLost;
  ASSERT_EQ(word, 0x0281);
  hal::CanFrame f;
  ASSERT_TRUE(encode(NavStatus{Mode::kRepeat, true, 87.5, 0x04AF, word, 9}, f).is_ok());
  expect_bytes(f, "200#12AFAF0481020900");
  NavStatus ns;
  ASSERT_TRUE(decode(f, ns).is_ok());
  EXPECT_EQ(ns.fault_flags, word);
  EXPECT_EQ(ns.counter, 9);
  ASSERT_TRUE(encode(Health{word, 3, 4, 50.0, true, false}, f).is_ok());
  expect_bytes(f, "210#8102030004006401");
  Health h;
  ASSERT_TRUE(decode(f, h).is_ok());
  EXPECT_EQ(h.fault_flags, word);
  EXPECT_EQ(h.rejected_inputs, 3);
  EXPECT_EQ(h.deadline_misses, 4);
  EXPECT_TRUE(h.leak);
  // Every defined bit, alone and all together, round-trips.
  for (int b = 0; b <= fault::kBitCount; ++b) {
    const std::uint16_t w = b == fault::kBitCount ? fault::kDefined : static_cast<std::uint16_t>(1u << b);
    ASSERT_TRUE(encode(NavStatus{Mode::kIdle, false, 0, 0, w, 0}, f).is_ok());
    ASSERT_TRUE(decode(f, ns).is_ok());
    EXPECT_EQ(ns.fault_flags, w);
    ASSERT_TRUE(encode(Health{w, 0, 0, 0, false, false}, f).is_ok());
    ASSERT_TRUE(decode(f, h).is_ok());
    EXPECT_EQ(h.fault_flags, w);
  }
  EXPECT_EQ(fault::kDefined, 0x03FF);
  EXPECT_EQ(fault::kSoftware, 1u << 5);
  EXPECT_EQ(fault::kSonarLost, 1u << 6);
  EXPECT_EQ(fault::kDvlLost, 1u << 8);
}

TEST(QnavCanCodec, ReservedFaultBitsAreRefusedOnEncodeAndIgnoredOnDecode) {
  hal::CanFrame f;
  f.id = 0x7FF;
  for (int b = fault::kBitCount; b < 16; ++b) {
    const std::uint16_t w = static_cast<std::uint16_t>(fault::kLeak | (1u << b));
    EXPECT_EQ(encode(NavStatus{Mode::kIdle, false, 0, 0, w, 0}, f), StatusCode::kOutOfRange) << b;
    EXPECT_EQ(encode(Health{w, 0, 0, 0, false, false}, f), StatusCode::kOutOfRange) << b;
  }
  EXPECT_EQ(f.id, 0x7FFu) << "a refused encode leaves the frame alone";
  // A frame from a newer sender with bits 10..15 set: the defined bits are read, the rest ignored.
  NavStatus ns;
  ASSERT_TRUE(decode(frame("200#0000000001FC0000"), ns).is_ok());
  EXPECT_EQ(ns.fault_flags, fault::kLeak);
  Health h;
  ASSERT_TRUE(decode(frame("210#02FC000000000000"), h).is_ok());
  EXPECT_EQ(h.fault_flags, fault::kSensorTimeout);
}

TEST(QnavCanCodec, PerBitFaultSignalsDecodeGenericallyByName) {
  const std::uint16_t word = fault::kSensorTimeout | fault::kSoftware | fault::kDvlLost;
  struct Case {
    hal::CanFrame f;
    std::size_t first;  // index of FaultLeak in the message's signal table
    std::size_t signals;
  };
  Case cases[2];
  ASSERT_TRUE(encode(NavStatus{Mode::kMap, true, 50, 3, word, 1, 2}, cases[0].f).is_ok());
  cases[0].first = 4;
  cases[0].signals = 16;  // ... + Counter + ModeReject
  ASSERT_TRUE(encode(Health{word, 1, 2, 10, false, true}, cases[1].f).is_ok());
  cases[1].first = 0;
  cases[1].signals = 15;
  for (const Case& c : cases) {
    const MessageDef* def = nullptr;
    double values[kMaxSignalsPerMessage];
    QNAV_EXPECT_NO_ALLOC(ASSERT_TRUE(decode_generic(c.f, def, values, kMaxSignalsPerMessage).is_ok()));
    ASSERT_NE(def, nullptr);
    SCOPED_TRACE(def->name);
    EXPECT_EQ(def->signals.size(), c.signals);
    for (int b = 0; b < fault::kBitCount; ++b) {
      const SignalDef& s = def->signals[c.first + static_cast<std::size_t>(b)];
      EXPECT_STREQ(s.name, fault::kSignalNames[b]);
      EXPECT_EQ(s.length, 1);
      EXPECT_EQ(s.start_bit, def->signals[c.first].start_bit + b);
      EXPECT_DOUBLE_EQ(values[c.first + static_cast<std::size_t>(b)], ((word >> b) & 1u) ? 1.0 : 0.0) << s.name;
    }
    // The old 8-value array is refused, never overrun.
    double small[8];
    EXPECT_EQ(decode_generic(c.f, def, small, 8), StatusCode::kCapacityExceeded);
    EXPECT_NE(def, nullptr);
  }
  EXPECT_STREQ(fault::kSignalNames[0], "FaultLeak");
  EXPECT_STREQ(fault::kSignalNames[5], "FaultSoftware");
  EXPECT_STREQ(fault::kSignalNames[9], "FaultCameraLost");
}

TEST(QnavCanCodec, NoMessageHasMoreSignalsThanTheGenericArray) {
  for (const MessageDef& m : all_messages()) EXPECT_LE(m.signals.size(), kMaxSignalsPerMessage) << m.name;
  const MessageDef* rs = find_message(kIdRouteStatus);
  ASSERT_NE(rs, nullptr);
  EXPECT_STREQ(rs->name, "QNAV_ROUTE_STATUS");
  EXPECT_EQ(rs->cycle_ms, 100u);
  hal::CanFrame f;
  ASSERT_TRUE(encode(RouteStatus{GuidanceState::kRouteEnd, SideOfRoute::kPort, 2.5, 40, 41, 42}, f).is_ok());
  const MessageDef* def = nullptr;
  double v[kMaxSignalsPerMessage];
  ASSERT_TRUE(decode_generic(f, def, v, kMaxSignalsPerMessage).is_ok());
  ASSERT_EQ(def, rs);
  EXPECT_DOUBLE_EQ(v[0], 3.0);
  EXPECT_DOUBLE_EQ(v[1], 1.0);
  EXPECT_NEAR(v[2], 2.5, 1e-9);
  EXPECT_DOUBLE_EQ(v[5], 42.0);
}

namespace qnav::drivers::qnavcan {
namespace {
// NAV_STATUS.ModeReject (bits 56..59) says why the last mode command was refused; 0 = accepted.
TEST(QnavCanCodec, NavStatusCarriesTheModeRejectReason) {
  for (std::uint8_t why = 0; why <= 8; ++why) {
    NavStatus in;
    in.state = Mode::kIdle;
    in.mode_reject = why;
    hal::CanFrame f;
    ASSERT_TRUE(encode(in, f));
    EXPECT_EQ(f.data[7] & 0x0F, why);
    NavStatus out;
    ASSERT_TRUE(decode(f, out));
    EXPECT_EQ(out.mode_reject, why);
  }
  NavStatus bad;
  bad.mode_reject = 9;  // outside the DBC's [0|8]
  hal::CanFrame f;
  EXPECT_FALSE(encode(bad, f));
}
}  // namespace
}  // namespace qnav::drivers::qnavcan

// MAP_POSE: 21-bit signed positions at 1 cm (m or mosaic px), a 14-bit heading at 0.0004 rad; a
// known frame, the round trip within half a step, the range ends and NaN refused.
TEST(QnavCanCodec, MapPoseKnownAnswerRoundTripAndRange) {
  hal::CanFrame f;
  ASSERT_TRUE(encode(MapPose{1.0, -1.0, 0.0004, 7}, f).is_ok());
  // X raw 100 at bits 0..20, Y raw -100 (21-bit two's complement) at 21..41, Heading raw 1 at 42..55, Counter 7.
  std::uint64_t raw = 0;
  for (int i = 0; i < 8; ++i) raw |= static_cast<std::uint64_t>(f.data[i]) << (8 * i);
  EXPECT_EQ(raw & 0x1FFFFFu, 100u);
  EXPECT_EQ((raw >> 21) & 0x1FFFFFu, (1u << 21) - 100u);
  EXPECT_EQ((raw >> 42) & 0x3FFFu, 1u);
  EXPECT_EQ(raw >> 56, 7u);
  for (const MapPose m : {MapPose{123.456, -7890.12, -3.1416, 1}, MapPose{-kMapPositionMax, kMapPositionMax, 3.1416, 255},
                          MapPose{0.004, -0.004, 2.0, 0}}) {
    ASSERT_TRUE(encode(m, f).is_ok());
    MapPose b;
    ASSERT_TRUE(decode(f, b).is_ok());
    EXPECT_NEAR(b.x, m.x, 0.005);
    EXPECT_NEAR(b.y, m.y, 0.005);
    EXPECT_NEAR(b.heading_rad, m.heading_rad, 0.0002);
    EXPECT_EQ(b.counter, m.counter);
  }
  EXPECT_EQ(encode(MapPose{kMapPositionMax + 0.1, 0, 0, 0}, f), StatusCode::kOutOfRange);
  EXPECT_EQ(encode(MapPose{0, 0, 3.2, 0}, f), StatusCode::kOutOfRange);
  EXPECT_FALSE(encode(MapPose{std::numeric_limits<double>::quiet_NaN(), 0, 0, 0}, f).is_ok());
}

// MAP_STATUS: every field and flag round-trips on its own (a walking flag), and decodes generically
// under its DBC names.
TEST(QnavCanCodec, MapStatusFlagsRoundTripEachOnItsOwn) {
  hal::CanFrame f;
  MapStatus m;
  m.node_id = 1234;
  m.node_count = 4321;
  m.frame_seq = 65535;
  m.counter = 9;
  ASSERT_TRUE(encode(m, f).is_ok());
  MapStatus b;
  ASSERT_TRUE(decode(f, b).is_ok());
  EXPECT_EQ(b.node_id, 1234);
  EXPECT_EQ(b.node_count, 4321);
  EXPECT_EQ(b.frame_seq, 65535);
  EXPECT_EQ(b.counter, 9);
  EXPECT_FALSE(b.registered || b.black || b.saturated || b.textureless || b.lost || b.metric || b.new_node || b.revisit);
  EXPECT_EQ(MapStatus{}.node_id, kMapNoNode);
  bool MapStatus::*const flags[] = {&MapStatus::registered, &MapStatus::black,  &MapStatus::saturated, &MapStatus::textureless,
                                    &MapStatus::lost,       &MapStatus::metric, &MapStatus::new_node,  &MapStatus::revisit};
  const char* const names[] = {"Registered", "Black", "Saturated", "Textureless", "Lost", "Metric", "NewNode", "Revisit"};
  for (std::size_t k = 0; k < 8; ++k) {
    MapStatus one;
    one.*flags[k] = true;
    ASSERT_TRUE(encode(one, f).is_ok());
    ASSERT_TRUE(decode(f, b).is_ok());
    for (std::size_t j = 0; j < 8; ++j) EXPECT_EQ(b.*flags[j], j == k) << names[k] << " set, " << names[j] << " read";
    const MessageDef* def = nullptr;
    double v[kMaxSignalsPerMessage];
    ASSERT_TRUE(decode_generic(f, def, v, kMaxSignalsPerMessage).is_ok());
    ASSERT_NE(def, nullptr);
    EXPECT_STREQ(def->name, "QNAV_MAP_STATUS");
    EXPECT_STREQ(def->signals[3 + k].name, names[k]);
    EXPECT_DOUBLE_EQ(v[3 + k], 1.0);
    EXPECT_EQ(def->cycle_ms, 0u);  // per frame, not periodic
  }
}
