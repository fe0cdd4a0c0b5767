#include "firmware/tools/route_file.hpp"

#include <gtest/gtest.h>

#include "test/support/route_nodes.hpp"
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <string>
#include <vector>

namespace qnav::tools {
namespace {

using test::route_node;
route::RouteParams params(std::uint16_t max_kp = 8) { return test::route_params(max_kp); }
route::RouteNode node(std::uint32_t i, int kps) { return route_node(i, kps); }

std::string temp_path(const char* name) {
  const char* dir = std::getenv("TMPDIR");
  std::string p = std::string(dir ? dir : "/tmp") + "/qnav_route_" + std::to_string(::getpid()) + "_" + name;
  std::remove(p.c_str());
  return p;
}

std::uint64_t file_size(const std::string& p) {
  struct stat st {};
  return ::stat(p.c_str(), &st) == 0 ? static_cast<std::uint64_t>(st.st_size) : 0;
}

TEST(RouteFile, WriteThenReadEveryNode) {
  const std::string p = temp_path("rw.qroute");
  {
    RouteFileWriter w;
    ASSERT_TRUE(w.create(p.c_str(), params()).is_ok());
    for (std::uint32_t i = 0; i < 20; ++i) ASSERT_TRUE(w.append(node(i, static_cast<int>(i % 9))).is_ok());
    ASSERT_TRUE(w.close().is_ok());
  }
  EXPECT_EQ(file_size(p), route::kHeaderBytes + 20 * route::record_bytes(8) + route::kEndMarkBytes);  // closed: the end mark
  RouteFileReader r;
  ASSERT_TRUE(r.open(p.c_str()).is_ok());
  EXPECT_EQ(r.node_count(), 20u);
  EXPECT_EQ(r.torn_bytes(), 0u);
  EXPECT_EQ(r.params().sensor, route::SensorKind::kSideScan);
  route::RouteNode out;
  for (std::uint32_t i = 0; i < 20; ++i) {
    ASSERT_TRUE(r.load(i, out).is_ok());
    EXPECT_EQ(out.meta.index, i);
    EXPECT_EQ(out.keypoints.size(), i % 9);
    EXPECT_DOUBLE_EQ(out.meta.along_m, 30.0 * i);
  }
  EXPECT_EQ(r.load(20, out), StatusCode::kOutOfRange);
  std::remove(p.c_str());
}

TEST(RouteFile, CreateRefusesToOverwriteByDefault) {
  const std::string p = temp_path("exists.qroute");
  RouteFileWriter a, b;
  ASSERT_TRUE(a.create(p.c_str(), params()).is_ok());
  const Status s = b.create(p.c_str(), params());
  EXPECT_EQ(s, StatusCode::kInvalidArgument);  // the file exists: refused, the taught route untouched
  EXPECT_NE(std::string(s.message()).find("File exists"), std::string::npos) << s.message();
  std::remove(p.c_str());
}

TEST(RouteFile, TornTailIsReportedAndAppendResumesAfterTheLastGoodNode) {
  const std::string p = temp_path("torn.qroute");
  {
    RouteFileWriter w;
    ASSERT_TRUE(w.create(p.c_str(), params()).is_ok());
    for (std::uint32_t i = 0; i < 5; ++i) ASSERT_TRUE(w.append(node(i, 3)).is_ok());
  }
  // A power cut in the middle of record 5: half of it reached the disk.
  const std::size_t rec = route::record_bytes(8);
  ASSERT_EQ(::truncate(p.c_str(), static_cast<off_t>(route::kHeaderBytes + 5 * rec + rec / 2)), 0);
  {
    RouteFileReader r;
    ASSERT_TRUE(r.open(p.c_str()).is_ok());
    EXPECT_EQ(r.node_count(), 5u);
    EXPECT_EQ(r.torn_bytes(), rec / 2);
  }
  RouteFileWriter w;
  RouteAppendReport rep;
  ASSERT_TRUE(w.open_append(p.c_str(), &rep).is_ok());
  EXPECT_EQ(rep.nodes, 5u);
  EXPECT_EQ(rep.torn_bytes, rec / 2);
  ASSERT_TRUE(w.append(node(99, 2)).is_ok());  // becomes node 5
  ASSERT_TRUE(w.close().is_ok());
  RouteFileReader r;
  ASSERT_TRUE(r.open(p.c_str()).is_ok());
  EXPECT_EQ(r.node_count(), 6u);
  EXPECT_EQ(r.torn_bytes(), 0u);
  route::RouteNode out;
  ASSERT_TRUE(r.load(5, out).is_ok());
  EXPECT_EQ(out.meta.index, 5u);
  EXPECT_EQ(out.keypoints.size(), 2u);
  std::remove(p.c_str());
}

TEST(RouteFile, DamagedRecordIsReportedOthersStillRead) {
  const std::string p = temp_path("damaged.qroute");
  {
    RouteFileWriter w;
    ASSERT_TRUE(w.create(p.c_str(), params()).is_ok());
    for (std::uint32_t i = 0; i < 8; ++i) ASSERT_TRUE(w.append(node(i, 4)).is_ok());
  }
  const std::size_t rec = route::record_bytes(8);
  FILE* f = std::fopen(p.c_str(), "r+b");
  ASSERT_NE(f, nullptr);
  std::fseek(f, static_cast<long>(route::kHeaderBytes + 3 * rec + 60), SEEK_SET);
  std::fputc(0x5A, f);
  std::fclose(f);
  RouteFileReader r;
  ASSERT_TRUE(r.open(p.c_str()).is_ok());
  route::RouteNode out;
  EXPECT_EQ(r.load(3, out), StatusCode::kCorrupt);
  EXPECT_EQ(r.counters().get(route::RouteFormatCounter::kBadRecordCrc), 1u);
  EXPECT_TRUE(r.load(4, out).is_ok());
  std::vector<route::NodeMeta> meta;
  std::uint32_t bad = 0;
  EXPECT_EQ(r.read_all_meta(meta, &bad), StatusCode::kCorrupt);
  EXPECT_EQ(bad, 3u);
  std::remove(p.c_str());
}

TEST(RouteFile, CorruptHeaderAndNonRouteFilesAreRejected) {
  const std::string p = temp_path("junk.qroute");
  FILE* f = std::fopen(p.c_str(), "wb");
  ASSERT_NE(f, nullptr);
  for (int i = 0; i < 200; ++i) std::fputc(i, f);
  std::fclose(f);
  RouteFileReader r;
  EXPECT_EQ(r.open(p.c_str()), StatusCode::kCorrupt);
  const Status missing = r.open("/nonexistent/dir/x.qroute");
  EXPECT_EQ(missing, StatusCode::kNotFound);
  EXPECT_NE(std::string(missing.message()).find("No such file"), std::string::npos) << missing.message();  // the OS reason
  std::remove(p.c_str());
  f = std::fopen(p.c_str(), "wb");
  std::fputc('Q', f);
  std::fclose(f);
  EXPECT_EQ(r.open(p.c_str()), StatusCode::kTruncated);
  std::remove(p.c_str());
}

TEST(RouteFile, TenThousandNodeRouteReadsInFixedMemory) {
  const std::string p = temp_path("big.qroute");
  RouteWriterOptions o;
  o.sync_each_node = false;  // 10,000 fdatasyncs would dominate the test; durability is pinned above
  {
    RouteFileWriter w;
    ASSERT_TRUE(w.create(p.c_str(), params(2), o).is_ok());
    for (std::uint32_t i = 0; i < 10000; ++i) {
      route::RouteNode n = node(i, 2);
      for (route::RouteKeypoint& k : n.keypoints) k.y_m = static_cast<float>(i % 50);  // within a tile (y = i m is refused beyond 4.9 km)
      ASSERT_TRUE(w.append(n).is_ok());
    }
  }
  RouteFileReader r;
  ASSERT_TRUE(r.open(p.c_str()).is_ok());
  ASSERT_EQ(r.node_count(), 10000u);
  route::RouteNode out;
  for (std::uint32_t i : {0u, 4999u, 9999u, 17u}) {
    ASSERT_TRUE(r.load(i, out).is_ok());
    EXPECT_EQ(out.meta.index, i);
  }
  std::remove(p.c_str());
}


// Issue 19: --force truncated the old route before the new one held a node. A replacement is taught
// next to the target and renamed over it only when complete; until then the old route is whole.
TEST(RouteFile, ReplacementOnDiskKeepsTheOldRouteUntilCommit) {
  const std::string p = temp_path("replace.qroute");
  std::remove((p + ".new").c_str());
  {
    RouteFileWriter w;
    ASSERT_TRUE(w.create(p.c_str(), params()).is_ok());
    for (std::uint32_t i = 0; i < 6; ++i) ASSERT_TRUE(w.append(node(i, 2)).is_ok());
    ASSERT_TRUE(w.close().is_ok());
  }
  const std::uint64_t old_size = file_size(p);
  EXPECT_EQ(old_size, route::kHeaderBytes + 6 * route::record_bytes(8) + route::kEndMarkBytes);
  RouteFileWriter w;
  RouteWriterOptions o;
  EXPECT_EQ(w.create_replacement(p.c_str(), params(), o), StatusCode::kInvalidArgument);
  o.replace_existing = true;
  ASSERT_TRUE(w.create_replacement(p.c_str(), params(), o).is_ok());
  EXPECT_EQ(std::string(w.path()), p + ".new");
  for (std::uint32_t i = 0; i < 3; ++i) ASSERT_TRUE(w.append(node(i, 7)).is_ok());
  EXPECT_EQ(file_size(p), old_size) << "the old route is untouched while the new one is taught";
  EXPECT_EQ(file_size(p + ".new"), route::kHeaderBytes + 3 * route::record_bytes(8));
  {
    RouteFileReader r;
    ASSERT_TRUE(r.open(p.c_str()).is_ok());
    EXPECT_TRUE(r.closed_cleanly());
    EXPECT_EQ(r.node_count(), 6u);
  }
  ASSERT_TRUE(w.commit().is_ok());
  EXPECT_EQ(file_size(p + ".new"), 0u) << "renamed, not copied";
  RouteFileReader r;
  ASSERT_TRUE(r.open(p.c_str()).is_ok());
  EXPECT_TRUE(r.closed_cleanly());
  EXPECT_EQ(r.node_count(), 3u);
  route::RouteNode out;
  ASSERT_TRUE(r.load(2, out).is_ok());
  EXPECT_EQ(out.keypoints.size(), 7u);
  std::remove(p.c_str());
}

TEST(RouteFile, ACutOffRouteOnDiskIsToldApartFromAClosedOne) {
  const std::string p = temp_path("cut.qroute");
  {
    RouteFileWriter w;
    ASSERT_TRUE(w.create(p.c_str(), params()).is_ok());
    for (std::uint32_t i = 0; i < 4; ++i) ASSERT_TRUE(w.append(node(i, 2)).is_ok());
  }  // destroyed without close(): a killed teach
  RouteFileReader r;
  ASSERT_TRUE(r.open(p.c_str()).is_ok());
  EXPECT_EQ(r.end(), RouteEnd::kCutOff);
  EXPECT_EQ(r.node_count(), 4u);
  r.close();
  RouteFileWriter w;
  RouteAppendReport rep;
  ASSERT_TRUE(w.open_append(p.c_str(), &rep).is_ok());
  EXPECT_FALSE(rep.end_mark_cut);
  ASSERT_TRUE(w.close().is_ok());
  ASSERT_TRUE(r.open(p.c_str()).is_ok());
  EXPECT_EQ(r.end(), RouteEnd::kClosedCleanly);
  EXPECT_EQ(r.end_mark_nodes(), 4u);
  std::remove(p.c_str());
}

}  // namespace
}  // namespace qnav::tools
