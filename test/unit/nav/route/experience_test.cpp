// Multi-experience localisation (issue 29): the experience record format, the index's replacement
// rule, the localiser registering against experiences (a far offset localises after an intermediate
// one was learnt), the learner learning nothing wrong (another route, never confident, estimates
// jumping against the odometry), and no heap in a step with experiences.
#include "nav/route/experience.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include "nav/route/experience_learner.hpp"
#include "nav/route/route_localiser.hpp"
#include "synthetic_route.hpp"
#include "test/support/alloc_guard.hpp"

namespace qnav::route {
namespace {

class MemorySource final : public NodeSource {
 public:
  std::vector<RouteNode> nodes;
  std::uint32_t node_count() const noexcept override { return static_cast<std::uint32_t>(nodes.size()); }
  Status load(std::uint32_t i, RouteNode& out) noexcept override {
    if (i >= nodes.size()) return Status(StatusCode::kOutOfRange, "no such node");
    out = nodes[i];
    return Status::ok();
  }
};

// Experiences in memory: record i = experiences[i] (what drivers/route_store/experience_file does on a medium).
struct MemoryExperiences final : public NodeSource {
  std::vector<Experience> records;
  std::uint32_t node_count() const noexcept override { return static_cast<std::uint32_t>(records.size()); }
  Status load(std::uint32_t i, RouteNode& out) noexcept override {
    if (i >= records.size()) return Status(StatusCode::kOutOfRange, "no such record");
    out = records[i].node;
    return Status::ok();
  }
  void append(Experience e, ExperienceIndex& index) {
    e.meta.record = static_cast<std::uint32_t>(records.size());
    records.push_back(e);
    ASSERT_TRUE(index.set(e.meta));
  }
};

constexpr double kSpacing = 50.0;
constexpr double kHalfLen = 25.0;
constexpr double kHalfWidth = 50.0;
constexpr std::uint32_t kNodes = 30;

struct Scenario {
  testing::SyntheticWorld world{1800.0, 400.0, 0.012, 42};
  MemorySource source;
  std::vector<NodeMeta> meta;
  RouteParams params;
  Scenario() {
    params.sensor = SensorKind::kSideScan;
    params.node_spacing_m = static_cast<float>(kSpacing);
    params.tile_length_m = 50.0f;
    params.tile_width_m = 100.0f;
    params.pixel_m = 0.2f;
    params.max_keypoints = 64;
    for (std::uint32_t i = 0; i < kNodes; ++i) {
      RouteNode n = world.observe(Pose2{50.0 + kSpacing * i, 0.0, 0.0}, kHalfLen, kHalfWidth, 0.2, 0.85, 64, 1000 + i, 8);
      n.meta.index = i;
      n.meta.along_m = kSpacing * i;
      source.nodes.push_back(n);
      meta.push_back(n.meta);
    }
  }
};

LocaliserConfig config(std::size_t experiences) {
  LocaliserConfig c;
  c.filter.max_nodes = 64;
  c.registration.robust.inlier_threshold_m = 1.0;
  c.experiences_per_node = experiences;
  c.experience_window_slots = 16;
  return c;
}

struct PassResult {
  int scored = 0, within1 = 0, learned = 0;
  double mean_inliers = 0.0;  // of the registration used, scored tiles
};

// A forward pass at lateral_m over nodes 3..27 (tiles between nodes). With exp: registers against
// its experiences; with learn: learns into them.
PassResult pass(Scenario& s, double lateral_m, std::uint64_t seed, MemoryExperiences* exp, ExperienceIndex* index, bool learn,
                const testing::SyntheticWorld* other_world = nullptr, std::uint32_t pass_id = 1) {
  LocaliserConfig c = config(exp ? 2 : 0);
  ArenaStorage arena(RouteLocaliser::arena_bytes(c) + ExperienceLearner::arena_bytes());
  auto loc = std::make_unique<RouteLocaliser>();
  auto learner = std::make_unique<ExperienceLearner>();
  EXPECT_TRUE(loc->init(c, arena).is_ok());
  EXPECT_TRUE(learner->init(ExperienceLearnConfig{}, arena).is_ok());
  EXPECT_TRUE(loc->start(s.params, Span<const NodeMeta>(s.meta.data(), s.meta.size()), s.source).is_ok());
  if (exp != nullptr) {
    EXPECT_TRUE(loc->attach_experiences(index, exp).is_ok());
  }
  EXPECT_TRUE(learner->start(Span<const NodeMeta>(s.meta.data(), s.meta.size()), loc->node_spacing_m(), false, pass_id).is_ok());
  const testing::SyntheticWorld& w = other_world ? *other_world : s.world;
  PassResult r;
  auto e = std::make_unique<Experience>();
  for (int k = 0; k < 24; ++k) {
    const double along = kSpacing * (3 + k) + 0.3 * kSpacing;
    RouteNode sensed = w.observe(Pose2{50.0 + along, lateral_m, 0.0}, kHalfLen, kHalfWidth, 0.2, 0.85, 64, seed + static_cast<std::uint64_t>(k), 8);
    LocaliserStep st;
    EXPECT_TRUE(loc->step(sensed, k == 0 ? 0.0 : kSpacing, st).is_ok());
    if (learn && learner->observe(sensed, k == 0 ? 0.0 : kSpacing, st, *index, *e)) {
      exp->append(*e, *index);
      ++r.learned;
    }
    if (k >= 3) {
      ++r.scored;
      r.within1 += std::abs(static_cast<double>(st.estimate) - along / kSpacing) <= 1.0;
      r.mean_inliers += st.best_inliers;
    }
  }
  learner->finish();
  if (r.scored) r.mean_inliers /= r.scored;
  return r;
}

struct Learnt {
  ArenaStorage arena{ExperienceIndex::arena_bytes(64, 2)};
  ExperienceIndex index;
  MemoryExperiences exp;
  Learnt() { EXPECT_TRUE(index.init(64, 2, arena).is_ok()); EXPECT_TRUE(index.reset(kNodes).is_ok()); }
};

TEST(RouteExperiences, AFarOffsetLocalisesAfterAnIntermediateOffsetWasLearnt) {
  Scenario s;
  // 75 m to the side a tile overlaps the taught footprint by a quarter: weak registrations.
  const PassResult before = pass(s, 75.0, 7000, nullptr, nullptr, false);
  Learnt l;
  const PassResult learnt = pass(s, 40.0, 8000, &l.exp, &l.index, true);
  EXPECT_GE(learnt.learned, 15) << "a confident pass at 40 m learns most of its tiles";
  EXPECT_EQ(static_cast<std::size_t>(learnt.learned), l.index.live());
  for (const Experience& e : l.exp.records) {
    EXPECT_NEAR(e.meta.offset_m, 40.0, 3.0) << "the pass's offset in the node's frame";
    EXPECT_FALSE(e.meta.reverse);
  }
  const PassResult after = pass(s, 75.0, 7000, &l.exp, &l.index, false);
  std::printf("far offset: before %d/%d within 1, %.1f inliers; learnt %d; after %d/%d, %.1f inliers\n", before.within1, before.scored, before.mean_inliers, learnt.learned, after.within1, after.scored, after.mean_inliers);
  EXPECT_GT(after.mean_inliers, before.mean_inliers + 5.0) << before.mean_inliers << " -> " << after.mean_inliers;
  EXPECT_GE(after.within1, after.scored - 1);
  EXPECT_GE(after.within1, before.within1);
}

TEST(RouteExperiences, WithoutExperiencesTheLocaliserIsUnchanged) {
  Scenario s;
  Learnt l;  // attached but empty: every step registers the taught keypoints first, as before
  const PassResult a = pass(s, 20.0, 9000, nullptr, nullptr, false);
  const PassResult b = pass(s, 20.0, 9000, &l.exp, &l.index, false);
  EXPECT_EQ(a.within1, b.within1);
  EXPECT_DOUBLE_EQ(a.mean_inliers, b.mean_inliers);
}

TEST(RouteExperiences, APassOnAnotherRouteLearnsNothing) {
  Scenario s;
  Learnt l;
  const testing::SyntheticWorld elsewhere{1800.0, 400.0, 0.012, 4242};
  const PassResult r = pass(s, 0.0, 9100, &l.exp, &l.index, true, &elsewhere);
  EXPECT_EQ(r.learned, 0);
  EXPECT_EQ(l.index.live(), 0u);
}

// Steps built by hand: confident, strong registrations, but the estimate does not move as the
// odometry says (a forced mislocalisation), or the filter is never confident.
TEST(RouteExperiences, EstimatesAgainstTheOdometryOrNeverConfidentLearnNothing) {
  Scenario s;
  Learnt l;
  ArenaStorage arena(ExperienceLearner::arena_bytes());
  auto learner = std::make_unique<ExperienceLearner>();
  ASSERT_TRUE(learner->init(ExperienceLearnConfig{}, arena).is_ok());
  auto e = std::make_unique<Experience>();
  const RouteNode sensed = s.source.nodes[5];
  auto step = [](std::uint32_t est, bool confident) {
    LocaliserStep st;
    st.estimate = est;
    st.confident = confident;
    st.registration.ok = true;
    st.registration.inliers = 14;
    st.best_inliers = 14;
    return st;
  };
  ASSERT_TRUE(learner->start(Span<const NodeMeta>(s.meta.data(), s.meta.size()), kSpacing, false, 3).is_ok());
  // Moving one node per tile on the odometry, the estimate jumps 4 nodes at a time.
  int learned = 0;
  for (std::uint32_t k = 0; k < 6; ++k) learned += learner->observe(sensed, kSpacing, step(4 * k, true), l.index, *e);
  learner->finish();
  EXPECT_EQ(learned, 0);
  // The odometry says stationary (0 m), the estimate runs on: 2 nodes per tile.
  ASSERT_TRUE(learner->start(Span<const NodeMeta>(s.meta.data(), s.meta.size()), kSpacing, false, 4).is_ok());
  for (std::uint32_t k = 0; k < 6; ++k) learned += learner->observe(sensed, 0.0, step(2 * k, true), l.index, *e);
  learner->finish();
  EXPECT_EQ(learned, 0);
  // Never confident.
  ASSERT_TRUE(learner->start(Span<const NodeMeta>(s.meta.data(), s.meta.size()), kSpacing, false, 5).is_ok());
  for (std::uint32_t k = 0; k < 6; ++k) learned += learner->observe(sensed, kSpacing, step(k, false), l.index, *e);
  learner->finish();
  EXPECT_EQ(learned, 0);
  // Estimates and odometry agreeing, but the tiles are flown against the pass's direction (a pass told
  // reverse flying forwards: its belief sweeps the route against the vehicle and meets it once): nothing.
  ASSERT_TRUE(learner->start(Span<const NodeMeta>(s.meta.data(), s.meta.size()), kSpacing, true, 7).is_ok());
  for (std::uint32_t k = 0; k < 6; ++k) learned += learner->observe(sensed, kSpacing, step(9 - k, true), l.index, *e);
  learner->finish();
  EXPECT_EQ(learned, 0);
  // The same steps agreeing with the odometry: learnt, each confirmed by the next (the last one is not).
  ASSERT_TRUE(learner->start(Span<const NodeMeta>(s.meta.data(), s.meta.size()), kSpacing, false, 6).is_ok());
  for (std::uint32_t k = 0; k < 6; ++k) learned += learner->observe(sensed, kSpacing, step(k + 2, true), l.index, *e);
  learner->finish();
  EXPECT_EQ(learned, 4);  // tiles 1..4: tile 0 has no anchor yet, tile 5 is never confirmed
  EXPECT_EQ(learner->counters().count_at(static_cast<std::size_t>(LearnCounter::kUnconfirmed)), 1u);
}

TEST(RouteExperiences, IndexKeepsTheNewestPerSlotAndReplacesTheOldestNotJustUsed) {
  ArenaStorage arena(ExperienceIndex::arena_bytes(4, 3));
  ExperienceIndex index;
  ASSERT_TRUE(index.init(4, 3, arena).is_ok());
  ASSERT_TRUE(index.reset(4).is_ok());
  EXPECT_FALSE(index.reset(5).is_ok());
  auto put = [&](std::uint32_t record, std::uint16_t slot) {
    ExperienceMeta m;
    m.record = record;
    m.node = 2;
    m.slot = slot;
    m.pass_id = record + 1;
    return index.set(m);
  };
  EXPECT_EQ(index.choose_slot(2, kNoExperience), 0u);
  ASSERT_TRUE(put(0, 0));
  EXPECT_EQ(index.choose_slot(2, kNoExperience), 1u);
  ASSERT_TRUE(put(1, 1));
  ASSERT_TRUE(put(2, 2));
  EXPECT_EQ(index.choose_slot(2, kNoExperience), 0u) << "full: the oldest";
  EXPECT_EQ(index.choose_slot(2, 0), 1u) << "full: the oldest that was not this pass's best match";
  ASSERT_TRUE(put(5, 0));
  ASSERT_TRUE(put(3, 0));  // an older record for a slot holding a newer one: ignored
  EXPECT_EQ(index.slots(2)[0].record, 5u);
  EXPECT_EQ(index.live(), 3u);
  EXPECT_FALSE(put(6, 3).is_ok()) << "slot beyond per_node";
}

TEST(RouteExperiences, RecordRoundTripsAndEveryFlippedByteIsDetected) {
  Scenario s;
  ExperienceHeader h;
  h.max_keypoints = 64;
  h.max_per_node = 2;
  Experience e;
  e.meta.record = 7;
  e.meta.node = 12;
  e.meta.slot = 1;
  e.meta.reverse = true;
  e.meta.offset_m = -31.5f;
  e.meta.pass_id = 9;
  e.meta.stamp_ns = 123456789ull;
  e.meta.inliers = 11;
  e.meta.node_heading_rad = 0.25f;
  e.node = s.source.nodes[12];
  std::vector<std::uint8_t> buf(exp_record_bytes(64));
  ASSERT_TRUE(encode_experience(s.params, h, kNodes, e, Span<std::uint8_t>(buf.data(), buf.size())));
  ExperienceMeta m;
  RouteNode n;
  ASSERT_TRUE(decode_experience(s.params, h, kNodes, Span<const std::uint8_t>(buf.data(), buf.size()), 7, m, &n, nullptr));
  EXPECT_EQ(m.node, 12u);
  EXPECT_EQ(m.slot, 1u);
  EXPECT_TRUE(m.reverse);
  EXPECT_FLOAT_EQ(m.offset_m, -31.5f);
  EXPECT_EQ(m.pass_id, 9u);
  EXPECT_EQ(m.stamp_ns, 123456789ull);
  EXPECT_EQ(n.meta.index, 12u);
  EXPECT_DOUBLE_EQ(n.meta.pose.heading_rad, 0.25);
  ASSERT_EQ(n.keypoints.size(), e.node.keypoints.size());
  EXPECT_FLOAT_EQ(n.keypoints[3].x_m, e.node.keypoints[3].x_m);
  EXPECT_EQ(n.keypoints[3].descriptor[5], e.node.keypoints[3].descriptor[5]);
  // Another record number, a node beyond the route: refused.
  EXPECT_FALSE(decode_experience(s.params, h, kNodes, Span<const std::uint8_t>(buf.data(), buf.size()), 8, m, &n, nullptr));
  EXPECT_FALSE(decode_experience(s.params, h, 12, Span<const std::uint8_t>(buf.data(), buf.size()), 7, m, &n, nullptr));
  ExperienceFormatCounters c(kExperienceFormatCounterNames);
  for (std::size_t i = 0; i < buf.size(); i += 7) {
    std::vector<std::uint8_t> bad = buf;
    bad[i] ^= 0x10;
    EXPECT_FALSE(decode_experience(s.params, h, kNodes, Span<const std::uint8_t>(bad.data(), bad.size()), 7, m, nullptr, &c)) << i;
  }
  // Not encodable: a NaN offset, pass id 0 (the taught pass), a slot beyond max_per_node.
  Experience bad = e;
  bad.meta.offset_m = std::nanf("");
  EXPECT_FALSE(encode_experience(s.params, h, kNodes, bad, Span<std::uint8_t>(buf.data(), buf.size())));
  bad = e;
  bad.meta.pass_id = 0;
  EXPECT_FALSE(encode_experience(s.params, h, kNodes, bad, Span<std::uint8_t>(buf.data(), buf.size())));
  bad = e;
  bad.meta.slot = 2;
  EXPECT_FALSE(encode_experience(s.params, h, kNodes, bad, Span<std::uint8_t>(buf.data(), buf.size())));
}

TEST(RouteExperiences, StepWithExperiencesDoesNotAllocateAndStaysInItsBudget) {
  Scenario s;
  Learnt l;
  pass(s, 40.0, 8000, &l.exp, &l.index, true);
  ASSERT_GT(l.index.live(), 10u);
  LocaliserConfig c = config(2);
  c.experience_registrations = 10;
  ArenaStorage arena(RouteLocaliser::arena_bytes(c));
  auto loc = std::make_unique<RouteLocaliser>();
  ASSERT_TRUE(loc->init(c, arena).is_ok());
  ASSERT_TRUE(loc->start(s.params, Span<const NodeMeta>(s.meta.data(), s.meta.size()), s.source).is_ok());
  ASSERT_TRUE(loc->attach_experiences(&l.index, &l.exp).is_ok());
  std::vector<RouteNode> tiles;
  for (int k = 0; k < 4; ++k)
    tiles.push_back(s.world.observe(Pose2{50.0 + kSpacing * (10 + k), 60.0, 0.0}, kHalfLen, kHalfWidth, 0.2, 0.85, 64, 300 + static_cast<std::uint64_t>(k), 8));
  LocaliserStep st;
  std::uint32_t most = 0;
  QNAV_EXPECT_NO_ALLOC({
    for (const RouteNode& t : tiles) {
      loc->step(t, kSpacing, st).ignore();
      most = st.registrations > most ? st.registrations : most;
    }
  });
  EXPECT_LE(most, c.filter.max_registrations() + 1 + c.experience_registrations);
  EXPECT_GT(st.experience_registrations, 0u);
  EXPECT_NE(st.experience_record, kNoExperience) << "at 60 m the 40 m experience matches better than the taught tile";
}

}  // namespace
}  // namespace qnav::route
