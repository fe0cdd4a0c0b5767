// MAVLink codec: the checksum and hash against their published check values, a HEARTBEAT frame
// derived from the specification, field offsets against common.xml, every message's payload round
// trip, truncation and sequence numbers.
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "drivers/mavlink/frame.hpp"
#include "drivers/mavlink/messages.hpp"
#include "drivers/mavlink/parser.hpp"
#include "drivers/mavlink/sha256.hpp"
#include "nav/core/byte_order.hpp"
#include "test/unit/drivers/mavlink/mavlink_test_util.hpp"

namespace qnav::drivers::mavlink {
namespace {

std::string hex(const std::uint8_t* p, std::size_t n) {
  static const char* d = "0123456789abcdef";
  std::string s;
  for (std::size_t i = 0; i < n; ++i) {
    s += d[p[i] >> 4];
    s += d[p[i] & 15];
  }
  return s;
}

TEST(MavlinkCrc, Mcrf4xxCheckValue) {
  // CRC-16/MCRF4XX catalogue check value: "123456789" -> 0x6F91.
  const char* s = "123456789";
  EXPECT_EQ(crc_mcrf4xx(reinterpret_cast<const std::uint8_t*>(s), 9), 0x6F91);
}

TEST(MavlinkSha256, Fips180Vectors) {
  auto digest = [](const std::string& m) {
    Sha256 h;
    h.update(reinterpret_cast<const std::uint8_t*>(m.data()), m.size());
    std::uint8_t d[32];
    h.finish(d);
    return hex(d, 32);
  };
  EXPECT_EQ(digest(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(digest("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(digest("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  // One million 'a' fed in uneven pieces (block boundaries inside update()).
  Sha256 h;
  const std::string piece(997, 'a');
  std::size_t left = 1000000;
  while (left > 0) {
    const std::size_t n = left < piece.size() ? left : piece.size();
    h.update(reinterpret_cast<const std::uint8_t*>(piece.data()), n);
    left -= n;
  }
  std::uint8_t d[32];
  h.finish(d);
  EXPECT_EQ(hex(d, 32), "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
}

TEST(MavlinkFrame, HeartbeatBytesFromTheSpecification) {
  // HEARTBEAT from system 42, component 197, seq 7: custom_mode 0x12345, type 18 (onboard controller),
  // autopilot 8 (invalid), base_mode 0, system_status 4, mavlink_version 3. Payload in wire order
  // (custom_mode u32 first), CRC-16/MCRF4XX over len..payload then CRC_EXTRA 50. The same bytes come
  // out of node-mavlink 2.3.0 (an independent implementation).
  FrameEncoder enc(42, 197);
  for (int i = 0; i < 7; ++i) {
    std::uint8_t scratch[kMaxFrameBytes];
    ASSERT_TRUE(encode(enc, Heartbeat{}, Span<std::uint8_t>(scratch)).is_ok());
  }
  Heartbeat hb;
  hb.custom_mode = 0x12345;
  hb.type = kMavTypeOnboardController;
  hb.autopilot = kMavAutopilotInvalid;
  hb.system_status = 4;
  std::uint8_t buf[kMaxFrameBytes];
  auto n = encode(enc, hb, Span<std::uint8_t>(buf));
  ASSERT_TRUE(n.is_ok());
  EXPECT_EQ(hex(buf, n.value()), "fd090000072ac5000000452301001208000403c9ff");
}

TEST(MavlinkFrame, ZeroPayloadKeepsOneByte) {
  FrameEncoder enc(1, 1);
  std::uint8_t buf[kMaxFrameBytes];
  auto n = encode(enc, SystemTime{}, Span<std::uint8_t>(buf));
  ASSERT_TRUE(n.is_ok());
  EXPECT_EQ(n.value(), kHeaderV2 + 1 + kChecksumBytes);
  EXPECT_EQ(buf[1], 1);
  EXPECT_EQ(buf[kHeaderV2], 0);
}

TEST(MavlinkFrame, TruncatesTrailingZerosAndTheParserRestoresThem) {
  Odometry o;
  o.time_usec = 123456789;
  o.x = 1.5f;
  o.frame_id = 0;
  o.child_frame_id = 0;  // everything after the velocity covariance is zero
  FrameEncoder enc(1, 197);
  std::uint8_t buf[kMaxFrameBytes];
  auto n = encode(enc, o, Span<std::uint8_t>(buf));
  ASSERT_TRUE(n.is_ok());
  // The last non-zero byte is q[0] = 1.0f (bytes 20..23: 00 00 80 3f): 24 bytes remain.
  EXPECT_EQ(buf[1], 24);
  Parser p;
  test::Sink sink;
  p.feed(Span<const std::uint8_t>(buf, n.value()), [&](const Frame& f) { sink(f); });
  ASSERT_EQ(sink.frames.size(), 1u);
  EXPECT_EQ(sink.frames[0].wire_len, 24);
  EXPECT_EQ(sink.frames[0].payload_len, 233);
  Odometry back;
  back.quality = 55;
  ASSERT_TRUE(decode(sink.frames[0], back));
  EXPECT_EQ(back.time_usec, 123456789u);
  EXPECT_EQ(back.x, 1.5f);
  EXPECT_EQ(back.q[0], 1.0f);
  EXPECT_EQ(back.quality, 0);
  EXPECT_EQ(back.velocity_covariance[20], 0.0f);
}

TEST(MavlinkFrame, SequenceNumbersPerSenderWrap) {
  FrameEncoder a(1, 1), b(2, 1);
  std::uint8_t buf[kMaxFrameBytes];
  for (int i = 0; i < 300; ++i) {
    ASSERT_TRUE(encode(a, Heartbeat{}, Span<std::uint8_t>(buf)).is_ok());
    EXPECT_EQ(buf[4], static_cast<std::uint8_t>(i));
  }
  ASSERT_TRUE(encode(b, Heartbeat{}, Span<std::uint8_t>(buf)).is_ok());
  EXPECT_EQ(buf[4], 0);
  EXPECT_EQ(a.next_seq(), static_cast<std::uint8_t>(300));
}

TEST(MavlinkFrame, EncoderErrorsWriteNothing) {
  FrameEncoder enc(1, 1);
  std::uint8_t payload[4] = {1, 2, 3, 4};
  std::uint8_t buf[kMaxFrameBytes];
  EXPECT_EQ(enc.encode(9999, payload, 4, Span<std::uint8_t>(buf)).status(), StatusCode::kNotFound);
  EXPECT_EQ(enc.encode(Heartbeat::kId, payload, 10, Span<std::uint8_t>(buf)).status(), StatusCode::kInvalidArgument);
  EXPECT_EQ(enc.encode(Heartbeat::kId, payload, 4, Span<std::uint8_t>(buf, 15)).status(), StatusCode::kCapacityExceeded);
  EXPECT_EQ(enc.next_seq(), 0);
  EXPECT_TRUE(enc.encode(Heartbeat::kId, payload, 4, Span<std::uint8_t>(buf, 16)).is_ok());
}

TEST(MavlinkMessages, TableMatchesCommonXmlLengths) {
  // Full and base lengths from the sum of each message's field sizes in common.xml/ardupilotmega.xml.
  EXPECT_EQ(known_messages().size(), 17u);
  for (const MessageInfo& m : known_messages()) {
    EXPECT_LE(m.base_len, m.full_len) << m.name;
    EXPECT_EQ(message_info(m.id), &m);
  }
  EXPECT_EQ(message_info(Odometry::kId)->full_len, 233);
  EXPECT_EQ(message_info(Odometry::kId)->crc_extra, 91);
  EXPECT_EQ(message_info(VisionPositionDelta::kId)->full_len, 44);
  EXPECT_EQ(message_info(12345), nullptr);
  // The EKF origin pair (common.xml): SET_GPS_GLOBAL_ORIGIN 48 and the autopilot's answer GPS_GLOBAL_ORIGIN 49.
  EXPECT_EQ(message_info(SetGpsGlobalOrigin::kId)->crc_extra, 41);
  EXPECT_EQ(message_info(SetGpsGlobalOrigin::kId)->base_len, 13);
  EXPECT_EQ(message_info(SetGpsGlobalOrigin::kId)->full_len, 21);
  EXPECT_EQ(message_info(GpsGlobalOrigin::kId)->crc_extra, 39);
  EXPECT_EQ(message_info(GpsGlobalOrigin::kId)->base_len, 12);
  EXPECT_EQ(message_info(GpsGlobalOrigin::kId)->full_len, 20);
}

TEST(MavlinkMessages, OdometryFieldOffsetsFollowTheXml) {
  Odometry o;
  o.time_usec = 0x0102030405060708ULL;
  o.x = 1.0f;
  o.q[0] = 2.0f;
  o.vx = 3.0f;
  o.yawspeed = 4.0f;
  o.pose_covariance[0] = 5.0f;
  o.velocity_covariance[20] = 6.0f;
  o.frame_id = 20;
  o.child_frame_id = 12;
  o.reset_counter = 9;
  o.estimator_type = kMavEstimatorTypeVio;
  o.quality = -1;
  std::uint8_t p[kMaxPayload] = {};
  encode_payload(o, p);
  EXPECT_EQ(load_le_u64(p + 0), 0x0102030405060708ULL);
  EXPECT_EQ(load_le_f32(p + 8), 1.0f);
  EXPECT_EQ(load_le_f32(p + 20), 2.0f);
  EXPECT_EQ(load_le_f32(p + 36), 3.0f);
  EXPECT_EQ(load_le_f32(p + 56), 4.0f);
  EXPECT_EQ(load_le_f32(p + 60), 5.0f);
  EXPECT_EQ(load_le_f32(p + 144 + 80), 6.0f);
  EXPECT_EQ(p[228], 20);
  EXPECT_EQ(p[229], 12);
  EXPECT_EQ(p[230], 9);
  EXPECT_EQ(p[231], 3);
  EXPECT_EQ(p[232], 0xFF);
}

TEST(MavlinkMessages, DistanceSensorAndCommandLongOffsets) {
  DistanceSensor d;
  d.time_boot_ms = 7;
  d.current_distance = 0x0A0B;
  d.orientation = 25;  // MAV_SENSOR_ROTATION_PITCH_270 (down)
  d.signal_quality = 77;
  d.quaternion[3] = 0.5f;
  std::uint8_t p[kMaxPayload] = {};
  encode_payload(d, p);
  EXPECT_EQ(load_le_u32(p), 7u);
  EXPECT_EQ(load_le_u16(p + 8), 0x0A0B);
  EXPECT_EQ(p[12], 25);
  EXPECT_EQ(load_le_f32(p + 22 + 12), 0.5f);
  EXPECT_EQ(p[38], 77);

  CommandLong c;
  c.param7 = 2.0f;
  c.command = 511;
  c.target_system = 1;
  c.target_component = 2;
  c.confirmation = 3;
  std::uint8_t q[kMaxPayload] = {};
  encode_payload(c, q);
  EXPECT_EQ(load_le_f32(q + 24), 2.0f);
  EXPECT_EQ(load_le_u16(q + 28), 511);
  EXPECT_EQ(q[30], 1);
  EXPECT_EQ(q[31], 2);
  EXPECT_EQ(q[32], 3);
}

TEST(MavlinkMessages, StringsAreCutAndTerminated) {
  NamedValueFloat n;
  set_string(n.name, "xtrack_sigma_m");  // 14 characters: 10 go on the wire
  EXPECT_STREQ(n.name, "xtrack_sig");
  n.value = -2.25f;
  std::uint8_t p[kMaxPayload] = {};
  encode_payload(n, p);
  NamedValueFloat back;
  decode_payload(p, back);
  EXPECT_STREQ(back.name, "xtrack_sig");
  EXPECT_EQ(back.value, -2.25f);
  StatusText s;
  set_string(s.text, "mode repeat");
  std::uint8_t q[kMaxPayload] = {};
  encode_payload(s, q);
  EXPECT_EQ(q[1], 'm');
  EXPECT_EQ(q[12], 0);
}

// Every known message: random payloads decode and re-encode byte for byte (every field is read and
// written at the place and size the encoder uses), and survive a frame through the parser.
TEST(MavlinkMessages, EveryMessageRoundTripsRandomPayloads) {
  test::Lcg rng(2026);
  FrameEncoder enc(3, 4);
  Parser parser;
  for (const MessageInfo& info : known_messages()) {
    for (int trial = 0; trial < 200; ++trial) {
      std::uint8_t in[kMaxPayload] = {};
      for (std::size_t i = 0; i < info.full_len; ++i) in[i] = rng.byte();
      if (trial % 4 == 0) {  // trailing zeros: truncation on the wire
        for (std::size_t i = rng.below(info.full_len); i < info.full_len; ++i) in[i] = 0;
      }
      test::normalise_strings(info.id, in);
      std::uint8_t out[kMaxPayload] = {};
      ASSERT_TRUE(test::typed_round_trip(info.id, in, out)) << info.name;
      ASSERT_EQ(std::memcmp(in, out, info.full_len), 0) << info.name << " trial " << trial;

      std::uint8_t frame[kMaxFrameBytes];
      auto n = enc.encode(info.id, in, info.full_len, Span<std::uint8_t>(frame));
      ASSERT_TRUE(n.is_ok());
      test::Sink sink;
      parser.feed(Span<const std::uint8_t>(frame, n.value()), [&](const Frame& f) { sink(f); });
      ASSERT_EQ(sink.frames.size(), 1u) << info.name;
      const Frame& f = sink.frames[0];
      EXPECT_EQ(f.msgid, info.id);
      EXPECT_EQ(f.sysid, 3);
      EXPECT_EQ(f.compid, 4);
      EXPECT_EQ(f.payload_len, info.full_len);
      ASSERT_EQ(std::memcmp(f.payload, in, info.full_len), 0) << info.name;
    }
  }
  EXPECT_EQ(parser.counters().total(), 0u);
  EXPECT_EQ(parser.stats().frames_v2, known_messages().size() * 200u);
}

}  // namespace
}  // namespace qnav::drivers::mavlink
