// What a reader can tell about a route after a crash, a close or a replacement (issue 19), on hal/sim's
// MemoryFileStore (the LEON code path; the host's files: test/unit/firmware/tools/route_file_test.cpp):
//  - close() appends the end mark; a writer killed (destroyed) or abandon()ed leaves none, so a cut-off
//    route is told apart from a complete one; a mark whose count disagrees is reported;
//  - open_append() cuts the end mark (or a torn tail) off durably before anything is appended, and says so;
//  - version 1 files (no end mark) are read and reported as such;
//  - create_replacement() never touches the old route before commit(), keeps a previous run's leftover;
//  - a node with non-finite or absurd fields is never written; a medium failing in the middle of a
//    record leaves the route valid up to the last durable node;
//  - a damaged node is named and the good prefix before it stays usable (limit_nodes);
//  - the one route-open policy for repeating (open_route_for_repeat, qnavd and the tool).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <vector>

#include "drivers/route_store/route_file.hpp"
#include "drivers/route_store/route_open.hpp"
#include "hal/sim/memory_file_store.hpp"
#include "nav/core/byte_order.hpp"
#include "nav/core/crc.hpp"
#include "test/support/route_nodes.hpp"

namespace qnav::drivers::route_store {
namespace {

using test::route_node;
route::RouteParams params(std::uint16_t max_kp = 8) { return test::route_params(max_kp); }
route::RouteNode node(std::uint32_t i, int kps) { return route_node(i, kps); }
const std::size_t kRec = route::record_bytes(8);

struct Store {
  std::vector<std::uint8_t> mem = std::vector<std::uint8_t>(8 * 64 * 1024);
  hal::MemoryFileStore fs{Span<std::uint8_t>(mem.data(), mem.size())};

