// The experience companion file (issue 29) on hal/sim's MemoryFileStore: appended durably record by
// record, read back into the index; a power cut mid-append (torn tail) keeps every fully written
// experience (reported, cut by open_append); a damaged record is skipped and counted, the rest used;
// a companion from another teach of the route is refused for reading and moved aside for learning;
// the route file itself is never touched (route readers see the same bytes); compaction drops the
// replaced records, keeps the live ones in order, and a power cut at any step of it (or a full disk)
// leaves a readable companion with every live experience.
#include <gtest/gtest.h>

#include <cstdint>
#include <memory>
#include <vector>

#include "drivers/route_store/experience_file.hpp"
#include "drivers/route_store/route_file.hpp"
#include "hal/sim/memory_file_store.hpp"
#include "test/support/route_nodes.hpp"

namespace qnav::drivers::route_store {
namespace {

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
  void cut(const char* path, std::uint64_t size) {
    Result<int> h = fs.open(path, hal::FileMode::kReadWrite);
    ASSERT_TRUE(h);
    ASSERT_TRUE(fs.truncate(*h, size));
    fs.close(*h);
  }
  void flip(const char* path, std::uint64_t at) {
    Result<int> h = fs.open(path, hal::FileMode::kReadWrite);
    ASSERT_TRUE(h);
    std::uint8_t b = 0;
    ASSERT_TRUE(fs.read_at(*h, &b, 1, at));
    b ^= 0x40;
    ASSERT_TRUE(fs.write_at(*h, &b, 1, at));
    fs.close(*h);
  }
};

RouteIdentity teach(Store& s, const char* path, std::uint32_t nodes, int stamp) {
  RouteFileWriter w(s.fs);
  EXPECT_TRUE(w.create(path, test::route_params(8)));
  for (std::uint32_t i = 0; i < nodes; ++i) {
    route::RouteNode n = test::route_node(i, 3);
    n.meta.stamp_ns = static_cast<std::uint64_t>(stamp);
    EXPECT_TRUE(w.append(n));
  }
  EXPECT_TRUE(w.close());
  RouteFileReader r(s.fs);
  EXPECT_TRUE(r.open(path));
  RouteIdentity id;
  route::RouteNode scratch;
  std::vector<std::uint8_t> bytes(route::record_bytes(8));
  EXPECT_TRUE(route_identity(r.params(), r, scratch, Span<std::uint8_t>(bytes.data(), bytes.size()), id));
  return id;
}

route::Experience experience(std::uint32_t node, std::uint16_t slot, std::uint32_t pass) {
  route::Experience e;
  e.meta.node = node;
  e.meta.slot = slot;
  e.meta.pass_id = pass;
  e.meta.offset_m = 12.5f;
  e.meta.reverse = true;
  e.node = test::route_node(node, 4);
  return e;
}

struct Index {
  ArenaStorage arena{route::ExperienceIndex::arena_bytes(16, 2)};
  route::ExperienceIndex index;
  Index() { EXPECT_TRUE(index.init(16, 2, arena)); }
};

const std::uint64_t kExpRec = route::exp_record_bytes(8);

TEST(ExperienceFile, AppendedExperiencesAreReadBackAndReplaceBySlot) {
  auto s = std::make_unique<Store>();
  const RouteIdentity id = teach(*s, "r.qroute", 6, 1);
  const std::uint64_t route_bytes = s->size_of("r.qroute");
  Index ix;
  {
    ExperienceFile f(s->fs);
    ExperienceOpenReport rep;
    ASSERT_TRUE(f.open_append("r.qroute.exp", id, 2, ix.index, &rep));
    EXPECT_TRUE(rep.created);
    for (std::uint32_t n = 0; n < 4; ++n) {
      route::Experience e = experience(n, 0, 1);
      ASSERT_TRUE(f.append(e, ix.index));
      EXPECT_EQ(e.meta.record, n);
    }
    route::Experience e = experience(2, 0, 2);  // replaces node 2's slot 0
    ASSERT_TRUE(f.append(e, ix.index));
    route::Experience bad = experience(9, 0, 2);  // node beyond the route: refused, nothing written
    EXPECT_FALSE(f.append(bad, ix.index));
  }
  EXPECT_EQ(s->size_of("r.qroute.exp"), route::kExpHeaderBytes + 5 * kExpRec);
  EXPECT_EQ(s->size_of("r.qroute"), route_bytes) << "the route file is never touched";
  Index back;
  ExperienceFile f(s->fs);
  ExperienceOpenReport rep;
  ASSERT_TRUE(f.open_read("r.qroute.exp", id, back.index, &rep));
  EXPECT_EQ(rep.records, 5u);
  EXPECT_EQ(rep.live, 4u);
  EXPECT_EQ(back.index.slots(2)[0].record, 4u);
  EXPECT_EQ(back.index.slots(2)[0].pass_id, 2u);
  route::RouteNode n;
  ASSERT_TRUE(f.load(4, n));
  EXPECT_EQ(n.meta.index, 2u);
  EXPECT_EQ(n.keypoints.size(), 4u);
  RouteFileReader r(s->fs);
  ASSERT_TRUE(r.open("r.qroute"));
  EXPECT_TRUE(r.closed_cleanly()) << "route readers see the route as it was taught";
}

TEST(ExperienceFile, APowerCutMidAppendKeepsEveryFullyWrittenExperience) {
  auto s = std::make_unique<Store>();
  const RouteIdentity id = teach(*s, "r.qroute", 6, 1);
  Index ix;
  {
    ExperienceFile f(s->fs);
    ASSERT_TRUE(f.open_append("r.qroute.exp", id, 2, ix.index));
    for (std::uint32_t n = 0; n < 3; ++n) {
      route::Experience e = experience(n, 0, 1);
      ASSERT_TRUE(f.append(e, ix.index));
    }
  }
  {  // the 4th record, then only half of it on the medium when the power went
    ExperienceFile f(s->fs);
    route::Experience e = experience(3, 0, 1);
    ASSERT_TRUE(f.open_append("r.qroute.exp", id, 2, ix.index));
    ASSERT_TRUE(f.append(e, ix.index));
  }
  s->cut("r.qroute.exp", route::kExpHeaderBytes + 3 * kExpRec + kExpRec / 2);
  Index back;
  ExperienceFile f(s->fs);
  ExperienceOpenReport rep;
  ASSERT_TRUE(f.open_read("r.qroute.exp", id, back.index, &rep));
  EXPECT_EQ(rep.records, 3u);
  EXPECT_EQ(rep.torn_bytes, kExpRec / 2);
  EXPECT_EQ(rep.live, 3u);
  EXPECT_EQ(f.counters().get(route::ExperienceFormatCounter::kTornTail), 1u);
  f.close();
  // Learning again: the torn tail is cut and reported, appending continues after record 2.
  ExperienceFile g(s->fs);
  ASSERT_TRUE(g.open_append("r.qroute.exp", id, 2, back.index, &rep));
  EXPECT_EQ(rep.torn_bytes, kExpRec / 2);
  route::Experience e = experience(5, 1, 3);
  ASSERT_TRUE(g.append(e, back.index));
  EXPECT_EQ(e.meta.record, 3u);
  g.close();
  EXPECT_EQ(s->size_of("r.qroute.exp"), route::kExpHeaderBytes + 4 * kExpRec);
  // A power cut while the companion was being created (shorter than its header): created again.
  s->cut("r.qroute.exp", 10);
  ASSERT_TRUE(g.open_append("r.qroute.exp", id, 2, back.index, &rep));
  EXPECT_TRUE(rep.created);
  EXPECT_EQ(rep.records, 0u);
}

TEST(ExperienceFile, ADamagedRecordIsSkippedAndCountedTheRestAreUsed) {
  auto s = std::make_unique<Store>();
  const RouteIdentity id = teach(*s, "r.qroute", 6, 1);
  Index ix;
  {
    ExperienceFile f(s->fs);
    ASSERT_TRUE(f.open_append("r.qroute.exp", id, 2, ix.index));
    for (std::uint32_t n = 0; n < 4; ++n) {
      route::Experience e = experience(n, 1, 1);
      ASSERT_TRUE(f.append(e, ix.index));
    }
  }
  s->flip("r.qroute.exp", route::kExpHeaderBytes + kExpRec + 60);
  Index back;
  ExperienceFile f(s->fs);
  ExperienceOpenReport rep;
  ASSERT_TRUE(f.open_read("r.qroute.exp", id, back.index, &rep));
  EXPECT_EQ(rep.damaged, 1u);
  EXPECT_EQ(rep.first_damaged, 1u);
  EXPECT_EQ(rep.live, 3u);
  EXPECT_EQ(back.index.slots(1)[1].record, route::kNoExperience);
  EXPECT_EQ(f.counters().get(route::ExperienceFormatCounter::kBadRecordCrc), 1u);
  route::RouteNode n;
  EXPECT_FALSE(f.load(1, n));
  // A damaged header: refused with its name.
  f.close();
  s->flip("r.qroute.exp", 13);
  const Status st = f.open_read("r.qroute.exp", id, back.index, &rep);
  EXPECT_EQ(st.code(), StatusCode::kCorrupt);
}

TEST(ExperienceFile, ACompanionOfAnotherTeachIsRefusedForRepeatAndMovedAsideForLearning) {
  auto s = std::make_unique<Store>();
  const RouteIdentity first = teach(*s, "a.qroute", 6, 1);
  const RouteIdentity second = teach(*s, "b.qroute", 6, 2);  // same parameters, other nodes
  EXPECT_EQ(first.header_crc, second.header_crc);
  EXPECT_NE(first.node0_crc, second.node0_crc);
  Index ix;
  {
    ExperienceFile f(s->fs);
    ASSERT_TRUE(f.open_append("a.qroute.exp", first, 2, ix.index));
    route::Experience e = experience(1, 0, 1);
    ASSERT_TRUE(f.append(e, ix.index));
  }
  ExperienceFile f(s->fs);
  const Status st = f.open_read("a.qroute.exp", second, ix.index);
  EXPECT_EQ(st.code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(f.counters().get(route::ExperienceFormatCounter::kOtherRoute), 1u);
  ExperienceOpenReport rep;
  ASSERT_TRUE(f.open_append("a.qroute.exp", second, 2, ix.index, &rep));
  EXPECT_TRUE(rep.moved_stale);
  EXPECT_EQ(rep.records, 0u);
  EXPECT_EQ(s->size_of("a.qroute.exp.stale"), route::kExpHeaderBytes + kExpRec) << "nothing learnt is deleted";
  // More experiences per node in the file than configured: refused with a reason.
  ArenaStorage a1(route::ExperienceIndex::arena_bytes(16, 1));
  route::ExperienceIndex one;
  ASSERT_TRUE(one.init(16, 1, a1));
  f.close();
  EXPECT_EQ(f.open_read("a.qroute.exp", second, one).code(), StatusCode::kInvalidArgument);
}


// A FileStore that loses power at its `cut`-th mutating call: that call does nothing (a write_at
// writes its first half), it and every later call fail. What the base store holds afterwards is the
// medium after the power cut (every call before it completed and was durable).
class PowerCutStore final : public hal::FileStore {
 public:
  PowerCutStore(hal::FileStore& base, std::uint32_t cut) noexcept : base_(base), cut_(cut) {}
  std::uint32_t calls() const noexcept { return calls_; }
  bool cut() const noexcept { return dead_; }
  Result<int> open(const char* path, hal::FileMode mode) noexcept override {
    if (mode == hal::FileMode::kCreateNew || mode == hal::FileMode::kCreateOrTruncate)
      if (!step()) return off();
    if (dead_) return off();
    return base_.open(path, mode);
  }
  void close(int handle) noexcept override { base_.close(handle); }
  Status read_at(int handle, std::uint8_t* data, std::size_t n, std::uint64_t offset) noexcept override {
    if (dead_) return off();
    return base_.read_at(handle, data, n, offset);
  }
  Status write_at(int handle, const std::uint8_t* data, std::size_t n, std::uint64_t offset) noexcept override {
    if (!step()) {
      if (calls_ == cut_ + 1) base_.write_at(handle, data, n / 2, offset).ignore();
      return off();
    }
    return base_.write_at(handle, data, n, offset);
  }
  Result<std::uint64_t> size(int handle) noexcept override {
    if (dead_) return off();
    return base_.size(handle);
  }
  Status truncate(int handle, std::uint64_t size) noexcept override { return step() ? base_.truncate(handle, size) : off(); }
  Status sync_data(int handle) noexcept override { return step() ? base_.sync_data(handle) : off(); }
  Status sync(int handle) noexcept override { return step() ? base_.sync(handle) : off(); }
  Status rename(const char* from, const char* to) noexcept override { return step() ? base_.rename(from, to) : off(); }
  Status sync_name(const char* path) noexcept override { return step() ? base_.sync_name(path) : off(); }

 private:
  bool step() noexcept {
    if (++calls_ > cut_) dead_ = true;
    return !dead_;
  }
  static Status off() noexcept { return Status(StatusCode::kIoError, "power cut (test)"); }
  hal::FileStore& base_;
  std::uint32_t cut_;
  std::uint32_t calls_ = 0;
  bool dead_ = false;
};

// Three passes over nodes 0..5 in slot 0 (the first two replaced: 12 dead records), then node 1
// slot 1: 19 records, 7 live.
void learn_three_passes(Store& s, const RouteIdentity& id) {
  Index ix;
  ExperienceFile f(s.fs);
  f.set_compact_min_dead(0xFFFFFFFFu);
  ASSERT_TRUE(f.open_append("r.qroute.exp", id, 2, ix.index));
  for (std::uint32_t pass = 1; pass <= 3; ++pass)
    for (std::uint32_t n = 0; n < 6; ++n) {
      route::Experience e = experience(n, 0, pass);
      e.node = test::route_node(n, static_cast<int>(pass + 1));  // pass p: p + 1 keypoints
      ASSERT_TRUE(f.append(e, ix.index));
    }
  route::Experience e = experience(1, 1, 3);
  ASSERT_TRUE(f.append(e, ix.index));
  EXPECT_EQ(f.records(), 19u);
  EXPECT_EQ(ix.index.live(), 7u);
}

// Every live experience of learn_three_passes is in `index`, read from `f`.
void expect_the_live_experiences(ExperienceFile& f, const route::ExperienceIndex& index) {
  EXPECT_EQ(index.live(), 7u);
  route::RouteNode n;
  for (std::uint32_t node = 0; node < 6; ++node) {
    const route::ExperienceSlot& s0 = index.slots(node)[0];
    ASSERT_NE(s0.record, route::kNoExperience) << node;
    EXPECT_EQ(s0.pass_id, 3u);
    ASSERT_TRUE(f.load(s0.record, n));
    EXPECT_EQ(n.meta.index, node);
    EXPECT_EQ(n.keypoints.size(), 4u) << "the third pass's keypoints";
  }
  EXPECT_EQ(index.slots(1)[1].pass_id, 3u);
  EXPECT_EQ(index.slots(2)[1].record, route::kNoExperience);
}

TEST(ExperienceFile, CompactionDropsReplacedRecordsAndKeepsTheLiveOnesInOrder) {
  auto s = std::make_unique<Store>();
  const RouteIdentity id = teach(*s, "r.qroute", 6, 1);
  const std::uint64_t route_bytes = s->size_of("r.qroute");
  learn_three_passes(*s, id);
  Index ix;
  ExperienceFile f(s->fs);
  ExperienceOpenReport rep;
  // 12 dead records < kCompactMinDead (16): the default rule leaves the file as it is.
  ASSERT_TRUE(f.open_append("r.qroute.exp", id, 2, ix.index, &rep));
  EXPECT_FALSE(rep.compacted);
  EXPECT_EQ(rep.records, 19u);
  f.close();
  f.set_compact_min_dead(4);
  ASSERT_TRUE(f.open_append("r.qroute.exp", id, 2, ix.index, &rep));
  EXPECT_TRUE(rep.compacted);
  EXPECT_FALSE(rep.compact_failed);
  EXPECT_EQ(rep.dropped, 12u);
  EXPECT_EQ(rep.records, 7u);
  EXPECT_EQ(f.records(), 7u);
  expect_the_live_experiences(f, ix.index);
  // Order kept: node 1's slot 1 (learnt last) is the last record; the keep rule's "oldest" stands.
  EXPECT_EQ(ix.index.slots(1)[1].record, 6u);
  EXPECT_EQ(ix.index.slots(0)[0].record, 0u);
  route::Experience e = experience(4, 1, 4);
  ASSERT_TRUE(f.append(e, ix.index));
  EXPECT_EQ(e.meta.record, 7u) << "appending goes on after the compacted records";
  f.close();
  EXPECT_EQ(s->size_of("r.qroute.exp"), route::kExpHeaderBytes + 8 * kExpRec);
  EXPECT_EQ(s->size_of("r.qroute"), route_bytes) << "the route file is never touched";
  // Live records only (dead 0 < live): a further open leaves it alone.
  ASSERT_TRUE(f.open_append("r.qroute.exp", id, 2, ix.index, &rep));
  EXPECT_FALSE(rep.compacted);
  EXPECT_EQ(rep.records, 8u);
}

TEST(ExperienceFile, APowerCutAtAnyStepOfCompactionLeavesEveryLiveExperienceReadable) {
  std::uint32_t steps = 0;
  {  // how many mutating calls an uninterrupted compaction makes
    auto s = std::make_unique<Store>();
    const RouteIdentity id = teach(*s, "r.qroute", 6, 1);
    learn_three_passes(*s, id);
    PowerCutStore never(s->fs, 0xFFFFFFFFu);
    Index ix;
    ExperienceFile f(never);
    f.set_compact_min_dead(4);
    ExperienceOpenReport rep;
    ASSERT_TRUE(f.open_append("r.qroute.exp", id, 2, ix.index, &rep));
    ASSERT_TRUE(rep.compacted);
    steps = never.calls();
  }
  ASSERT_GE(steps, 10u);  // create, header, 7 records, fsync, rename
  std::uint32_t old_seen = 0, compacted_seen = 0;
  for (std::uint32_t cut = 0; cut <= steps; ++cut) {
    SCOPED_TRACE(cut);
    auto s = std::make_unique<Store>();
    const RouteIdentity id = teach(*s, "r.qroute", 6, 1);
    learn_three_passes(*s, id);
    const std::uint64_t route_bytes = s->size_of("r.qroute");
    {
      PowerCutStore power(s->fs, cut);
      Index ix;
      ExperienceFile f(power);
      f.set_compact_min_dead(4);
      (void)f.open_append("r.qroute.exp", id, 2, ix.index);
    }
    // After the power cut: the companion reads whole (no damaged record, no torn tail) ...
    Index back;
    ExperienceFile f(s->fs);
    ExperienceOpenReport rep;
    ASSERT_TRUE(f.open_read("r.qroute.exp", id, back.index, &rep));
    EXPECT_EQ(rep.damaged, 0u);
    EXPECT_EQ(rep.torn_bytes, 0u);
    ASSERT_TRUE(rep.records == 19u || rep.records == 7u) << rep.records;
    (rep.records == 19u ? old_seen : compacted_seen) += 1;
    expect_the_live_experiences(f, back.index);
    f.close();
    EXPECT_EQ(s->size_of("r.qroute"), route_bytes);
    // ... and learning goes on (compacting now if the cut came before the rename).
    f.set_compact_min_dead(4);
    ASSERT_TRUE(f.open_append("r.qroute.exp", id, 2, back.index, &rep));
    EXPECT_EQ(rep.records, 7u);
    route::Experience e = experience(5, 1, 4);
    ASSERT_TRUE(f.append(e, back.index));
    EXPECT_EQ(e.meta.record, 7u);
  }
  EXPECT_EQ(compacted_seen, 1u) << "only the cut after the last step sees the compacted file";
  EXPECT_EQ(old_seen, steps);
}

TEST(ExperienceFile, ACompactionThatCannotWriteKeepsTheOldFileAndLearningGoesOn) {
  auto s = std::make_unique<Store>();
  const RouteIdentity id = teach(*s, "r.qroute", 6, 1);
  learn_three_passes(*s, id);
  s->fs.fail_writes_after(route::kExpHeaderBytes + 2 * kExpRec);  // the medium fails mid-compaction
  Index ix;
  ExperienceFile f(s->fs);
  f.set_compact_min_dead(4);
  ExperienceOpenReport rep;
  ASSERT_TRUE(f.open_append("r.qroute.exp", id, 2, ix.index, &rep));
  EXPECT_FALSE(rep.compacted);
  EXPECT_TRUE(rep.compact_failed);
  EXPECT_EQ(rep.compact_status.code(), StatusCode::kIoError);
  EXPECT_EQ(f.records(), 19u);
  expect_the_live_experiences(f, ix.index);
  s->fs.fail_writes_after(static_cast<std::size_t>(-1));
  route::Experience e = experience(5, 1, 4);
  ASSERT_TRUE(f.append(e, ix.index));
  EXPECT_EQ(e.meta.record, 19u);
}

}  // namespace
}  // namespace qnav::drivers::route_store
