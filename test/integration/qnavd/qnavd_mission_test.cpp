// qnavd through whole missions on the sim backend (in-process buses, mission time):
//  - teach, repeat forwards at +10 % of the swath and in reverse at -20 %: the ROUTE_STATUS /
//    NAV_STATUS frames the simulated autopilot received agree with the simulator's truth (node within
//    +/-1 >= 95 %, side correct >= 95 % where decided) and with the nav worker's own per-tile report;
//    no heap allocation while repeating; no software fault.
//  - a stop request while teaching: run() returns 0 within the shutdown bound and every node taught
//    is readable; a damaged route is refused by name and the daemon carries on.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <unistd.h>

#include "drivers/qnavcan/messages.hpp"
#include "firmware/qnavd/daemon.hpp"
#include "firmware/qnavd/software_fault.hpp"
#include "firmware/tools/route_file.hpp"
#include "test/support/alloc_guard.hpp"

namespace qnav::daemon {
namespace {

namespace qc = drivers::qnavcan;

constexpr std::size_t kMaxTiles = 512;

struct Recorder {
  std::array<TileReport, kMaxTiles> tiles{};
  std::atomic<std::uint32_t> n{0};
  // ROUTE_STATUS by tile sequence number, as the autopilot received it (-1 = never seen).
  std::array<int, kMaxTiles> can_estimate{};
  std::array<int, kMaxTiles> can_side{};
  std::array<int, kMaxTiles> can_status{};
  std::atomic<int> stop_after{-1};
  Daemon* daemon = nullptr;
  std::atomic<std::uint32_t> faults_seen{0};      // OR of the NAV_STATUS fault words sent in repeat mode
  std::atomic<std::uint32_t> last_faults{0};
  std::atomic<std::uint32_t> hold_frames{0};      // ROUTE_STATUS frames saying "hold course" while the sonar is lost
  std::atomic<int> last_state{0};                 // NAV_STATUS.State of the newest frame
  std::atomic<std::uint32_t> stale_guidance{0};   // ROUTE_STATUS "Tracking" or NAV_STATUS "Localised" outside Repeat
  std::atomic<std::int64_t> repeat_start_ns{-1};  // the first NAV_STATUS in State = Repeat
  std::atomic<std::int64_t> first_leak_ns{-1};    // the first HEALTH frame with Leak = 1
  std::atomic<std::uint32_t> leak_cleared{0};     // HEALTH frames with Leak = 0 after one with Leak = 1
  Recorder() {
    can_estimate.fill(-1);
    can_side.fill(-1);
    can_status.fill(-1);
  }
};

void on_tile(void* ctx, const TileReport& r) {
  auto* rec = static_cast<Recorder*>(ctx);
  const std::uint32_t i = rec->n.load();
  if (i < kMaxTiles) rec->tiles[i] = r;
  rec->n.store(i + 1);
  if (rec->stop_after.load() >= 0 && static_cast<int>(i + 1) >= rec->stop_after.load() && rec->daemon) rec->daemon->stop();
}

void on_frame(void* ctx, const hal::CanRxFrame& f) {
  auto* rec = static_cast<Recorder*>(ctx);
  if (f.frame.id == qc::kIdHealth) {
    qc::Health h;
    if (qc::decode(f.frame, h)) {
      if (h.leak && rec->first_leak_ns.load() < 0) rec->first_leak_ns.store(f.stamp.sample_ns);
      if (!h.leak && rec->first_leak_ns.load() >= 0) rec->leak_cleared.fetch_add(1);
    }
  }
  if (f.frame.id == qc::kIdNavStatus) {
    qc::NavStatus ns;
    if (qc::decode(f.frame, ns) && ns.state == qc::Mode::kRepeat) {
      if ((ns.fault_flags & ~rec->faults_seen.load()) && std::getenv("QNAVD_TEST_DEBUG"))
        std::printf("new fault bits 0x%x at t=%.3f s after %u tiles\n", ns.fault_flags, static_cast<double>(f.stamp.sample_ns) * 1e-9, rec->n.load());
      rec->faults_seen.fetch_or(ns.fault_flags);
    }
    if (qc::decode(f.frame, ns)) {
      rec->last_faults.store(ns.fault_flags);
      rec->last_state.store(static_cast<int>(ns.state));
      if (ns.state == qc::Mode::kRepeat && rec->repeat_start_ns.load() < 0) rec->repeat_start_ns.store(f.stamp.sample_ns);
      if (ns.localised && ns.state != qc::Mode::kRepeat) rec->stale_guidance.fetch_add(1);
    }
  }
  if (f.frame.id != qc::kIdRouteStatus) return;
  qc::RouteStatus rs;
  if (!qc::decode(f.frame, rs)) return;
  if (rs.status == qc::GuidanceState::kTracking && rec->last_state.load() != static_cast<int>(qc::Mode::kRepeat)) rec->stale_guidance.fetch_add(1);
  if (rs.status == qc::GuidanceState::kNotRepeating) return;
  if (rs.status == qc::GuidanceState::kHoldCourse && (rec->last_faults.load() & qc::fault::kSonarLost)) rec->hold_frames.fetch_add(1);
  const std::size_t seq = rs.tile_seq;
  if (seq >= kMaxTiles) return;
  rec->can_estimate[seq] = rs.estimate_node;
  rec->can_side[seq] = static_cast<int>(rs.side);
  rec->can_status[seq] = static_cast<int>(rs.status);
}

std::string temp_dir() {
  char t[] = "/tmp/qnavd_test_XXXXXX";
  const char* d = mkdtemp(t);
  return d ? std::string(d) : std::string("/tmp");
}

DaemonConfig sim_config(const std::string& dir, double length_m) {
  DaemonConfig c;
  c.backend = Backend::kSim;
  c.route_dir = dir;
  c.log = LogFormat::kOff;
  c.realtime = false;
  c.sim_length_m = length_m;
  c.sim_seed = 1;
  c.sim_speed = SimSpeed::kFast;
  c.tile_budget_us = 10000000;  // timing is measured by bench, not asserted here (ASan is slow)
  c.ping_budget_us = 1000000;
  return c;
}

SimPass sim_pass(qc::Mode mode, double offset_pct, bool reverse) {
  SimPass p;
  p.mode = mode;
  p.offset_pct = offset_pct;
  p.reverse = reverse;
  return p;
}

qc::SideOfRoute expected_side(double lateral_m, bool reverse, double deadband) {
  if (std::abs(lateral_m) <= deadband) return qc::SideOfRoute::kOnRoute;
  return ((lateral_m > 0) != reverse) ? qc::SideOfRoute::kStarboard : qc::SideOfRoute::kPort;
}

qc::SideOfRoute wire(route::RouteSide s) {
  switch (s) {
    case route::RouteSide::kPort: return qc::SideOfRoute::kPort;
    case route::RouteSide::kStarboard: return qc::SideOfRoute::kStarboard;
    case route::RouteSide::kOnRoute: return qc::SideOfRoute::kOnRoute;
    default: return qc::SideOfRoute::kUnknown;
  }
}

// Nearest taught node (by the simulator's along-route truth) to a sensed tile, as `qnav route eval` scores.
int true_node(const std::vector<double>& node_along, double along_m) {
  int truth = 0;
  double best = 1e300;
  for (std::size_t j = 0; j < node_along.size(); ++j)
    if (std::abs(node_along[j] - along_m) < best) best = std::abs(node_along[j] - along_m), truth = static_cast<int>(j);
  return truth;
}

std::vector<double> taught_nodes(const Recorder& rec) {
  std::vector<double> node_along;
  const std::uint32_t n = std::min<std::uint32_t>(rec.n.load(), kMaxTiles);
  for (std::uint32_t i = 0; i < n; ++i)
    if (rec.tiles[i].mode == qc::Mode::kTeach) node_along.push_back(rec.tiles[i].truth_along_m);
  return node_along;
}

// Repeat tiles after the first pass's two warm-up tiles: how many, and how many within +/-1 node.
struct NodeScore {
  std::uint32_t repeat_tiles = 0, eq5_tiles = 0, scored = 0, within1 = 0;
};
// taught: the recorder of the run that taught the route (default: the same run).
NodeScore score_nodes(const Recorder& rec, const Recorder* taught = nullptr) {
  const std::vector<double> node_along = taught_nodes(taught != nullptr ? *taught : rec);
  NodeScore out;
  const std::uint32_t n = std::min<std::uint32_t>(rec.n.load(), kMaxTiles);
  for (std::uint32_t i = 0; i < n; ++i) {
    const TileReport& r = rec.tiles[i];
    if (r.mode != qc::Mode::kRepeat) continue;
    out.eq5_tiles += r.eq5_motion;
    if (out.repeat_tiles++ < 2) continue;
    ++out.scored;
    out.within1 += std::abs(static_cast<int>(r.step.estimate) - true_node(node_along, r.truth_along_m)) <= 1;
  }
  return out;
}

TEST(QnavdMission, TeachThenRepeatForwardAndReverseMatchesTruthOnTheBus) {
  SoftwareFaults::reset_for_tests();
  const std::string dir = temp_dir();
  DaemonConfig c = sim_config(dir, 1500.0);
  const SimPass teach = sim_pass(qc::Mode::kTeach, 0.0, false), fwd = sim_pass(qc::Mode::kRepeat, 10.0, false),
                rev = sim_pass(qc::Mode::kRepeat, -20.0, true);
  ASSERT_TRUE(c.sim_mission.push_back(teach));
  ASSERT_TRUE(c.sim_mission.push_back(fwd));
  ASSERT_TRUE(c.sim_mission.push_back(rev));
  auto rec = std::make_unique<Recorder>();
  Daemon d(c);
  rec->daemon = &d;
  d.set_tile_observer(on_tile, rec.get());
  d.set_bus_observer(on_frame, rec.get());
  ASSERT_TRUE(d.init(nullptr));
  ASSERT_TRUE(d.start());
  test::AllocationGuard guard;
  std::uint64_t allocs = 0;
  {
    test::EigenMallocForbidden no_eigen_malloc;  // Debug builds: an Eigen heap allocation in any thread asserts
    EXPECT_EQ(d.run(), 0);
    allocs = guard.allocations();
  }
  EXPECT_TRUE(d.mission_done());
  EXPECT_EQ(SoftwareFaults::count(), 0u) << (SoftwareFaults::first().what ? SoftwareFaults::first().what : "");

  // The taught route: its nodes' truth positions along the route.
  const std::vector<double> node_along = taught_nodes(*rec);
  const std::uint32_t n = std::min<std::uint32_t>(rec->n.load(), kMaxTiles);
  ASSERT_GE(node_along.size(), 15u);
  tools::RouteFileReader reader;
  ASSERT_TRUE(reader.open((dir + "/route_1.qroute").c_str()));
  EXPECT_EQ(reader.node_count(), node_along.size());

  const double swath = 2.0 * std::sqrt(50.0 * 50.0 - 8.0 * 8.0);
  int scored = 0, within1 = 0, decided = 0, side_ok = 0, on_bus = 0, bus_agrees = 0;
  int pass_tile = 0;
  bool prev_rev = false;
  for (std::uint32_t i = 0; i < n; ++i) {
    const TileReport& r = rec->tiles[i];
    if (r.mode != qc::Mode::kRepeat) continue;
    if (r.reverse != prev_rev || (i > 0 && rec->tiles[i - 1].mode != qc::Mode::kRepeat)) pass_tile = 0;
    prev_rev = r.reverse;
    if (pass_tile++ < 2) continue;  // warm-up: the belief starts uniform (as qnav route eval scores)
    const int truth = true_node(node_along, r.truth_along_m);
    ++scored;
    within1 += std::abs(static_cast<int>(r.step.estimate) - truth) <= 1;
    const double lateral = (r.reverse ? -20.0 : 10.0) / 100.0 * swath;
    const qc::SideOfRoute want = expected_side(lateral, r.reverse, c.localiser.guidance.side_deadband_m);
    const qc::SideOfRoute got = wire(r.step.guidance.side);
    if (want != qc::SideOfRoute::kOnRoute && got != qc::SideOfRoute::kUnknown) {
      ++decided;
      side_ok += got == want;
    }
    if (rec->can_estimate[r.seq] >= 0) {
      ++on_bus;
      bus_agrees += rec->can_estimate[r.seq] == static_cast<int>(r.step.estimate) && rec->can_side[r.seq] == static_cast<int>(got);
    }
  }
  ASSERT_GT(scored, 20);
  const double pct1 = 100.0 * within1 / scored, pct_side = decided ? 100.0 * side_ok / decided : 0.0;
  std::printf("qnavd mission: %d repeat tiles scored, node +/-1 %.1f %%, side correct %.1f %% of %d decided, %d on the bus (%d agree), "
              "%llu heap allocations after start, %u deadline misses\n",
              scored, pct1, pct_side, decided, on_bus, bus_agrees, static_cast<unsigned long long>(allocs), d.nav().deadline_misses());
  EXPECT_GE(pct1, 95.0);
  EXPECT_GE(pct_side, 95.0);
  EXPECT_GE(decided, scored / 2);
  EXPECT_EQ(on_bus, scored) << "every repeat tile's ROUTE_STATUS must reach the autopilot";
  EXPECT_EQ(rec->stale_guidance.load(), 0u) << "no Tracking / Localised may be sent outside Repeat (a previous pass's guidance)";
  EXPECT_EQ(bus_agrees, on_bus);
  // Deadline misses depend on the machine's load (measured by the benchmark, not asserted here).
  EXPECT_EQ(rec->faults_seen.load() & ~qc::fault::kDeadlineMiss, 0u) << "no sensor fault may be reported while every sensor is healthy";
  if (test::malloc_counted()) {
    EXPECT_EQ(allocs, 0u) << guard.report();
  }
}

// A sensor of the simulated vehicle falls silent for a stretch of the repeat pass.
struct StallRun {
  std::unique_ptr<Recorder> rec = std::make_unique<Recorder>();
  NodeScore score;
};

// The mission every stall and fault run flies: teach over 1,200 m, then repeat 10 % to starboard.
void teach_repeat_config(const std::string& dir, DaemonConfig& c) {
  SoftwareFaults::reset_for_tests();
  c = sim_config(dir, 1200.0);
  ASSERT_TRUE(c.sim_mission.push_back(sim_pass(qc::Mode::kTeach, 0.0, false)));
  ASSERT_TRUE(c.sim_mission.push_back(sim_pass(qc::Mode::kRepeat, 10.0, false)));
}

// Flies d's mission with rec watching the tiles and the bus: it must end by itself, complete, with
// no software fault.
void fly(Daemon& d, Recorder& rec, const char* what) {
  d.set_tile_observer(on_tile, &rec);
  d.set_bus_observer(on_frame, &rec);
  ASSERT_TRUE(d.init(nullptr)) << what;
  ASSERT_TRUE(d.start()) << what;
  ASSERT_EQ(d.run(), 0) << what;
  EXPECT_TRUE(d.mission_done()) << what;
  EXPECT_EQ(SoftwareFaults::count(), 0u) << what;
}

void run_with_stall(const char* sensor, double start_s, double length_s, StallRun& out) {
  DaemonConfig c;
  teach_repeat_config(temp_dir(), c);
  if (::testing::Test::HasFatalFailure()) return;
  c.sim_stall = sensor;
  c.sim_stall_pass = 1;
  c.sim_stall_start_s = start_s;
  c.sim_stall_s = length_s;
  Daemon d(c);
  fly(d, *out.rec, sensor);
  if (::testing::Test::HasFatalFailure()) return;
  out.score = score_nodes(*out.rec);
  std::printf("stall %s %.0f s from %.0f s: %u repeat tiles (%u on the eq. 5 model), node +/-1 on %u of %u, faults seen 0x%x, %u hold-course frames\n",
              sensor, length_s, start_s, out.score.repeat_tiles, out.score.eq5_tiles, out.score.within1, out.score.scored,
              out.rec->faults_seen.load(), out.rec->hold_frames.load());
}

// route.learn (issue 29): a repeat appends its confirmed tiles to the route's companion ROUTE.exp,
// durably; the next repeat reads them; without the key nothing is written.
TEST(QnavdMission, ARepeatWithRouteLearnAddsExperiencesTheNextRepeatReads) {
  SoftwareFaults::reset_for_tests();
  const std::string dir = temp_dir();
  DaemonConfig c = sim_config(dir, 1200.0);
  ASSERT_TRUE(c.sim_mission.push_back(sim_pass(qc::Mode::kTeach, 0.0, false)));
  ASSERT_TRUE(c.sim_mission.push_back(sim_pass(qc::Mode::kRepeat, 10.0, false)));  // route.learn off: reads none, writes none
  auto taught = std::make_unique<Recorder>();
  {
    Daemon d(c);
    fly(d, *taught, "teach + repeat without route.learn");
    if (HasFatalFailure()) return;
    EXPECT_EQ(d.nav().repeat().learned(), 0u);
    EXPECT_EQ(d.nav().repeat().experience_errors(), 0u);
  }
  const std::string exp_path = dir + "/route_1.qroute.exp";
  struct stat st {};
  EXPECT_NE(::stat(exp_path.c_str(), &st), 0) << "a repeat without route.learn wrote " << exp_path;
  // Learning: two repeats of the taught route; the second reads what the first learnt.
  c.sim_mission.clear();
  c.route_learn = true;
  ASSERT_TRUE(c.sim_mission.push_back(sim_pass(qc::Mode::kRepeat, 10.0, false)));
  ASSERT_TRUE(c.sim_mission.push_back(sim_pass(qc::Mode::kRepeat, 15.0, false)));
  Daemon d(c);
  auto rec = std::make_unique<Recorder>();
  fly(d, *rec, "two repeats with route.learn");
  if (HasFatalFailure()) return;
  const NodeScore score = score_nodes(*rec, taught.get());
  std::printf("route.learn: %u experiences learnt, %u errors; node +/-1 on %u of %u repeat tiles\n", d.nav().repeat().learned(),
              d.nav().repeat().experience_errors(), score.within1, score.scored);
  EXPECT_GT(d.nav().repeat().learned(), 5u) << "a confident repeat at 10 % learns its tiles";
  EXPECT_EQ(d.nav().repeat().experience_errors(), 0u);
  ASSERT_EQ(::stat(exp_path.c_str(), &st), 0) << exp_path;
  EXPECT_GT(st.st_size, 10000) << "each experience is a record of its keypoints";
  EXPECT_GE(score.within1 * 100, score.scored * 95) << "the repeats localise with and after learning";
}

TEST(QnavdMission, DvlLossFallsBackToTheEq5ModelAndRecovers) {
  StallRun r;
  run_with_stall("dvl", 150.0, 200.0, r);  // 300 m of travel without velocities
  EXPECT_TRUE(r.rec->faults_seen.load() & qc::fault::kDvlLost);
  EXPECT_FALSE(r.rec->faults_seen.load() & (qc::fault::kSonarLost | qc::fault::kAttitudeLost));
  EXPECT_GE(r.score.eq5_tiles, 2u) << "tiles during the loss use the paper's motion model";
  EXPECT_LT(r.score.eq5_tiles, r.score.repeat_tiles) << "odometry returns with the DVL";
  EXPECT_GE(r.score.within1, r.score.scored * 8 / 10);
}

TEST(QnavdMission, SonarLossHoldsCourseInsteadOfStopping) {
  StallRun r;
  run_with_stall("sonar", 150.0, 60.0, r);
  EXPECT_TRUE(r.rec->faults_seen.load() & qc::fault::kSonarLost);
  // 60 s of silence, stale after sonar.stale_s = 2 s: ~58 s of ROUTE_STATUS (one per AHRS frame at
  // the replay's pace, 5 Hz), all "hold course".
  EXPECT_GT(r.rec->hold_frames.load(), 200u) << "the autopilot is told to hold course while the sonar is silent";
  EXPECT_FALSE(r.rec->faults_seen.load() & (qc::fault::kDvlLost | qc::fault::kAttitudeLost));
  EXPECT_GE(r.score.repeat_tiles, 10u) << "tiles resume after the stall";
}

TEST(QnavdMission, AttitudeLossIsReportedAndTilesResume) {
  StallRun r;
  run_with_stall("attitude", 150.0, 30.0, r);
  EXPECT_TRUE(r.rec->faults_seen.load() & qc::fault::kAttitudeLost);
  EXPECT_FALSE(r.rec->faults_seen.load() & qc::fault::kSonarLost);
  EXPECT_GE(r.score.repeat_tiles, 10u);
  EXPECT_GE(r.score.within1, r.score.scored * 8 / 10);
}

TEST(QnavdMission, DroneCanAhrsIsAnAttitudeSource) {
  SoftwareFaults::reset_for_tests();
  DaemonConfig c = sim_config(temp_dir(), 1200.0);
  c.sim_ahrs = "dronecan";  // uavcan.equipment.ahrs.Solution, multi-frame transfers on 29-bit ids
  ASSERT_TRUE(c.sim_mission.push_back(sim_pass(qc::Mode::kTeach, 0.0, false)));
  ASSERT_TRUE(c.sim_mission.push_back(sim_pass(qc::Mode::kRepeat, -15.0, true)));
  auto rec = std::make_unique<Recorder>();
  Daemon d(c);
  d.set_tile_observer(on_tile, rec.get());
  d.set_bus_observer(on_frame, rec.get());
  ASSERT_TRUE(d.init(nullptr));
  ASSERT_TRUE(d.start());
  ASSERT_EQ(d.run(), 0);
  EXPECT_TRUE(d.mission_done());
  const NodeScore sc = score_nodes(*rec);
  const std::uint32_t scored = sc.scored, within1 = sc.within1;
  ASSERT_GE(scored, 10u);
  EXPECT_GE(within1, scored * 95 / 100);
  EXPECT_EQ(rec->faults_seen.load() & ~qc::fault::kDeadlineMiss, 0u) << "the DroneCAN heading keeps the attitude alive";
  EXPECT_EQ(SoftwareFaults::count(), 0u);
}

TEST(QnavdMission, StopWhileTeachingKeepsEveryCompletedNode) {
  SoftwareFaults::reset_for_tests();
  const std::string dir = temp_dir();
  DaemonConfig c = sim_config(dir, 2000.0);
  ASSERT_TRUE(c.sim_mission.push_back(sim_pass(qc::Mode::kTeach, 0.0, false)));
  auto rec = std::make_unique<Recorder>();
  rec->stop_after.store(6);
  Daemon d(c);
  rec->daemon = &d;
  d.set_tile_observer(on_tile, rec.get());
  ASSERT_TRUE(d.init(nullptr));
  ASSERT_TRUE(d.start());
  EXPECT_EQ(d.run(), 0);
  EXPECT_FALSE(d.mission_done());
  tools::RouteFileReader reader;
  ASSERT_TRUE(reader.open((dir + "/route_1.qroute").c_str())) << "the route taught so far is committed on stop";
  EXPECT_GE(reader.node_count(), 6u);
  EXPECT_EQ(reader.torn_bytes(), 0u);
  std::vector<route::NodeMeta> meta;
  std::uint32_t bad = 0;
  EXPECT_TRUE(reader.read_all_meta(meta, &bad));
  EXPECT_EQ(SoftwareFaults::count(), 0u);
}

// A 400 m route taught into dir (route_1.qroute).
void teach_short_route(const std::string& dir) {
  DaemonConfig c = sim_config(dir, 400.0);
  ASSERT_TRUE(c.sim_mission.push_back(sim_pass(qc::Mode::kTeach, 0.0, false)));
  Daemon d(c);
  ASSERT_TRUE(d.init(nullptr));
  ASSERT_TRUE(d.start());
  EXPECT_EQ(d.run(), 0);
}

TEST(QnavdMission, AnEarlierInterruptedTeachIsKeptNotOverwritten) {
  const std::string dir = temp_dir();
  for (int round = 0; round < 2; ++round) {  // two earlier runs cut off: both kept, under distinct names
    FILE* f = std::fopen((dir + "/route_1.qroute.new").c_str(), "wb");
    ASSERT_NE(f, nullptr);
    std::fprintf(f, "interrupted run %d", round);
    std::fclose(f);
    teach_short_route(dir);
  }
  for (int round = 0; round < 2; ++round) {
    FILE* f = std::fopen((dir + "/route_1.qroute.new.kept." + std::to_string(round + 1)).c_str(), "rb");
    ASSERT_NE(f, nullptr) << "kept file " << round + 1;
    char buf[64] = {};
    const std::size_t n = std::fread(buf, 1, sizeof buf - 1, f);
    std::fclose(f);
    EXPECT_EQ(std::string(buf, n), "interrupted run " + std::to_string(round));
  }
  tools::RouteFileReader r;
  EXPECT_TRUE(r.open((dir + "/route_1.qroute").c_str()));
}

TEST(QnavdMission, DamagedRouteIsRefusedAndTheDaemonCarriesOn) {
  SoftwareFaults::reset_for_tests();
  const std::string dir = temp_dir();
  teach_short_route(dir);
  const std::string path = dir + "/route_1.qroute";
  FILE* f = std::fopen(path.c_str(), "r+b");
  ASSERT_NE(f, nullptr);
  std::fseek(f, 200, SEEK_SET);  // inside node 0's record
  std::fputc(0x5A, f);
  std::fclose(f);
  DaemonConfig c = sim_config(dir, 400.0);
  ASSERT_TRUE(c.sim_mission.push_back(sim_pass(qc::Mode::kRepeat, 0.0, false)));
  ASSERT_TRUE(c.sim_mission.push_back(sim_pass(qc::Mode::kHold, 0.0, false)));
  Daemon d(c);
  ASSERT_TRUE(d.init(nullptr));
  ASSERT_TRUE(d.start());
  EXPECT_EQ(d.run(), 0);
  EXPECT_TRUE(d.mission_done());
  EXPECT_EQ(SoftwareFaults::count(), 0u);
}

TEST(QnavdMission, MissingCanInterfaceIsAClearStartUpError) {
  DaemonConfig c = sim_config(temp_dir(), 400.0);
  c.backend = Backend::kLinux;
  c.can_interface = "qnavnone0";
  Daemon d(c);
  const Status s = d.init(nullptr);
  EXPECT_FALSE(s);
}


// ---- Fault injection (sim.fault): damaged or disordered input during the repeat pass ----
// Each fault runs from 100 s (start_s) for `length_s` of the repeat pass (teach + repeat over 1,200 m). The
// daemon must count every damaged sample (faults_injected, from the simulator, against its own
// counters), keep navigating (tiles and ROUTE_STATUS for every repeat tile), report the state the
// fault implies, and recover after it.
struct FaultRun {
  std::unique_ptr<Recorder> rec = std::make_unique<Recorder>();
  NodeScore score;
  std::uint32_t injected = 0;
  std::uint32_t dvl_rejected = 0, can_rejected = 0, error_frames = 0, pings_rejected = 0, pings_out_of_order = 0, writer_errors = 0;
  std::uint32_t final_faults = 0;
  std::uint32_t route_nodes = 0;
  bool route_intact = false;
};

// recovers: the fault word is clear again by the end of the pass (false for a latched fault: a leak).
void run_with_fault(const char* kind, int pass, double length_s, FaultRun& out, double start_s = 100.0, bool recovers = true) {
  const std::string dir = temp_dir();
  DaemonConfig c;
  teach_repeat_config(dir, c);
  if (::testing::Test::HasFatalFailure()) return;
  c.sim_fault = kind;
  c.sim_fault_pass = pass;
  c.sim_fault_start_s = start_s;
  c.sim_fault_s = length_s;
  Daemon d(c);
  fly(d, *out.rec, kind);
  if (::testing::Test::HasFatalFailure()) return;
  out.score = score_nodes(*out.rec);
  const IoCounters& io = d.io_counters();
  out.injected = io.faults_injected.load();
  out.dvl_rejected = io.dvl_rejected.load();
  out.can_rejected = d.nav().inputs().can_rejected();
  out.error_frames = d.nav().inputs().receiver().counters().get(qc::RxCounter::kErrorFrame);
  out.pings_rejected = d.nav().pings_rejected();
  out.pings_out_of_order = d.nav().pings_out_of_order();
  out.writer_errors = d.nav().writer_errors();
  out.final_faults = out.rec->last_faults.load();
  tools::RouteFileReader reader;
  if (reader.open((dir + "/route_1.qroute").c_str())) {
    out.route_nodes = reader.node_count();
    route::NodeMeta m;
    out.route_intact = true;
    for (std::uint32_t i = 0; i < reader.node_count(); ++i) out.route_intact = out.route_intact && reader.load_meta(i, m).is_ok();
  }
  std::printf("fault %s %.1f s: %u injected; rejected dvl %u, can %u (error frames %u), pings %u, out of order %u; writer errors %u; "
              "%u repeat tiles, node +/-1 on %u of %u; faults seen 0x%x, at the end 0x%x\n",
              kind, length_s, out.injected, out.dvl_rejected, out.can_rejected, out.error_frames, out.pings_rejected, out.pings_out_of_order,
              out.writer_errors, out.score.repeat_tiles, out.score.within1, out.score.scored, out.rec->faults_seen.load(), out.final_faults);
  EXPECT_GT(out.injected, 0u) << kind << ": the simulator injected nothing";
  if (recovers) {
    EXPECT_EQ(out.final_faults & ~qc::fault::kDeadlineMiss, 0u) << kind << ": recovered by the end of the pass";
  }
}

TEST(QnavdFaults, DamagedDvlSentencesAreRejectedAndCounted) {
  // 0.5 s of NaN: shorter than dvl.stale_s, so the DVL is never reported lost. Duplicates and line
  // noise come with every good sentence, so it never is either.
  for (const char* kind : {"dvl_nan", "dvl_duplicate", "dvl_line_noise"}) {
    FaultRun r;
    run_with_fault(kind, 1, std::strcmp(kind, "dvl_nan") == 0 ? 0.5 : 20.0, r);
    EXPECT_GE(r.dvl_rejected, r.injected) << kind;
    EXPECT_LE(r.dvl_rejected, r.injected + 5u) << kind << ": rejections beyond the injected ones";
    EXPECT_FALSE(r.rec->faults_seen.load() & qc::fault::kDvlLost) << kind << ": good sentences kept coming";
    EXPECT_GE(r.score.within1, r.score.scored * 8 / 10) << kind;
  }
}

TEST(QnavdFaults, ADvlClockSteppedBackIsStaleUntilItPassesTheLastGoodTime) {
  // For 20 s the DVL's time of validity runs 5 s behind: the sentences stamped at or before the last
  // accepted one (the first 5 s, 5 Hz) are stale, counted, and the DVL is reported lost meanwhile;
  // then its clock is past the last good time again and its velocities are used.
  FaultRun r;
  run_with_fault("dvl_time_back", 1, 20.0, r);
  EXPECT_GE(r.dvl_rejected, 24u);
  EXPECT_LE(r.dvl_rejected, 30u);
  EXPECT_TRUE(r.rec->faults_seen.load() & qc::fault::kDvlLost);
  EXPECT_GE(r.score.within1, r.score.scored * 8 / 10);
}

TEST(QnavdFaults, LongDvlNanIsADvlLossAndRecovers) {
  FaultRun r;
  run_with_fault("dvl_nan", 1, 20.0, r);
  EXPECT_GE(r.dvl_rejected, r.injected);
  EXPECT_TRUE(r.rec->faults_seen.load() & qc::fault::kDvlLost) << "20 s of unusable velocities is a DVL loss";
  EXPECT_GE(r.score.within1, r.score.scored * 8 / 10);
}

TEST(QnavdFaults, DamagedAttitudeFramesAreRejectedAndCounted) {
  for (const char* kind : {"attitude_out_of_range", "attitude_duplicate"}) {
    FaultRun r;
    run_with_fault(kind, 1, 20.0, r);
    EXPECT_GE(r.can_rejected, r.injected) << kind;
    if (std::strcmp(kind, "attitude_out_of_range") == 0) {
      EXPECT_TRUE(r.rec->faults_seen.load() & qc::fault::kAttitudeLost) << "20 s without a usable heading";
    } else {
      EXPECT_FALSE(r.rec->faults_seen.load() & qc::fault::kAttitudeLost) << "the first copy of each frame is good";
    }
    EXPECT_GE(r.score.repeat_tiles, 10u) << kind;
  }
}

TEST(QnavdFaults, CanErrorFramesAndBusOffAreCountedAndReported) {
  FaultRun e;
  run_with_fault("can_error_frames", 1, 20.0, e);
  EXPECT_EQ(e.error_frames, e.injected);
  EXPECT_FALSE(e.rec->faults_seen.load() & qc::fault::kBusOff);
  EXPECT_GE(e.score.within1, e.score.scored * 8 / 10);
  FaultRun b;
  run_with_fault("can_bus_off", 1, 20.0, b);
  EXPECT_TRUE(b.rec->faults_seen.load() & qc::fault::kBusOff) << "bus-off is reported until the controller restarts";
  EXPECT_GE(b.score.within1, b.score.scored * 8 / 10);
}

TEST(QnavdFaults, DamagedAndDisorderedPingsAreRejectedAndCounted) {
  for (const char* kind : {"sonar_nan", "sonar_bad_range"}) {
    FaultRun r;
    run_with_fault(kind, 1, 20.0, r);
    EXPECT_EQ(r.pings_rejected, r.injected) << kind;
    EXPECT_GE(r.score.repeat_tiles, 10u) << kind;
  }
  FaultRun t;
  run_with_fault("ping_time_back", 1, 2.0, t);  // stamped 3 s in the past for 2 s: every one out of order
  EXPECT_EQ(t.pings_out_of_order, t.injected);
  EXPECT_GE(t.score.within1, t.score.scored * 8 / 10);
}

TEST(QnavdFaults, ALeakIsLatchedInHealthWithinOnePeriodAndNavigationGoesOn) {
  // Water at the detector (the simulated GPIO line, through the daemon's LeakMonitor) for 1 s from
  // 100 s into the repeat pass: HEALTH.Leak within one HEALTH period (1 s), FaultLeak in NAV_STATUS,
  // both latched to the end (the line dried, the vehicle must still surface), and the repeat pass
  // goes on localising.
  FaultRun r;
  run_with_fault("leak", 1, 1.0, r, 100.0, false);
  EXPECT_EQ(r.injected, 1u);
  ASSERT_GE(r.rec->repeat_start_ns.load(), 0);
  ASSERT_GE(r.rec->first_leak_ns.load(), 0) << "no HEALTH frame with Leak = 1";
  const double after_s = static_cast<double>(r.rec->first_leak_ns.load() - r.rec->repeat_start_ns.load()) * 1e-9 - 100.0;
  std::printf("leak: HEALTH.Leak %.3f s after the line went active\n", after_s);
  EXPECT_GT(after_s, -0.3) << "reported before the water came (the pass starts within one NAV_STATUS period of the first Repeat frame)";
  EXPECT_LT(after_s, 1.3) << "later than one HEALTH period";
  EXPECT_EQ(r.rec->leak_cleared.load(), 0u) << "the leak is latched";
  EXPECT_TRUE(r.final_faults & qc::fault::kLeak);
  EXPECT_TRUE(r.rec->faults_seen.load() & qc::fault::kLeak);
  EXPECT_EQ(r.final_faults & ~(qc::fault::kLeak | qc::fault::kDeadlineMiss), 0u);
  EXPECT_GE(r.score.within1, r.score.scored * 8 / 10);
}

TEST(QnavdFaults, AFullDiskWhileTeachingEndsTheRouteAtItsLastDurableNode) {
  // The disk is full from 400 s to 460 s of the teach pass: the first node that cannot be written
  // ends the route there (no gap), the route is committed with the nodes before it, and the repeat
  // pass localises on that prefix.
  FaultRun r;
  run_with_fault("disk_full", 0, 60.0, r, 400.0);
  EXPECT_EQ(r.writer_errors, 1u) << "one failed append, then no more attempts on this route";
  EXPECT_TRUE(r.route_intact) << "every node in the route file decodes";
  const std::size_t taught = taught_nodes(*r.rec).size();
  EXPECT_GE(r.route_nodes, 3u) << "the nodes taught before the disk filled are kept";
  EXPECT_LT(r.route_nodes, taught) << "nothing is appended after the failure";
  // Repeat tiles over the kept prefix localise; beyond its end they cannot.
  std::uint32_t scored = 0, within1 = 0;
  const std::vector<double> node_along = taught_nodes(*r.rec);
  const double end_along = node_along[r.route_nodes - 1];
  bool warm = false;
  for (std::uint32_t i = 0, seen = 0; i < std::min<std::uint32_t>(r.rec->n.load(), kMaxTiles); ++i) {
    const TileReport& t = r.rec->tiles[i];
    if (t.mode != qc::Mode::kRepeat) continue;
    if (++seen <= 2 || t.truth_along_m > end_along - 10.0) continue;
    warm = true;
    ++scored;
    const std::vector<double> prefix(node_along.begin(), node_along.begin() + r.route_nodes);
    within1 += std::abs(static_cast<int>(t.step.estimate) - true_node(prefix, t.truth_along_m)) <= 1;
  }
  ASSERT_TRUE(warm);
  EXPECT_GE(within1, scored * 8 / 10) << within1 << " of " << scored;
}

}  // namespace
}  // namespace qnav::daemon
