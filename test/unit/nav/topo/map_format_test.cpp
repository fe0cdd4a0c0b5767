// The map file format's byte layout (nav/topo/map_format.hpp) is little-endian on every target:
// known bytes at known offsets, and decode(encode(x)) == x; run on the big-endian LEON3 build too.
#include "nav/topo/map_format.hpp"

#include <gtest/gtest.h>

#include <cstring>

namespace qnav::topo {
namespace {

TEST(MapFormat, HeaderAndRecordsAreLittleEndianAndRoundTrip) {
  MapHeader h;
  h.max_edges_per_node = 6;
  h.node_count = 0x0102;
  h.edge_count = 3;
  h.capacity = 0x0400;
  h.observations = 0x0A0B0C0D;
  h.revisits = 7;
  h.node_spacing = 0.25;
  h.metric = true;
  std::uint8_t b[kMapNodeBytes] = {};
  ASSERT_TRUE(encode_map_header(h, Span<std::uint8_t>(b, kMapHeaderBytes)).is_ok());
  EXPECT_EQ(std::memcmp(b, "QNAVTOPO", 8), 0);
  EXPECT_EQ(b[8], 1);  // version, low byte first
  EXPECT_EQ(b[9], 0);
  EXPECT_EQ(b[20], 0x02);
  EXPECT_EQ(b[21], 0x01);
  EXPECT_EQ(b[32], 0x0D);
  EXPECT_EQ(b[35], 0x0A);
  EXPECT_EQ(b[47], 0x3F);  // 0.25 = 0x3FD0000000000000, most significant byte last
  EXPECT_EQ(b[46], 0xD0);
  EXPECT_EQ(b[48], 1);
  MapHeader d;
  ASSERT_TRUE(decode_map_header(Span<const std::uint8_t>(b, kMapHeaderBytes), d).is_ok());
  EXPECT_EQ(d.node_count, h.node_count);
  EXPECT_EQ(d.observations, h.observations);
  EXPECT_EQ(d.node_spacing, h.node_spacing);
  EXPECT_TRUE(d.metric);
  b[30] ^= 1;
  EXPECT_EQ(decode_map_header(Span<const std::uint8_t>(b, kMapHeaderBytes), d).code(), StatusCode::kCorrupt);

  TopoNode n;
  n.position = Vec2d(-1.5, 2.0);
  n.heading_rad = 0.5;
  n.created = 9;
  n.visits = 4;
  for (int i = 0; i < kSignatureBins; ++i) n.signature.bins[i] = static_cast<float>(i) / 2016.0f;  // sums to 1
  ASSERT_TRUE(encode_map_node(0x0203, n, Span<std::uint8_t>(b, kMapNodeBytes)).is_ok());
  EXPECT_EQ(std::memcmp(b, "QTND", 4), 0);
  EXPECT_EQ(b[4], 0x03);
  EXPECT_EQ(b[5], 0x02);
  EXPECT_EQ(b[15], 0xBF);  // -1.5 = 0xBFF8000000000000
  EXPECT_EQ(b[14], 0xF8);
  std::uint16_t id = 0;
  TopoNode m;
  ASSERT_TRUE(decode_map_node(Span<const std::uint8_t>(b, kMapNodeBytes), id, m).is_ok());
  EXPECT_EQ(id, 0x0203);
  EXPECT_EQ(m.position, n.position);
  EXPECT_EQ(m.heading_rad, 0.5);
  EXPECT_EQ(m.created, 9u);
  EXPECT_EQ(std::memcmp(m.signature.bins, n.signature.bins, sizeof n.signature.bins), 0);
  b[100] ^= 0x40;
  EXPECT_EQ(decode_map_node(Span<const std::uint8_t>(b, kMapNodeBytes), id, m).code(), StatusCode::kCorrupt);
  n.position.x() = std::nan("");
  EXPECT_EQ(encode_map_node(1, n, Span<std::uint8_t>(b, kMapNodeBytes)).code(), StatusCode::kInvalidArgument);

  ASSERT_TRUE(encode_map_edge(0x0102, 5, 300, Span<std::uint8_t>(b, kMapEdgeBytes)).is_ok());
  EXPECT_EQ(b[0], 0x02);
  EXPECT_EQ(b[1], 0x01);
  EXPECT_EQ(b[4], 300 & 0xFF);
  std::uint16_t a = 0, e = 0, age = 0;
  ASSERT_TRUE(decode_map_edge(Span<const std::uint8_t>(b, kMapEdgeBytes), a, e, age).is_ok());
  EXPECT_EQ(a, 0x0102);
  EXPECT_EQ(e, 5);
  EXPECT_EQ(age, 300);
  b[2] ^= 1;
  EXPECT_EQ(decode_map_edge(Span<const std::uint8_t>(b, kMapEdgeBytes), a, e, age).code(), StatusCode::kCorrupt);
}

}  // namespace
}  // namespace qnav::topo
