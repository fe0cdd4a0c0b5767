// RouteRepeatSession: the repeat component qnavd's Mode = Repeat and `qnav route repeat` both run.
// It must give exactly what the localiser gives when wired by hand (the pass's first tile with no
// travel, eq. 5 while the DVL is lost), and learn into and read back the route's experiences.
// Host only (test_firmware_pipeline_host): the simulated passes cost seconds under qemu.
#include "firmware/pipeline/route_repeat_session.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "firmware/pipeline/route_defaults.hpp"
#include "firmware/pipeline/sim_survey.hpp"
#include "firmware/pipeline/vector_node_source.hpp"
#include "hal/sim/memory_file_store.hpp"

namespace {

using namespace qnav;
using namespace qnav::pipeline;

// A 600 m simulated route taught at zero offset, and one repeat pass 20 % of the swath to the side
// (built once: both tests repeat on it).
struct Route {
  SimSurvey w;
  RouteTilePipeline pipe;
  std::vector<RouteTile> taught, repeat;
  std::vector<route::NodeMeta> meta;
  route::RouteParams params{};
  explicit Route(double offset_pct, bool reverse) {
    const std::uint64_t seed = 4;
    EXPECT_TRUE(w.init(600.0, seed).is_ok());
    EXPECT_TRUE(pipe.init(default_route_tile_config()).is_ok());
    fly(w.pass(0.0, false, teach_pass_seed(seed)), taught);
    for (std::size_t i = 0; i < taught.size(); ++i) {
      meta.push_back(taught[i].node.meta);
      meta.back().index = static_cast<std::uint32_t>(i);
    }
    params = side_scan_route_params(pipe.config(), tile_stride_m(pipe.config(), w.route.speed_mps, w.route.ping_rate_hz), w.swath_m);
    fly(w.pass(offset_pct / 100.0 * w.swath_m, reverse, repeat_pass_seed(seed)), repeat);
  }
  void fly(const sidescan::TrajectoryConfig& t, std::vector<RouteTile>& out) {
    pipe.reset_pass();
    EXPECT_TRUE(pipe.run_sim_pass(w.seabed, w.sonar_for(t.seed), t, [&out](const RouteTile& tile) {
                      out.push_back(tile);
                      return true;
                    }).is_ok());
  }
  Span<const route::NodeMeta> m() const { return Span<const route::NodeMeta>(meta.data(), meta.size()); }
};

const Route& route20() {
  static const Route r(20.0, false);
  return r;
}

RepeatSessionConfig session_config(std::size_t nodes, bool reverse, std::uint16_t per_node) {
  RepeatSessionConfig c;
  c.localiser = default_localiser_config(reverse ? route::RouteDirection::kReverse : route::RouteDirection::kForward, nodes + 8);
  if (per_node > 0) enable_experiences(c.localiser, per_node);
  c.max_nodes = nodes;
  c.experiences_per_node = per_node;
  return c;
}

TEST(RouteRepeatSession, GivesWhatTheLocaliserWiredByHandGivesWithTheDvlLostMidPass) {
  const Route& r = route20();
  ASSERT_GE(r.taught.size(), 8u);
  ASSERT_GE(r.repeat.size(), 8u);
  VectorNodeSource<RouteTile> nodes_a(&r.taught), nodes_b(&r.taught);
  std::vector<std::uint8_t> disk(1 << 16);
  hal::MemoryFileStore store(Span<std::uint8_t>(disk.data(), disk.size()));
  RouteRepeatSession session(store);
  const RepeatSessionConfig sc = session_config(r.meta.size(), false, 0);
  ASSERT_TRUE(session.init(sc).is_ok());
  ASSERT_TRUE(session.start(r.params, r.m(), nodes_a, false).is_ok());
  RouteRepeater hand;
  ASSERT_TRUE(hand.init(sc.localiser).is_ok());
  ASSERT_TRUE(hand.start(r.params, r.m(), nodes_b).is_ok());
  // The session starts a pass with the entry prior (the pass starts at the route's entry end).
  ASSERT_TRUE(hand.apply_entry_prior(RouteRepeatSession::kEntryPriorMass, RouteRepeatSession::kEntryPriorSigmaNodes).is_ok());
  const std::size_t lost_from = 3, lost_to = 6;  // the DVL lost for tiles 3..5: eq. 5, then odometry again
  int confident = 0;
  for (std::size_t k = 0; k < r.repeat.size(); ++k) {
    const bool lost = k >= lost_from && k < lost_to;
    if (k == lost_from || k == lost_to)
      hand.set_motion(route::RouteDirection::kForward, lost ? route::MotionModel::kPaperEq5 : route::MotionModel::kOdometry);
    route::LocaliserStep a, b;
    const RepeatTileResult res = session.step(r.repeat[k], lost, a);
    ASSERT_TRUE(res.step.is_ok());
    EXPECT_EQ(res.eq5, lost) << "tile " << k;
    ASSERT_TRUE(hand.step(r.repeat[k].node, k == 0 ? 0.0 : r.repeat[k].nav_step_m, b).is_ok());
    EXPECT_EQ(a.estimate, b.estimate) << "tile " << k;
    EXPECT_EQ(a.probability, b.probability) << "tile " << k;
    EXPECT_EQ(a.guidance.cross_track_m, b.guidance.cross_track_m) << "tile " << k;
    EXPECT_EQ(session.next_stride_m(a, 30.0), route_aligned_stride_m(b, r.m(), route::RouteDirection::kForward, 30.0));
    confident += a.guidance.status == route::GuidanceStatus::kTracking;
  }
  EXPECT_GT(confident, static_cast<int>(r.repeat.size()) / 2);  // a 20 % pass localises: the comparison is not of two lost filters
  EXPECT_EQ(session.tiles(), r.repeat.size());
  EXPECT_EQ(session.end(), 0u);
}

TEST(RouteRepeatSession, EntryPriorZeroStartsUniformAndOutOfRangeIsRefused) {
  const Route& r = route20();
  ASSERT_GE(r.repeat.size(), 4u);
  std::vector<std::uint8_t> disk(1 << 16);
  hal::MemoryFileStore store(Span<std::uint8_t>(disk.data(), disk.size()));
  RepeatSessionConfig sc = session_config(r.meta.size(), false, 0);
  for (const double bad : {-0.1, 1.0, 2.0}) {
    sc.entry_prior = bad;
    RouteRepeatSession refused(store);
    EXPECT_EQ(refused.init(sc).code(), StatusCode::kInvalidArgument) << bad;
  }
  // qnavd's route.entry_prior = 0: the filter starts uniform, as the localiser wired by hand does.
  sc.entry_prior = 0.0;
  RouteRepeatSession session(store);
  ASSERT_TRUE(session.init(sc).is_ok());
  VectorNodeSource<RouteTile> nodes_a(&r.taught), nodes_b(&r.taught), nodes_c(&r.taught);
  ASSERT_TRUE(session.start(r.params, r.m(), nodes_a, false).is_ok());
  RouteRepeater uniform, prior;
  ASSERT_TRUE(uniform.init(sc.localiser).is_ok());
  ASSERT_TRUE(uniform.start(r.params, r.m(), nodes_b).is_ok());
  ASSERT_TRUE(prior.init(sc.localiser).is_ok());
  ASSERT_TRUE(prior.start(r.params, r.m(), nodes_c).is_ok());
  ASSERT_TRUE(prior.apply_entry_prior(kDefaultEntryPrior, RouteRepeatSession::kEntryPriorSigmaNodes).is_ok());
  route::LocaliserStep a, b, c;
  ASSERT_TRUE(session.step(r.repeat[0], false, a).step.is_ok());
  ASSERT_TRUE(uniform.step(r.repeat[0].node, 0.0, b).is_ok());
  ASSERT_TRUE(prior.step(r.repeat[0].node, 0.0, c).is_ok());
  EXPECT_EQ(a.estimate, b.estimate);
  EXPECT_EQ(a.probability, b.probability);
  EXPECT_NE(a.probability, c.probability) << "the prior must change the first step, or this test compares nothing";
}

TEST(RouteRepeatSession, LearnsIntoTheRoutesExperiencesAndTheNextPassReadsThem) {
  const Route& r = route20();
  VectorNodeSource<RouteTile> nodes(&r.taught);
  std::vector<std::uint8_t> disk(4 << 20);
  hal::MemoryFileStore store(Span<std::uint8_t>(disk.data(), disk.size()));
  RouteRepeatSession session(store);
  ASSERT_TRUE(session.init(session_config(r.meta.size(), false, 4)).is_ok());
  // Experiences belong to a started pass.
  EXPECT_EQ(session.open_experiences("r.qroute", true).status.code(), StatusCode::kNotReady);
  ASSERT_TRUE(session.start(r.params, r.m(), nodes, false).is_ok());
  // Reading a route that has none: no companion, no experiences, not an error.
  ExperiencesOpened o = session.open_experiences("r.qroute", false);
  ASSERT_TRUE(o.ok()) << o.status.message();
  EXPECT_FALSE(session.with_experiences());
  // Learning creates the companion and appends the confirmed tiles.
  o = session.open_experiences("r.qroute", true);
  ASSERT_TRUE(o.ok()) << o.status.message();
  EXPECT_TRUE(o.report.created);
  ASSERT_TRUE(session.with_experiences());
  std::uint32_t learned = 0;
  for (const RouteTile& t : r.repeat) {
    route::LocaliserStep st;
    const RepeatTileResult res = session.step(t, false, st);
    ASSERT_TRUE(res.step.is_ok());
    ASSERT_TRUE(res.learn.is_ok()) << res.learn.message();
    learned += res.learned ? 1 : 0;
  }
  EXPECT_GT(learned, 0u);
  EXPECT_EQ(session.end(), learned);
  EXPECT_FALSE(session.with_experiences());
  // The next pass reads what was learnt.
  RouteRepeatSession next(store);
  ASSERT_TRUE(next.init(session_config(r.meta.size(), false, 4)).is_ok());
  ASSERT_TRUE(next.start(r.params, r.m(), nodes, false).is_ok());
  o = next.open_experiences("r.qroute", false);
  ASSERT_TRUE(o.ok()) << o.status.message();
  EXPECT_TRUE(next.with_experiences());
  EXPECT_EQ(o.report.live, learned);
  // A session configured without experiences never opens the companion.
  RouteRepeatSession none(store);
  ASSERT_TRUE(none.init(session_config(r.meta.size(), false, 0)).is_ok());
  ASSERT_TRUE(none.start(r.params, r.m(), nodes, false).is_ok());
  EXPECT_TRUE(none.open_experiences("r.qroute", true).ok());
  EXPECT_FALSE(none.with_experiences());
}

}  // namespace
