#include "nav/route/route_format.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <vector>

#include "nav/core/byte_order.hpp"
#include "nav/core/crc.hpp"

namespace qnav::route {
namespace {

RouteParams params() {
  RouteParams p;
  p.sensor = SensorKind::kSideScan;
  p.depth_m = 12.5f;
  p.node_spacing_m = 40.0f;
  p.tile_length_m = 50.0f;
  p.tile_width_m = 120.0f;
  p.pixel_m = 0.25f;
  p.max_keypoints = 16;
  p.harris_window_px = 5;
  p.keypoint_min_distance_px = 6;
  return p;
}

RouteNode node(std::uint32_t index, int kps) {
  RouteNode n;
  n.meta.index = index;
  n.meta.pose = Pose2{100.25 + index, -7.5, 0.75};
  n.meta.along_m = 40.0 * index;
  n.meta.stamp_ns = 1234567890123ull + index;
  for (int i = 0; i < kps; ++i) {
    RouteKeypoint* k = n.keypoints.emplace_back();
    k->x_m = 1.5f * static_cast<float>(i);
    k->y_m = -0.25f * static_cast<float>(i);
    k->score = 3.0f + static_cast<float>(i);
    for (std::size_t b = 0; b < kDescriptorBytes; ++b) k->descriptor[b] = static_cast<std::int8_t>((i * 7 + static_cast<int>(b)) % 255 - 127);
  }
  n.meta.keypoint_count = static_cast<std::uint16_t>(kps);
  return n;
}

TEST(RouteFormat, HeaderRoundTripAndFixedLittleEndianLayout) {
  std::uint8_t buf[kHeaderBytes];
  ASSERT_TRUE(encode_header(params(), Span<std::uint8_t>(buf)).is_ok());
  EXPECT_EQ(0, std::memcmp(buf, "QNAVRTE", 7));
  EXPECT_EQ(buf[8], 2);  // version, little-endian on every host
  EXPECT_EQ(buf[9], 0);
  for (std::size_t i = 44; i < 60; ++i) EXPECT_EQ(buf[i], 0) << "reserved byte " << i;
  EXPECT_EQ(load_le_u32(buf + 60), crc32(buf, 60));
  RouteFormatCounters c{kRouteFormatCounterNames};
  Result<RouteParams> p = decode_header(Span<const std::uint8_t>(buf), &c);
  ASSERT_TRUE(p.is_ok());
  EXPECT_EQ(p->sensor, SensorKind::kSideScan);
  EXPECT_FLOAT_EQ(p->depth_m, 12.5f);
  EXPECT_FLOAT_EQ(p->node_spacing_m, 40.0f);
  EXPECT_EQ(p->max_keypoints, 16);
  EXPECT_EQ(p->harris_window_px, 5);
  EXPECT_EQ(c.total(), 0u);
}

TEST(RouteFormat, DamagedHeaderIsRejectedAndCounted) {
  std::uint8_t buf[kHeaderBytes];
  ASSERT_TRUE(encode_header(params(), Span<std::uint8_t>(buf)).is_ok());
  RouteFormatCounters c{kRouteFormatCounterNames};
  buf[30] ^= 0x10;
  EXPECT_EQ(decode_header(Span<const std::uint8_t>(buf), &c).status(), StatusCode::kCorrupt);
  EXPECT_EQ(c.get(RouteFormatCounter::kBadHeaderCrc), 1u);
  buf[30] ^= 0x10;
  buf[0] = 'X';
  EXPECT_EQ(decode_header(Span<const std::uint8_t>(buf), &c).status(), StatusCode::kCorrupt);
  EXPECT_EQ(c.get(RouteFormatCounter::kBadHeaderMagic), 1u);
  EXPECT_EQ(decode_header(Span<const std::uint8_t>(buf, 10), &c).status(), StatusCode::kTruncated);
}

TEST(RouteFormat, InvalidParamsAreRefusedByTheWriter) {
  std::uint8_t buf[kHeaderBytes];
  RouteParams p = params();
  p.sensor = SensorKind::kUnknown;
  EXPECT_FALSE(encode_header(p, Span<std::uint8_t>(buf)).is_ok());
  p = params();
  p.node_spacing_m = std::nanf("");
  EXPECT_FALSE(encode_header(p, Span<std::uint8_t>(buf)).is_ok());
  p = params();
  p.max_keypoints = static_cast<std::uint16_t>(kMaxKeypointsPerNode + 1);
  EXPECT_FALSE(encode_header(p, Span<std::uint8_t>(buf)).is_ok());
}

TEST(RouteFormat, NodeRoundTripIsExact) {
  const RouteParams p = params();
  std::vector<std::uint8_t> buf(record_bytes(p.max_keypoints));
  const RouteNode in = node(7, 11);
  ASSERT_TRUE(encode_node(p, in, Span<std::uint8_t>(buf.data(), buf.size())).is_ok());
  RouteNode out;
  ASSERT_TRUE(decode_node(p, Span<const std::uint8_t>(buf.data(), buf.size()), 7, out, nullptr).is_ok());
  EXPECT_EQ(out.meta.index, 7u);
  EXPECT_DOUBLE_EQ(out.meta.pose.x_m, in.meta.pose.x_m);
  EXPECT_DOUBLE_EQ(out.meta.pose.y_m, in.meta.pose.y_m);
  EXPECT_NEAR(out.meta.pose.heading_rad, 0.75, 1e-7);
  EXPECT_DOUBLE_EQ(out.meta.along_m, 280.0);
  EXPECT_EQ(out.meta.stamp_ns, in.meta.stamp_ns);
  ASSERT_EQ(out.keypoints.size(), 11u);
  for (std::size_t i = 0; i < 11; ++i) {
    EXPECT_EQ(out.keypoints[i].x_m, in.keypoints[i].x_m);
    EXPECT_EQ(out.keypoints[i].y_m, in.keypoints[i].y_m);
    EXPECT_EQ(0, std::memcmp(out.keypoints[i].descriptor, in.keypoints[i].descriptor, kDescriptorBytes));
  }
}

TEST(RouteFormat, EveryFlippedByteOfARecordIsDetectedAndNothingIsWritten) {
  const RouteParams p = params();
  std::vector<std::uint8_t> buf(record_bytes(p.max_keypoints));
  ASSERT_TRUE(encode_node(p, node(3, 5), Span<std::uint8_t>(buf.data(), buf.size())).is_ok());
  RouteFormatCounters c{kRouteFormatCounterNames};
  const RouteNode sentinel = node(99, 2);
  for (std::size_t i = 0; i < buf.size(); ++i) {
    buf[i] ^= 0x01;
    RouteNode out = sentinel;
    EXPECT_EQ(decode_node(p, Span<const std::uint8_t>(buf.data(), buf.size()), 3, out, &c), StatusCode::kCorrupt) << "byte " << i;
    EXPECT_EQ(out.meta.index, 99u) << "half-read at byte " << i;
    EXPECT_EQ(out.keypoints.size(), 2u);
    buf[i] ^= 0x01;
  }
  EXPECT_EQ(c.total(), buf.size());
}

TEST(RouteFormat, OutOfSequenceAndTruncatedRecordsAreReported) {
  const RouteParams p = params();
  std::vector<std::uint8_t> buf(record_bytes(p.max_keypoints));
  ASSERT_TRUE(encode_node(p, node(3, 5), Span<std::uint8_t>(buf.data(), buf.size())).is_ok());
  RouteNode out;
  RouteFormatCounters c{kRouteFormatCounterNames};
  EXPECT_EQ(decode_node(p, Span<const std::uint8_t>(buf.data(), buf.size()), 4, out, &c), StatusCode::kCorrupt);
  EXPECT_EQ(c.get(RouteFormatCounter::kBadRecordIndex), 1u);
  EXPECT_EQ(decode_node(p, Span<const std::uint8_t>(buf.data(), buf.size() - 1), 3, out, &c), StatusCode::kTruncated);
}

TEST(RouteFormat, WriterRefusesTooManyKeypointsAndNonFinitePoses) {
  const RouteParams p = params();
  std::vector<std::uint8_t> buf(record_bytes(p.max_keypoints));
  EXPECT_EQ(encode_node(p, node(0, 17), Span<std::uint8_t>(buf.data(), buf.size())), StatusCode::kCapacityExceeded);
  RouteNode n = node(0, 1);
  n.meta.pose.x_m = std::nan("");
  EXPECT_EQ(encode_node(p, n, Span<std::uint8_t>(buf.data(), buf.size())), StatusCode::kInvalidArgument);
}


TEST(RouteFormat, Version1HeadersAreReadAndOtherVersionsRefused) {
  std::uint8_t buf[kHeaderBytes];
  ASSERT_TRUE(encode_header(params(), Span<std::uint8_t>(buf)).is_ok());
  RouteFormatCounters c{kRouteFormatCounterNames};
  RouteHeaderInfo info;
  ASSERT_TRUE(decode_header(Span<const std::uint8_t>(buf), &c, &info).is_ok());
  EXPECT_EQ(info.version, 2);
  store_le_u16(buf + 8, 1);
  store_le_u32(buf + 60, crc32(buf, 60));
  ASSERT_TRUE(decode_header(Span<const std::uint8_t>(buf), &c, &info).is_ok());
  EXPECT_EQ(info.version, 1);
  for (std::uint16_t v : {std::uint16_t{0}, std::uint16_t{3}, std::uint16_t{0x0200}}) {
    store_le_u16(buf + 8, v);
    store_le_u32(buf + 60, crc32(buf, 60));
    EXPECT_EQ(decode_header(Span<const std::uint8_t>(buf), &c, &info).status(), StatusCode::kUnsupported) << v;
  }
  EXPECT_EQ(c.get(RouteFormatCounter::kUnsupportedVersion), 3u);
}

TEST(RouteFormat, AbsurdHeaderLengthsAreRefused) {
  std::uint8_t buf[kHeaderBytes];
  RouteParams p = params();
  p.node_spacing_m = 7.07e7f;  // 70,710 km: the bad-XTF route of issue 19
  EXPECT_EQ(encode_header(p, Span<std::uint8_t>(buf)), StatusCode::kInvalidArgument);
  p = params();
  p.depth_m = 1e9f;
  EXPECT_EQ(encode_header(p, Span<std::uint8_t>(buf)), StatusCode::kInvalidArgument);
  // ... and on reading: a CRC-valid header holding one is bad_params.
  ASSERT_TRUE(encode_header(params(), Span<std::uint8_t>(buf)).is_ok());
  store_le_f32(buf + 32, std::numeric_limits<float>::infinity());
  store_le_u32(buf + 60, crc32(buf, 60));
  RouteFormatCounters c{kRouteFormatCounterNames};
  EXPECT_FALSE(decode_header(Span<const std::uint8_t>(buf), &c).is_ok());
  EXPECT_EQ(c.get(RouteFormatCounter::kBadParams), 1u);
}

// Rewrites field bytes of an encoded record and makes its CRC valid again: what a foreign writer or
// damage the CRC missed would leave.
void patch_f32(std::vector<std::uint8_t>& rec, std::size_t at, float v) {
  store_le_f32(rec.data() + at, v);
  store_le_u32(rec.data() + rec.size() - 4, crc32(rec.data(), rec.size() - 4));
}
void patch_f64(std::vector<std::uint8_t>& rec, std::size_t at, double v) {
  store_le_f64(rec.data() + at, v);
  store_le_u32(rec.data() + rec.size() - 4, crc32(rec.data(), rec.size() - 4));
}

TEST(RouteFormat, CrcValidRecordsWithNonFiniteOrAbsurdFieldsAreCorruptNeverUsed) {
  const RouteParams p = params();
  std::vector<std::uint8_t> good(record_bytes(p.max_keypoints));
  ASSERT_TRUE(encode_node(p, node(3, 5), Span<std::uint8_t>(good.data(), good.size())).is_ok());
  const std::size_t kp2 = kRecordFixedBytes + 2 * kKeypointBytes;
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  struct Case {
    const char* what;
    std::size_t at;
    bool f64;
    double v;
    const char* why;
  };
  const double bound = kMaxKeypointOffsetPx * static_cast<double>(p.pixel_m);
  const Case cases[] = {
      {"keypoint x NaN", kp2, false, nan, "route keypoint not finite"},
      {"keypoint y inf", kp2 + 4, false, -inf, "route keypoint not finite"},
      {"keypoint score NaN", kp2 + 8, false, nan, "route keypoint not finite"},
      {"keypoint x beyond any tile", kp2, false, 1.01 * bound, "route keypoint position out of range"},
      {"keypoint y 1e30", kp2 + 4, false, 1e30, "route keypoint position out of range"},
      {"node x 1e12 m", 8, true, 1e12, "route node position out of range"},
      {"node along NaN", 28, true, std::nan(""), "route node pose not finite"},
      {"node heading 1e6 rad", 24, false, 1e6, "route node heading out of range"},
  };
  for (const Case& k : cases) {
    std::vector<std::uint8_t> rec = good;
    if (k.f64)
      patch_f64(rec, k.at, k.v);
    else
      patch_f32(rec, k.at, static_cast<float>(k.v));
    RouteFormatCounters c{kRouteFormatCounterNames};
    RouteNode out = node(99, 2);
    const Status s = decode_node(p, Span<const std::uint8_t>(rec.data(), rec.size()), 3, out, &c);
    EXPECT_EQ(s, StatusCode::kCorrupt) << k.what;
    EXPECT_STREQ(s.message(), k.why) << k.what;
    EXPECT_EQ(c.get(RouteFormatCounter::kBadRecordField), 1u) << k.what;
    EXPECT_EQ(c.total(), 1u) << k.what;
    EXPECT_EQ(out.meta.index, 99u) << k.what << ": half-read";
    // The metadata decoder (route info, the repeat's start) applies the same checks.
    NodeMeta m;
    EXPECT_EQ(decode_node_meta(p, Span<const std::uint8_t>(rec.data(), rec.size()), 3, m, &c), StatusCode::kCorrupt) << k.what;
  }
  // Within the bounds: a keypoint at the edge of the largest tile and a large but real position.
  std::vector<std::uint8_t> rec = good;
  patch_f32(rec, kp2, static_cast<float>(0.99 * bound));
  patch_f64(rec, 8, 6.4e6);
  RouteNode out;
  EXPECT_TRUE(decode_node(p, Span<const std::uint8_t>(rec.data(), rec.size()), 3, out, nullptr).is_ok());
}

TEST(RouteFormat, TheWriterRefusesEveryValueTheReaderWouldRejectAndWritesNothing) {
  const RouteParams p = params();
  std::vector<std::uint8_t> buf(record_bytes(p.max_keypoints), 0xEE);
  const std::vector<std::uint8_t> untouched = buf;
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  for (int i = 0; i < 7; ++i) {
    RouteNode n = node(1, 4);
    switch (i) {
      case 0: n.keypoints[3].x_m = nan; break;
      case 1: n.keypoints[0].y_m = inf; break;
      case 2: n.keypoints[2].score = -inf; break;
      case 3: n.keypoints[1].x_m = 1e20f; break;
      case 4: n.meta.pose.y_m = -3e7; break;
      case 5: n.meta.along_m = std::numeric_limits<double>::infinity(); break;
      case 6: n.meta.pose.heading_rad = 1e300; break;
    }
    EXPECT_EQ(encode_node(p, n, Span<std::uint8_t>(buf.data(), buf.size())), StatusCode::kInvalidArgument) << "case " << i;
    EXPECT_EQ(buf, untouched) << "case " << i << ": bytes written before the refusal";
    EXPECT_EQ(validate_node(p, n), StatusCode::kInvalidArgument) << "case " << i;
  }
}

TEST(RouteFormat, EndMarkRoundTripAndEveryFlippedByteIsDetected) {
  std::uint8_t m[kEndMarkBytes];
  ASSERT_TRUE(encode_end_mark(123456, Span<std::uint8_t>(m)).is_ok());
  EXPECT_EQ(0, std::memcmp(m, "QEND", 4));
  EXPECT_EQ(load_le_u32(m + 4), 123456u);  // little-endian on every host
  Result<std::uint32_t> n = decode_end_mark(Span<const std::uint8_t>(m), nullptr);
  ASSERT_TRUE(n.is_ok());
  EXPECT_EQ(*n, 123456u);
  RouteFormatCounters c{kRouteFormatCounterNames};
  for (std::size_t i = 0; i < kEndMarkBytes; ++i) {
    m[i] ^= 0x08;
    EXPECT_EQ(decode_end_mark(Span<const std::uint8_t>(m), &c).status(), StatusCode::kCorrupt) << "byte " << i;
    m[i] ^= 0x08;
  }
  EXPECT_EQ(c.get(RouteFormatCounter::kBadEndMark), kEndMarkBytes);
  EXPECT_EQ(decode_end_mark(Span<const std::uint8_t>(m, kEndMarkBytes - 1), &c).status(), StatusCode::kCorrupt);
  EXPECT_LT(kEndMarkBytes, record_bytes(1)) << "a mark can never be mistaken for a whole record";
}

}  // namespace
}  // namespace qnav::route