  std::uint64_t size_of(const char* path) {
    Result<int> h = fs.open(path, hal::FileMode::kRead);
    if (!h) return 0;
    const std::uint64_t n = *fs.size(*h);
    fs.close(*h);
    return n;
  }
  void write(const char* path, const std::uint8_t* data, std::size_t n, std::uint64_t at) {
    Result<int> h = fs.open(path, hal::FileMode::kReadWrite);
    ASSERT_TRUE(h);
    ASSERT_TRUE(fs.write_at(*h, data, n, at));
    fs.close(*h);
  }
  void read(const char* path, std::uint8_t* data, std::size_t n, std::uint64_t at) {
    Result<int> h = fs.open(path, hal::FileMode::kRead);
    ASSERT_TRUE(h);
    ASSERT_TRUE(fs.read_at(*h, data, n, at));
    fs.close(*h);
  }
  void cut(const char* path, std::uint64_t size) {
    Result<int> h = fs.open(path, hal::FileMode::kReadWrite);
    ASSERT_TRUE(h);
    ASSERT_TRUE(fs.truncate(*h, size));
    fs.close(*h);
  }
};

void teach(Store& s, const char* path, std::uint32_t nodes, bool close, int kps = 3) {
  RouteFileWriter w(s.fs);
  ASSERT_TRUE(w.create(path, params()));
  for (std::uint32_t i = 0; i < nodes; ++i) ASSERT_TRUE(w.append(node(i, kps)));
  if (close) {
    ASSERT_TRUE(w.close());
  }
}  // without close: destroyed like a killed process (no end mark)

void expect_all_nodes_decode(RouteFileReader& r, int kps = 3) {
  route::RouteNode out;
  for (std::uint32_t i = 0; i < r.node_count(); ++i) {
    ASSERT_TRUE(r.load(i, out)) << "node " << i;
    EXPECT_EQ(out.meta.index, i);
    EXPECT_EQ(out.keypoints.size(), static_cast<std::size_t>(kps));
  }
}

TEST(RouteStoreDurability, ClosedRouteIsToldApartFromACutOffOne) {
  auto s = std::make_unique<Store>();
  teach(*s, "closed.qroute", 5, true);
  teach(*s, "killed.qroute", 5, false);
  EXPECT_EQ(s->size_of("closed.qroute"), route::kHeaderBytes + 5 * kRec + route::kEndMarkBytes);
  EXPECT_EQ(s->size_of("killed.qroute"), route::kHeaderBytes + 5 * kRec);
  RouteFileReader r(s->fs);
  ASSERT_TRUE(r.open("closed.qroute"));
  EXPECT_TRUE(r.closed_cleanly());
  EXPECT_EQ(r.end(), RouteEnd::kClosedCleanly);
  EXPECT_EQ(r.end_mark_nodes(), 5u);
  EXPECT_EQ(r.node_count(), 5u);
  EXPECT_EQ(r.torn_bytes(), 0u) << "the end mark is not a torn tail";
  EXPECT_EQ(r.format_version(), 2u);
  EXPECT_EQ(r.counters().total(), 0u);
  expect_all_nodes_decode(r);
  RouteFileReader k(s->fs);
  ASSERT_TRUE(k.open("killed.qroute"));
  EXPECT_FALSE(k.closed_cleanly());
  EXPECT_EQ(k.end(), RouteEnd::kCutOff);
  EXPECT_EQ(k.node_count(), 5u) << "every durable node of a cut-off route stays usable";
  EXPECT_EQ(k.counters().get(route::RouteFormatCounter::kNoEndMark), 1u);
  expect_all_nodes_decode(k);
}

TEST(RouteStoreDurability, AbandonLeavesNoEndMark) {
  auto s = std::make_unique<Store>();
  RouteFileWriter w(s->fs);
  ASSERT_TRUE(w.create("a.qroute", params()));
  ASSERT_TRUE(w.append(node(0, 1)));
  ASSERT_TRUE(w.abandon());
  RouteFileReader r(s->fs);
  ASSERT_TRUE(r.open("a.qroute"));
  EXPECT_EQ(r.end(), RouteEnd::kCutOff);
  EXPECT_EQ(r.node_count(), 1u);
}

TEST(RouteStoreDurability, EndMarkWithTheWrongCountIsReported) {
  auto s = std::make_unique<Store>();
  teach(*s, "m.qroute", 4, false);
  std::uint8_t mark[route::kEndMarkBytes];
  ASSERT_TRUE(route::encode_end_mark(7, Span<std::uint8_t>(mark)));
  s->write("m.qroute", mark, sizeof mark, route::kHeaderBytes + 4 * kRec);
  RouteFileReader r(s->fs);
  ASSERT_TRUE(r.open("m.qroute"));
  EXPECT_EQ(r.end(), RouteEnd::kCountMismatch);
  EXPECT_FALSE(r.closed_cleanly());
  EXPECT_EQ(r.end_mark_nodes(), 7u);
  EXPECT_EQ(r.node_count(), 4u);
  EXPECT_EQ(r.counters().get(route::RouteFormatCounter::kBadEndMark), 1u);
}

TEST(RouteStoreDurability, DamagedOrTornEndMarkReadsAsATornTail) {
  auto s = std::make_unique<Store>();
  teach(*s, "t.qroute", 3, true);
  std::uint8_t b = 0;
  s->read("t.qroute", &b, 1, route::kHeaderBytes + 3 * kRec + 5);
  b ^= 0x40;
  s->write("t.qroute", &b, 1, route::kHeaderBytes + 3 * kRec + 5);
  RouteFileReader r(s->fs);
  ASSERT_TRUE(r.open("t.qroute"));
  EXPECT_EQ(r.end(), RouteEnd::kCutOff);
  EXPECT_EQ(r.torn_bytes(), route::kEndMarkBytes);
  EXPECT_EQ(r.counters().get(route::RouteFormatCounter::kBadEndMark), 1u);
  EXPECT_EQ(r.counters().get(route::RouteFormatCounter::kTornTail), 1u);
  r.close();
  s->cut("t.qroute", route::kHeaderBytes + 3 * kRec + 9);  // a power cut while the mark was written
  ASSERT_TRUE(r.open("t.qroute"));
  EXPECT_EQ(r.end(), RouteEnd::kCutOff);
  EXPECT_EQ(r.torn_bytes(), 9u);
  EXPECT_EQ(r.node_count(), 3u);
}

TEST(RouteStoreDurability, OpenAppendCutsTheEndMarkBeforeTheFirstAppendAndSaysSo) {
  auto s = std::make_unique<Store>();
  teach(*s, "r.qroute", 5, true);
  {
    RouteFileWriter w(s->fs);
    RouteAppendReport rep;
    ASSERT_TRUE(w.open_append("r.qroute", &rep));
    EXPECT_EQ(rep.nodes, 5u);
    EXPECT_TRUE(rep.end_mark_cut);
    EXPECT_EQ(rep.torn_bytes, 0u);
    EXPECT_EQ(rep.version, 2u);
  }  // killed now, before anything was appended
  {
    RouteFileReader r(s->fs);
    ASSERT_TRUE(r.open("r.qroute"));
    EXPECT_EQ(r.end(), RouteEnd::kCutOff) << "a reopened route must not claim to be complete";
    EXPECT_EQ(r.node_count(), 5u);
  }
  RouteFileWriter w(s->fs);
  RouteAppendReport rep;
  ASSERT_TRUE(w.open_append("r.qroute", &rep));
  EXPECT_FALSE(rep.end_mark_cut);
  ASSERT_TRUE(w.append(node(5, 3)));
  ASSERT_TRUE(w.close());
  RouteFileReader r(s->fs);
  ASSERT_TRUE(r.open("r.qroute"));
  EXPECT_TRUE(r.closed_cleanly());
  EXPECT_EQ(r.end_mark_nodes(), 6u);
  expect_all_nodes_decode(r);
}

TEST(RouteStoreDurability, OpenAppendReportsTheTornTailItCuts) {
  auto s = std::make_unique<Store>();
  teach(*s, "torn.qroute", 4, false);
  std::vector<std::uint8_t> part(kRec / 3, 0x11);
  s->write("torn.qroute", part.data(), part.size(), route::kHeaderBytes + 4 * kRec);
  {
    RouteFileWriter w(s->fs);
    RouteAppendReport rep;
    ASSERT_TRUE(w.open_append("torn.qroute", &rep));
    EXPECT_EQ(rep.nodes, 4u);
    EXPECT_EQ(rep.torn_bytes, part.size());
    EXPECT_FALSE(rep.end_mark_cut);
  }  // killed before the first append: the tail is already cut
  EXPECT_EQ(s->size_of("torn.qroute"), route::kHeaderBytes + 4 * kRec);
  RouteFileWriter w(s->fs);
  RouteAppendReport rep;
  ASSERT_TRUE(w.open_append("torn.qroute", &rep));
  EXPECT_EQ(rep.torn_bytes, 0u);
  ASSERT_TRUE(w.append(node(4, 3)));
  ASSERT_TRUE(w.close());
  RouteFileReader r(s->fs);
  ASSERT_TRUE(r.open("torn.qroute"));
  EXPECT_TRUE(r.closed_cleanly());
  EXPECT_EQ(r.node_count(), 5u);
  expect_all_nodes_decode(r);
}

TEST(RouteStoreDurability, OpenAppendRefusesADamagedLastNodeAndSaysWhich) {
  auto s = std::make_unique<Store>();
  teach(*s, "d.qroute", 4, true);
  const std::uint8_t flip = 0x77;
  s->write("d.qroute", &flip, 1, route::kHeaderBytes + 3 * kRec + 60);
  RouteFileWriter w(s->fs);
  RouteAppendReport rep;
  EXPECT_EQ(w.open_append("d.qroute", &rep), StatusCode::kCorrupt);
  EXPECT_TRUE(rep.damaged);
  EXPECT_EQ(rep.nodes, 4u);  // the damaged node is rep.nodes - 1
  EXPECT_EQ(s->size_of("d.qroute"), route::kHeaderBytes + 4 * kRec + route::kEndMarkBytes) << "nothing cut or written";
}

// A version-1 route (written before end marks): the same records, read and reported as such.
TEST(RouteStoreDurability, Version1RoutesAreReadAndReportedWithoutAnEndMarker) {
  auto s = std::make_unique<Store>();
  teach(*s, "v1.qroute", 3, false);
  std::uint8_t h[route::kHeaderBytes];
  s->read("v1.qroute", h, sizeof h, 0);
  store_le_u16(h + 8, 1);
  store_le_u32(h + 60, crc32(h, 60));
  s->write("v1.qroute", h, sizeof h, 0);
  RouteFileReader r(s->fs);
  ASSERT_TRUE(r.open("v1.qroute"));
  EXPECT_EQ(r.format_version(), 1u);
  EXPECT_EQ(r.end(), RouteEnd::kNoEndMarkV1);
  EXPECT_FALSE(r.closed_cleanly());
  expect_all_nodes_decode(r);
  r.close();
  // Appending to it keeps version 1 and closes it with an end mark.
  RouteFileWriter w(s->fs);
  RouteAppendReport rep;
  ASSERT_TRUE(w.open_append("v1.qroute", &rep));
  EXPECT_EQ(rep.version, 1u);
  ASSERT_TRUE(w.append(node(3, 3)));
  ASSERT_TRUE(w.close());
  ASSERT_TRUE(r.open("v1.qroute"));
  EXPECT_EQ(r.format_version(), 1u);
  EXPECT_TRUE(r.closed_cleanly());
  EXPECT_EQ(r.node_count(), 4u);
}

TEST(RouteStoreDurability, ReplacementLeavesTheOldRouteWholeUntilCommit) {
  auto s = std::make_unique<Store>();
  teach(*s, "route.qroute", 3, true, 2);
  RouteFileWriter w(s->fs);
  EXPECT_EQ(w.create_replacement("route.qroute", params()), StatusCode::kInvalidArgument) << "an existing route is never replaced implicitly";
  RouteWriterOptions o;
  o.replace_existing = true;
  RouteReplaceReport rep;
  ASSERT_TRUE(w.create_replacement("route.qroute", params(), o, &rep));
  EXPECT_STREQ(rep.temp_path, "route.qroute.new");
  EXPECT_STREQ(w.path(), "route.qroute.new");
  EXPECT_FALSE(rep.previous_kept);
  for (std::uint32_t i = 0; i < 9; ++i) {
    ASSERT_TRUE(w.append(node(i, 5)));
    RouteFileReader r(s->fs);  // at every step the old route is intact and complete
    ASSERT_TRUE(r.open("route.qroute"));
    EXPECT_TRUE(r.closed_cleanly());
    EXPECT_EQ(r.node_count(), 3u);
    expect_all_nodes_decode(r, 2);
  }
  ASSERT_TRUE(w.commit());
  RouteFileReader r(s->fs);
  ASSERT_TRUE(r.open("route.qroute"));
  EXPECT_TRUE(r.closed_cleanly());
  EXPECT_EQ(r.node_count(), 9u);
  expect_all_nodes_decode(r, 5);
  EXPECT_FALSE(s->fs.exists("route.qroute.new"));
}

TEST(RouteStoreDurability, ReplacementKeepsAPreviousRunsLeftoverAndAKilledOneChangesNothing) {
  auto s = std::make_unique<Store>();
  teach(*s, "route.qroute", 3, true, 2);
  RouteWriterOptions o;
  o.replace_existing = true;
  {
    RouteFileWriter w(s->fs);  // killed after 2 nodes: destroyed without commit
    ASSERT_TRUE(w.create_replacement("route.qroute", params(), o));
    ASSERT_TRUE(w.append(node(0, 4)));
    ASSERT_TRUE(w.append(node(1, 4)));
  }
  RouteFileReader r(s->fs);
  ASSERT_TRUE(r.open("route.qroute"));
  EXPECT_EQ(r.node_count(), 3u);
  EXPECT_TRUE(r.closed_cleanly());
  r.close();
  RouteFileWriter w(s->fs);
  RouteReplaceReport rep;
  ASSERT_TRUE(w.create_replacement("route.qroute", params(), o, &rep));
  EXPECT_TRUE(rep.previous_kept);
  EXPECT_STREQ(rep.kept_path, "route.qroute.new.kept.1");
  ASSERT_TRUE(r.open("route.qroute.new.kept.1"));  // the cut-off run's nodes, not deleted
  EXPECT_EQ(r.end(), RouteEnd::kCutOff);
  EXPECT_EQ(r.node_count(), 2u);
  expect_all_nodes_decode(r, 4);
}

TEST(RouteStoreDurability, NonFiniteOrAbsurdNodesAreRefusedAndNothingIsWritten) {
  auto s = std::make_unique<Store>();
  RouteFileWriter w(s->fs);
  ASSERT_TRUE(w.create("n.qroute", params()));
  ASSERT_TRUE(w.append(node(0, 3)));
  const std::uint64_t size = s->size_of("n.qroute");
  route::RouteNode bad = node(1, 3);
  bad.keypoints[1].y_m = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(w.append(bad), StatusCode::kInvalidArgument);
  bad = node(1, 3);
  bad.keypoints[2].score = std::numeric_limits<float>::infinity();
  EXPECT_EQ(w.append(bad), StatusCode::kInvalidArgument);
  bad = node(1, 3);
  bad.keypoints[0].x_m = 1e30f;
  EXPECT_EQ(w.append(bad), StatusCode::kInvalidArgument);
  bad = node(1, 3);
  bad.meta.pose.heading_rad = 1e300;
  EXPECT_EQ(w.append(bad), StatusCode::kInvalidArgument);
  EXPECT_EQ(w.node_count(), 1u);
  EXPECT_EQ(s->size_of("n.qroute"), size);
  ASSERT_TRUE(w.append(node(1, 3)));
  ASSERT_TRUE(w.close());
  RouteFileReader r(s->fs);
  ASSERT_TRUE(r.open("n.qroute"));
  EXPECT_TRUE(r.closed_cleanly());
  EXPECT_EQ(r.node_count(), 2u);
  expect_all_nodes_decode(r);
}

// A store whose medium fails in the middle of a write (disk full, a failing flash page): half of the
// bytes reach it, then the error.
class TearingStore final : public hal::FileStore {
 public:
  explicit TearingStore(hal::FileStore& inner) : inner_(inner) {}
  bool tear_next_write = false;
  std::uint64_t size_after_tear = 0;
  Result<int> open(const char* p, hal::FileMode m) noexcept override { return inner_.open(p, m); }
  void close(int h) noexcept override { inner_.close(h); }
  Status read_at(int h, std::uint8_t* d, std::size_t n, std::uint64_t o) noexcept override { return inner_.read_at(h, d, n, o); }
  Status write_at(int h, const std::uint8_t* d, std::size_t n, std::uint64_t o) noexcept override {
    if (!tear_next_write) return inner_.write_at(h, d, n, o);
    tear_next_write = false;
    static_cast<void>(inner_.write_at(h, d, n / 2, o));
    size_after_tear = *inner_.size(h);
    return Status(StatusCode::kCapacityExceeded, "store full (injected)");
  }
  Result<std::uint64_t> size(int h) noexcept override { return inner_.size(h); }
  Status truncate(int h, std::uint64_t n) noexcept override { return inner_.truncate(h, n); }
  Status sync_data(int h) noexcept override { return inner_.sync_data(h); }
  Status sync(int h) noexcept override { return inner_.sync(h); }
  Status rename(const char* a, const char* b) noexcept override { return inner_.rename(a, b); }
  Status sync_name(const char* p) noexcept override { return inner_.sync_name(p); }

