// The route store on hal/sim's MemoryFileStore: the code path a LEON build (no OS, big-endian) runs.
// Same behaviour as on the host's file system (test/unit/firmware/tools/route_file_test.cpp): every
// node back, a torn tail reported and cut, a damaged record named, commit by rename replacing the old
// route only when the new one is complete, a failing medium reported (never half-written records
// read back as good), no heap once the buffers are reserved.
#include "drivers/route_store/route_file.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <memory>
#include <vector>

#include "hal/sim/memory_file_store.hpp"
#include "test/support/alloc_guard.hpp"
#include "test/support/route_nodes.hpp"

namespace qnav::drivers::route_store {
namespace {

using test::route_node;
route::RouteParams params(std::uint16_t max_kp = 8) { return test::route_params(max_kp); }
route::RouteNode node(std::uint32_t i, int kps) { return route_node(i, kps); }

struct Store {
  std::vector<std::uint8_t> mem = std::vector<std::uint8_t>(8 * 64 * 1024);
  hal::MemoryFileStore fs{Span<std::uint8_t>(mem.data(), mem.size())};
};

TEST(RouteStoreMemory, WriteThenReadEveryNode) {
  auto s = std::make_unique<Store>();
  RouteFileWriter w(s->fs);
  ASSERT_TRUE(w.create("r.qroute", params()));
  for (std::uint32_t i = 0; i < 20; ++i) ASSERT_TRUE(w.append(node(i, static_cast<int>(i % 9))));
  ASSERT_TRUE(w.close());
  RouteFileReader r(s->fs);
  ASSERT_TRUE(r.open("r.qroute"));
  EXPECT_EQ(r.node_count(), 20u);
  EXPECT_EQ(r.torn_bytes(), 0u);
  route::RouteNode out;
  for (std::uint32_t i = 0; i < 20; ++i) {
    ASSERT_TRUE(r.load(i, out));
    EXPECT_EQ(out.meta.index, i);
    EXPECT_EQ(out.keypoints.size(), i % 9);
    EXPECT_DOUBLE_EQ(out.meta.along_m, 30.0 * i);
  }
  EXPECT_EQ(r.load(20, out), StatusCode::kOutOfRange);
  RouteFileReader missing(s->fs);
  EXPECT_EQ(missing.open("none.qroute"), StatusCode::kNotFound);
}

TEST(RouteStoreMemory, TornTailIsCutAndAppendResumes) {
  auto s = std::make_unique<Store>();
  {
    RouteFileWriter w(s->fs);
    ASSERT_TRUE(w.create("t.qroute", params()));
    for (std::uint32_t i = 0; i < 6; ++i) ASSERT_TRUE(w.append(node(i, 3)));
    ASSERT_TRUE(w.close());
  }
  // A power cut in the middle of node 6: half a record on the medium.
  Result<int> h = s->fs.open("t.qroute", hal::FileMode::kReadWrite);
  ASSERT_TRUE(h);
  std::vector<std::uint8_t> half(route::record_bytes(8) / 2, 0xAB);
  ASSERT_TRUE(s->fs.write_at(*h, half.data(), half.size(), route::kHeaderBytes + 6 * route::record_bytes(8)));
  s->fs.close(*h);
  RouteFileReader r(s->fs);
  ASSERT_TRUE(r.open("t.qroute"));
  EXPECT_EQ(r.node_count(), 6u);
  EXPECT_EQ(r.torn_bytes(), half.size());
  r.close();
  RouteFileWriter w(s->fs);
  RouteAppendReport rep;
  ASSERT_TRUE(w.open_append("t.qroute", &rep));
  EXPECT_EQ(rep.nodes, 6u);
  EXPECT_EQ(rep.torn_bytes, half.size());
  ASSERT_TRUE(w.append(node(6, 2)));
  ASSERT_TRUE(w.close());
  ASSERT_TRUE(r.open("t.qroute"));
  EXPECT_EQ(r.node_count(), 7u);
  EXPECT_EQ(r.torn_bytes(), 0u);
}

TEST(RouteStoreMemory, DamagedRecordIsNamed) {
  auto s = std::make_unique<Store>();
  RouteFileWriter w(s->fs);
  ASSERT_TRUE(w.create("d.qroute", params()));
  for (std::uint32_t i = 0; i < 8; ++i) ASSERT_TRUE(w.append(node(i, 4)));
  ASSERT_TRUE(w.close());
  Result<int> h = s->fs.open("d.qroute", hal::FileMode::kReadWrite);
  ASSERT_TRUE(h);
  const std::uint8_t flip = 0x5A;
  ASSERT_TRUE(s->fs.write_at(*h, &flip, 1, route::kHeaderBytes + 5 * route::record_bytes(8) + 20));
  s->fs.close(*h);
  RouteFileReader r(s->fs);
  ASSERT_TRUE(r.open("d.qroute"));
  std::vector<route::NodeMeta> meta;
  std::uint32_t bad = 0;
  EXPECT_EQ(r.read_all_meta(meta, &bad), StatusCode::kCorrupt);
  EXPECT_EQ(bad, 5u);
  route::RouteNode out;
  EXPECT_TRUE(r.load(4, out));
  EXPECT_TRUE(r.load(6, out));
}

TEST(RouteStoreMemory, CommitReplacesTheOldRouteOnlyWhenComplete) {
  auto s = std::make_unique<Store>();
  {
    RouteFileWriter w(s->fs);
    ASSERT_TRUE(w.create("route_1.qroute", params()));
    for (std::uint32_t i = 0; i < 3; ++i) ASSERT_TRUE(w.append(node(i, 2)));
    ASSERT_TRUE(w.close());
  }
  RouteFileWriter w(s->fs);
  ASSERT_TRUE(w.create("route_1.qroute.new", params()));
  for (std::uint32_t i = 0; i < 9; ++i) ASSERT_TRUE(w.append(node(i, 2)));
  RouteFileReader r(s->fs);
  ASSERT_TRUE(r.open("route_1.qroute"));
  EXPECT_EQ(r.node_count(), 3u) << "the old route stays while the new one is taught";
  r.close();
  ASSERT_TRUE(w.commit_as("route_1.qroute"));
  ASSERT_TRUE(r.open("route_1.qroute"));
  EXPECT_EQ(r.node_count(), 9u);
  EXPECT_FALSE(s->fs.exists("route_1.qroute.new"));
}

TEST(RouteStoreMemory, AFailingMediumIsReportedAndNothingHalfWrittenReadsAsGood) {
  auto s = std::make_unique<Store>();
  RouteFileWriter w(s->fs);
  ASSERT_TRUE(w.create("f.qroute", params()));
  for (std::uint32_t i = 0; i < 4; ++i) ASSERT_TRUE(w.append(node(i, 2)));
  s->fs.fail_writes_after(route::record_bytes(8) / 2);
  EXPECT_EQ(w.append(node(4, 2)), StatusCode::kIoError);
  EXPECT_EQ(w.node_count(), 4u);
  static_cast<void>(w.close());
  RouteFileReader r(s->fs);
  ASSERT_TRUE(r.open("f.qroute"));
  EXPECT_EQ(r.node_count(), 4u);
  std::vector<route::NodeMeta> meta;
  std::uint32_t bad = 0;
  EXPECT_TRUE(r.read_all_meta(meta, &bad));
}

TEST(RouteStoreMemory, NoHeapOnceReserved) {
  auto s = std::make_unique<Store>();
  RouteFileWriter w(s->fs);
  RouteFileReader r(s->fs);
  w.reserve(route::record_bytes(route::kMaxKeypointsPerNode));
  r.reserve(route::record_bytes(route::kMaxKeypointsPerNode));
  std::vector<route::NodeMeta> meta;
  meta.reserve(16);
  const route::RouteNode n = node(0, 5);
  QNAV_EXPECT_NO_ALLOC({
    ASSERT_TRUE(w.create("h.qroute", params()));
    for (int i = 0; i < 10; ++i) ASSERT_TRUE(w.append(n));
    ASSERT_TRUE(w.commit_as("h2.qroute"));
    ASSERT_TRUE(r.open("h2.qroute"));
    std::uint32_t bad = 0;
    ASSERT_TRUE(r.read_all_meta(meta, &bad));
  });
  EXPECT_EQ(meta.size(), 10u);
}

}  // namespace
}  // namespace qnav::drivers::route_store
