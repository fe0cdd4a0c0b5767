// The topological map file (firmware/tools/map_file on a hal::FileStore, format nav/topo/map_format):
// a map saved and loaded is the same map (nodes, edges, path costs); a damaged file (header, node or
// edge bytes, truncated, trailing bytes, foreign file, too big for the map) is refused with a status
// naming the check and the map left empty; saving replaces the previous file atomically.
#include "firmware/tools/map_file.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "hal/sim/memory_file_store.hpp"
#include "nav/topo/topo_map.hpp"
#include "test/support/alloc_guard.hpp"

namespace qnav::tools {
namespace {

using topo::kSignatureBins;
using topo::PlaceSignature;
using topo::TopoMap;
using topo::TopoMapConfig;

PlaceSignature place(int id) {
  PlaceSignature s;
  for (int i = 0; i < kSignatureBins; ++i) s.bins[i] = 0.5f / kSignatureBins;
  s.bins[(id * 7) % kSignatureBins] += 0.25f;
  s.bins[(id * 13 + 5) % kSignatureBins] += 0.25f;
  s.words = 100;
  return s;
}

TopoMapConfig config(std::size_t max_nodes = 64) {
  TopoMapConfig c;
  c.max_nodes = max_nodes;
  c.node_spacing = 1.0;
  c.gate = 1.5;
  c.max_edge_length = 3.0;
  c.max_edge_age = 4;
  return c;
}

struct Map {
  std::vector<std::byte> block;
  Arena arena;
  TopoMap map;
  explicit Map(const TopoMapConfig& c) : block(TopoMap::arena_bytes(c)), arena(Span<std::byte>(block.data(), block.size())) {
    EXPECT_TRUE(map.init(c, arena).is_ok());
  }
};

// A lawnmower with a return leg: a mesh with crossings, aged and pruned edges, revisits.
void build(TopoMap& m) {
  topo::ObserveResult r;
  for (int row = 0; row < 4; ++row)
    for (int j = 0; j < 6; ++j) {
      const int col = row % 2 ? 5 - j : j;
      ASSERT_TRUE(m.observe(place(row * 6 + col), Vec2d(1.5 * col, 1.5 * row), 0.1 * col, r).is_ok());
    }
  for (int row = 3; row >= 0; --row) ASSERT_TRUE(m.observe(place(row * 6 + 2), Vec2d(3.0, 1.5 * row), 0.0, r).is_ok());
}

void expect_same(const TopoMap& a, const TopoMap& b) {
  ASSERT_EQ(a.node_count(), b.node_count());
  ASSERT_EQ(a.edge_count(), b.edge_count());
  EXPECT_EQ(a.observations(), b.observations());
  EXPECT_EQ(a.revisits(), b.revisits());
  for (std::uint16_t i = 0; i < a.capacity(); ++i) {
    ASSERT_EQ(a.active(i), b.active(i));
    if (!a.active(i)) continue;
    EXPECT_EQ(a.node(i).position, b.node(i).position);
    EXPECT_FLOAT_EQ(static_cast<float>(a.node(i).heading_rad), static_cast<float>(b.node(i).heading_rad));
    EXPECT_EQ(a.node(i).visits, b.node(i).visits);
    EXPECT_EQ(a.node(i).edge_count, b.node(i).edge_count);
    EXPECT_EQ(std::memcmp(a.node(i).signature.bins, b.node(i).signature.bins, sizeof a.node(i).signature.bins), 0);
  }
}

TEST(MapFile, SavedAndLoadedIsTheSameMap) {
  std::vector<std::uint8_t> storage(1 << 20);
  hal::MemoryFileStore store(Span<std::uint8_t>(storage.data(), storage.size()));
  Map a(config());
  build(a.map);
  ASSERT_GT(a.map.revisits(), 0u);
  ASSERT_TRUE(save_map(store, "m.qmap", a.map, true).is_ok());
  EXPECT_FALSE(store.exists("m.qmap.tmp"));
  Map b(config());
  MapFileInfo info;
  {
    qnav::test::AllocationGuard guard;
    const Status s = load_map(store, "m.qmap", b.map, &info);
    ASSERT_TRUE(s.is_ok()) << s.message();
    EXPECT_EQ(guard.allocations(), 0u);
  }
  EXPECT_TRUE(info.metric);
  expect_same(a.map, b.map);
  std::uint16_t pa[64], pb[64];
  const topo::PathResult ra = a.map.dijkstra(0, 23, Span<std::uint16_t>(pa, 64));
  const topo::PathResult rb = b.map.astar(0, 23, Span<std::uint16_t>(pb, 64));
  ASSERT_EQ(ra.status, topo::PathStatus::kFound);
  ASSERT_EQ(rb.status, topo::PathStatus::kFound);
  EXPECT_NEAR(ra.cost, rb.cost, 1e-9);
  // Saving again replaces the file (the same bytes for the same map).
  ASSERT_TRUE(save_map(store, "m.qmap", b.map, true).is_ok());
  Map c(config());
  ASSERT_TRUE(load_map(store, "m.qmap", c.map, nullptr).is_ok());
  expect_same(a.map, c.map);
}

std::uint64_t file_size(hal::FileStore& s, const char* path) {
  Result<int> fd = s.open(path, hal::FileMode::kRead);
  const std::uint64_t n = fd ? *s.size(*fd) : 0;
  if (fd) s.close(*fd);
  return n;
}

void poke(hal::FileStore& s, const char* path, std::uint64_t at, std::uint8_t x) {
  Result<int> fd = s.open(path, hal::FileMode::kReadWrite);
  ASSERT_TRUE(fd.is_ok());
  std::uint8_t b = 0;
  ASSERT_TRUE(s.read_at(*fd, &b, 1, at).is_ok());
  b ^= x;
  ASSERT_TRUE(s.write_at(*fd, &b, 1, at).is_ok());
  s.close(*fd);
}

TEST(MapFile, DamagedFilesAreRefusedWithTheirReasonAndTheMapLeftEmpty) {
  std::vector<std::uint8_t> storage(1 << 20);
  hal::MemoryFileStore store(Span<std::uint8_t>(storage.data(), storage.size()));
  Map a(config());
  build(a.map);
  ASSERT_TRUE(save_map(store, "good", a.map, false).is_ok());
  const std::uint64_t size = file_size(store, "good");
  ASSERT_EQ(size, topo::map_file_bytes(a.map.node_count(), a.map.edge_count()));
  struct Case {
    const char* what;
    std::uint64_t at;  // byte to flip; or ~0 for a length change
    long resize;       // bytes added (+) or cut (-)
    StatusCode code;
    const char* says;
  };
  const std::uint64_t node0 = topo::kMapHeaderBytes, edge0 = topo::kMapHeaderBytes + a.map.node_count() * topo::kMapNodeBytes;
  const Case cases[] = {
      {"magic", 0, 0, StatusCode::kCorrupt, "bad magic"},
      {"header field", 21, 0, StatusCode::kCorrupt, "header CRC"},
      {"node position", node0 + 9, 0, StatusCode::kCorrupt, "node record CRC"},
      {"node signature", node0 + 3 * topo::kMapNodeBytes + 100, 0, StatusCode::kCorrupt, "node record CRC"},
      {"edge", edge0 + 1, 0, StatusCode::kCorrupt, "edge record CRC"},
      {"last edge crc", size - 1, 0, StatusCode::kCorrupt, "edge record CRC"},
      {"cut", ~0ull, -5, StatusCode::kTruncated, "shorter"},
      {"cut into header", ~0ull, -static_cast<long>(size) + 10, StatusCode::kTruncated, "shorter than its header"},
      {"trailing", ~0ull, 7, StatusCode::kCorrupt, "bytes after"},
  };
  std::vector<std::uint8_t> bytes(size);
  {
    Result<int> fd = store.open("good", hal::FileMode::kRead);
    ASSERT_TRUE(store.read_at(*fd, bytes.data(), size, 0).is_ok());
    store.close(*fd);
  }
  for (const Case& c : cases) {
    Result<int> fd = store.open("bad", hal::FileMode::kCreateOrTruncate);
    ASSERT_TRUE(fd.is_ok());
    const std::uint64_t n = c.at == ~0ull ? static_cast<std::uint64_t>(static_cast<long>(size) + c.resize) : size;
    std::vector<std::uint8_t> b(bytes);
    b.resize(n, 0xAB);
    ASSERT_TRUE(store.write_at(*fd, b.data(), n, 0).is_ok());
    store.close(*fd);
    if (c.at != ~0ull) poke(store, "bad", c.at, 0x10);
    Map m(config());
    build(m.map);  // a map with content: a refused load must leave it empty, not half-loaded
    const Status s = load_map(store, "bad", m.map, nullptr);
    EXPECT_EQ(s.code(), c.code) << c.what << ": " << s.message();
    EXPECT_NE(std::strstr(s.message(), c.says), nullptr) << c.what << ": " << s.message();
    EXPECT_EQ(m.map.node_count(), 0u) << c.what;
  }
  // A file with more nodes than the map holds.
  Map small(config(8));
  const Status s = load_map(store, "good", small.map, nullptr);
  EXPECT_EQ(s.code(), StatusCode::kCapacityExceeded) << s.message();
  EXPECT_EQ(small.map.node_count(), 0u);
  // Missing file.
  EXPECT_EQ(load_map(store, "none", small.map, nullptr).code(), StatusCode::kNotFound);
}

TEST(MapFile, HostFileSystemRoundTripLeavesNoTemporary) {
  char dir[] = "/tmp/qnav_map_file_XXXXXX";
  ASSERT_NE(mkdtemp(dir), nullptr);
  const std::string path = std::string(dir) + "/map.qmap";
  Map a(config());
  build(a.map);
  ASSERT_TRUE(save_map(path.c_str(), a.map, false).is_ok());
  ASSERT_TRUE(save_map(path.c_str(), a.map, false).is_ok());  // over an existing map
  EXPECT_NE(access(path.c_str(), F_OK), -1);
  EXPECT_EQ(access((path + ".tmp").c_str(), F_OK), -1);
  Map b(config());
  ASSERT_TRUE(load_map(path.c_str(), b.map, nullptr).is_ok());
  expect_same(a.map, b.map);
  std::remove(path.c_str());
  rmdir(dir);
}

}  // namespace
}  // namespace qnav::tools