 private:
  hal::FileStore& inner_;
};

TEST(RouteStoreDurability, AWriteTornByAFullMediumIsCutAtCloseAndTheRouteStaysValid) {
  auto s = std::make_unique<Store>();
  TearingStore ts(s->fs);
  RouteFileWriter w(ts);
  ASSERT_TRUE(w.create("full.qroute", params()));
  for (std::uint32_t i = 0; i < 4; ++i) ASSERT_TRUE(w.append(node(i, 3)));
  ts.tear_next_write = true;
  EXPECT_EQ(w.append(node(4, 3)), StatusCode::kCapacityExceeded);
  EXPECT_EQ(w.node_count(), 4u);
  EXPECT_EQ(ts.size_after_tear, route::kHeaderBytes + 4 * kRec + kRec / 2) << "half a record reached the medium";
  ASSERT_TRUE(w.close());
  RouteFileReader r(s->fs);
  ASSERT_TRUE(r.open("full.qroute"));
  EXPECT_TRUE(r.closed_cleanly());
  EXPECT_EQ(r.torn_bytes(), 0u);
  EXPECT_EQ(r.node_count(), 4u);
  expect_all_nodes_decode(r);
}

TEST(RouteStoreDurability, ADamagedMiddleNodeIsNamedAndTheGoodPrefixStaysUsable) {
  auto s = std::make_unique<Store>();
  teach(*s, "p.qroute", 8, true);
  // A CRC-valid record holding a NaN keypoint (a foreign writer, or damage the CRC missed).
  std::vector<std::uint8_t> rec(kRec);
  s->read("p.qroute", rec.data(), rec.size(), route::kHeaderBytes + 5 * kRec);
  store_le_f32(rec.data() + route::kRecordFixedBytes + route::kKeypointBytes + 4, std::numeric_limits<float>::quiet_NaN());
  store_le_u32(rec.data() + kRec - 4, crc32(rec.data(), kRec - 4));
  s->write("p.qroute", rec.data(), rec.size(), route::kHeaderBytes + 5 * kRec);
  RouteFileReader r(s->fs);
  ASSERT_TRUE(r.open("p.qroute"));
  std::vector<route::NodeMeta> meta;
  std::uint32_t bad = 0;
  const Status st = r.read_all_meta(meta, &bad);
  EXPECT_EQ(st, StatusCode::kCorrupt);
  EXPECT_STREQ(st.message(), "route keypoint not finite");
  EXPECT_EQ(bad, 5u);
  EXPECT_EQ(meta.size(), 5u) << "the good prefix";
  EXPECT_EQ(r.counters().get(route::RouteFormatCounter::kBadRecordField), 1u);
  route::RouteNode out;
  EXPECT_EQ(r.load(5, out), StatusCode::kCorrupt);
  ASSERT_TRUE(r.limit_nodes(5));
  EXPECT_EQ(r.node_count(), 5u);
  EXPECT_EQ(r.file_nodes(), 8u);
  EXPECT_EQ(r.load(5, out), StatusCode::kOutOfRange);
  expect_all_nodes_decode(r);
  EXPECT_EQ(r.limit_nodes(9), StatusCode::kOutOfRange);
}

// Damages node k's record (a byte flipped: the CRC no longer matches).
void damage(Store& s, const char* path, std::uint32_t k) {
  std::uint8_t b = 0;
  s.read(path, &b, 1, route::kHeaderBytes + k * kRec + 40);
  b ^= 0x5A;
  s.write(path, &b, 1, route::kHeaderBytes + k * kRec + 40);
}

TEST(RouteOpenForRepeat, ACleanRouteIsUsedWhole) {
  auto s = std::make_unique<Store>();
  teach(*s, "c.qroute", 6, true);
  RouteFileReader r(s->fs);
  std::vector<route::NodeMeta> meta;
  const RepeatOpenReport rep = open_route_for_repeat(r, "c.qroute", meta, 100);
  EXPECT_EQ(rep.outcome, RepeatOpen::kOk);
  EXPECT_TRUE(usable(rep.outcome));
  EXPECT_FALSE(rep.cut_off);
  EXPECT_EQ(rep.nodes_used, 6u);
  EXPECT_EQ(meta.size(), 6u);
}

TEST(RouteOpenForRepeat, ADamagedNodeAfterTwoGoodOnesLeavesTheGoodPrefix) {
  auto s = std::make_unique<Store>();
  teach(*s, "d.qroute", 8, false);  // cut off too: still used, and said
  damage(*s, "d.qroute", 5);
  RouteFileReader r(s->fs);
  std::vector<route::NodeMeta> meta;
  const RepeatOpenReport rep = open_route_for_repeat(r, "d.qroute", meta, 100);
  EXPECT_EQ(rep.outcome, RepeatOpen::kGoodPrefix);
  EXPECT_TRUE(rep.cut_off);
  EXPECT_EQ(rep.first_bad_node, 5u);
  EXPECT_EQ(rep.nodes_used, 5u);
  EXPECT_EQ(rep.file_nodes, 8u);
  EXPECT_EQ(rep.why, StatusCode::kCorrupt);
  EXPECT_EQ(meta.size(), 5u);
  EXPECT_EQ(r.node_count(), 5u) << "the reader serves the prefix only";
  expect_all_nodes_decode(r);
}

TEST(RouteOpenForRepeat, RefusesWhatCannotBeRepeatedAndSaysWhy) {
  auto s = std::make_unique<Store>();
  std::vector<route::NodeMeta> meta;
  RouteFileReader r(s->fs);
  EXPECT_EQ(open_route_for_repeat(r, "none.qroute", meta, 100).outcome, RepeatOpen::kMissing);
  teach(*s, "early.qroute", 6, true);
  damage(*s, "early.qroute", 1);
  RepeatOpenReport rep = open_route_for_repeat(r, "early.qroute", meta, 100);
  EXPECT_EQ(rep.outcome, RepeatOpen::kDamaged) << "fewer than 2 good nodes before the damage";
  EXPECT_EQ(rep.first_bad_node, 1u);
  EXPECT_TRUE(meta.empty());
  teach(*s, "long.qroute", 6, true);
  EXPECT_EQ(open_route_for_repeat(r, "long.qroute", meta, 5).outcome, RepeatOpen::kTooLong);
  teach(*s, "one.qroute", 1, true);
  EXPECT_EQ(open_route_for_repeat(r, "one.qroute", meta, 100).outcome, RepeatOpen::kTooShort);
  teach(*s, "junk.qroute", 3, true);
  const std::uint8_t junk[8] = {1, 2, 3, 4, 5, 6, 7, 8};
  s->write("junk.qroute", junk, sizeof junk, 0);  // the header's magic
  rep = open_route_for_repeat(r, "junk.qroute", meta, 100);
  EXPECT_FALSE(usable(rep.outcome));
  EXPECT_FALSE(rep.why.is_ok());
}

}  // namespace
}  // namespace qnav::drivers::route_store
