#include "nav/route/route_format.hpp"

#include <gtest/gtest.h>

#include <cstring>
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
  EXPECT_EQ(buf[8], 1);  // version, little-endian on every host
  EXPECT_EQ(buf[9], 0);
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

}  // namespace
}  // namespace qnav::route
