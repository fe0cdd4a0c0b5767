// sim.speed (issue #31): SimPacer keeps absolute deadlines (no drift however late the steps wake),
// counts a late step and never skips one; the monotonic clock sleeps to an absolute deadline; the same
// mission flown fast and at 20x gives the same tiles (the log's tile lines byte for byte, latency
// aside) and the same route file; a missing sim.can_interface is a start-up error that names it.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <unistd.h>

#include "drivers/qnavcan/messages.hpp"
#include "firmware/qnavd/daemon.hpp"
#include "firmware/qnavd/sim_pacer.hpp"
#include "hal/linux/monotonic_clock.hpp"
#include "hal/sim/manual_clock.hpp"

namespace qnav::daemon {
namespace {

namespace qc = drivers::qnavcan;

constexpr std::int64_t kMs = 1000000;

TEST(SimPacer, SleepsToAbsoluteDeadlinesSoWorkBetweenStepsDoesNotDrift) {
  hal::ManualClock wall(5 * kMs);
  SimPacer p(wall, 2.0);  // twice real time: 10 ms of mission every 5 ms of wall
  p.start(1000 * kMs);
  std::int64_t work_total_ns = 0;
  for (int i = 1; i <= 1000; ++i) {
    const std::int64_t work = (i * 7919) % 4 * kMs / 2;  // 0 to 1.5 ms of work before each step
    wall.advance_ns(work);
    work_total_ns += work;
    const std::int64_t t = 1000 * kMs + i * 10 * kMs;
    while (!p.due(t)) {
      ASSERT_TRUE(p.waiting());
      p.sleep(SimPacer::kPollSliceNs);
    }
    EXPECT_EQ(wall.now_ns(), 5 * kMs + i * 5 * kMs) << "step " << i;  // its deadline, not its wake-up + 5 ms
  }
  EXPECT_GT(work_total_ns, 500 * kMs);  // relative sleeps would have drifted by this much
  EXPECT_EQ(p.steps(), 1000u);
  EXPECT_EQ(p.late_steps(), 0u);
  EXPECT_EQ(p.max_late_ns(), 0);
}

TEST(SimPacer, ALateStepIsCountedAndTakenNeverSkipped) {
  hal::ManualClock wall(0);
  SimPacer p(wall, 1.0);
  p.start(0);
  int taken = 0;
  for (int i = 1; i <= 20; ++i) {
    if (i == 5) wall.advance_ns(45 * kMs);  // a stall of 45 ms before step 5 (10 ms steps)
    const std::int64_t t = i * 10 * kMs;
    while (!p.due(t)) p.sleep(SimPacer::kPollSliceNs);
    ++taken;
  }
  EXPECT_EQ(taken, 20);
  EXPECT_EQ(p.steps(), 20u);
  // Step 5 due at 50 ms, taken at 85 ms (35 ms late); 6 at 85 (25 late), 7 at 85 (15 late), 8 at
  // 85 (5 ms: within the 10 ms tolerance); then on time again.
  EXPECT_EQ(p.late_steps(), 3u);
  EXPECT_EQ(p.max_late_ns(), 35 * kMs);
  EXPECT_EQ(wall.now_ns(), 200 * kMs);
}

TEST(SimPacer, SpeedZeroIsAsFastAsTheCallerGoes) {
  hal::ManualClock wall(0);
  SimPacer p(wall, SimSpeed::kFast);
  p.start(0);
  EXPECT_FALSE(p.paced());
  EXPECT_TRUE(p.due(3600000 * kMs));
  EXPECT_FALSE(p.waiting());
  EXPECT_FALSE(p.sleep(SimPacer::kPollSliceNs));
  EXPECT_EQ(wall.now_ns(), 0);
}

TEST(SimPacer, ASleepIsSlicedSoTheCallerStillPolls) {
  hal::ManualClock wall(0);
  SimPacer p(wall, 1.0);
  p.start(0);
  ASSERT_FALSE(p.due(7 * kMs));
  EXPECT_TRUE(p.sleep(SimPacer::kPollSliceNs));
  EXPECT_EQ(wall.now_ns(), SimPacer::kPollSliceNs);
  EXPECT_TRUE(p.sleep(100 * kMs));
  EXPECT_EQ(wall.now_ns(), 7 * kMs);  // never past the deadline
  EXPECT_FALSE(p.sleep(100 * kMs));   // its deadline has come: nothing to sleep for (the lockstep may hold the step)
  EXPECT_EQ(wall.now_ns(), 7 * kMs);
  EXPECT_TRUE(p.due(7 * kMs));
}

TEST(MonotonicClock, SleepsToAnAbsoluteDeadline) {
  hal::MonotonicClock c;
  const std::int64_t deadline = c.now_ns() + 3 * kMs;
  EXPECT_TRUE(c.sleep_until_ns(deadline));
  EXPECT_GE(c.now_ns(), deadline);
  const std::int64_t before = c.now_ns();
  EXPECT_TRUE(c.sleep_until_ns(before - 10 * kMs));  // a deadline in the past returns at once
}

// ---- The daemon ----------------------------------------------------------------------------------

std::string temp_dir() {
  char t[] = "/tmp/qnavd_pacing_test_XXXXXX";
  const char* d = mkdtemp(t);
  return d ? std::string(d) : std::string("/tmp");
}

// The shortest survey (200 m): teach, then repeat 10 % of the swath to the right (277 s of mission).
DaemonConfig short_mission(const std::string& dir, double speed) {
  DaemonConfig c;
  c.backend = Backend::kSim;
  c.route_dir = dir;
  c.log = LogFormat::kJson;
  c.health_period_s = 3600.0;
  c.realtime = false;
  c.vo_enabled = false;
  c.sim_length_m = 200.0;
  c.sim_speed = speed;
  c.tile_budget_us = 10000000;
  c.ping_budget_us = 1000000;
  SimPass teach, repeat;
  teach.mode = qc::Mode::kTeach;
  repeat.mode = qc::Mode::kRepeat;
  repeat.offset_pct = 10.0;
  (void)c.sim_mission.push_back(teach);
  (void)c.sim_mission.push_back(repeat);
  return c;
}

struct Flown {
  std::string tiles;  // the log's tile lines, latency_ms removed (the only wall-time field)
  std::string route;  // route_1.qroute, byte for byte
  std::size_t tile_lines = 0, repeat_tiles = 0;
  double wall_s = 0.0, mission_s = 0.0;
  unsigned late_steps = 0;
};

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

Flown fly(double speed) {
  const std::string dir = temp_dir();
  const std::string log_path = dir + "/qnavd.log";
  FILE* log = std::fopen(log_path.c_str(), "w");
  EXPECT_NE(log, nullptr);
  Flown out;
  {
    Daemon d(short_mission(dir, speed));
    EXPECT_TRUE(d.init(log));
    EXPECT_TRUE(d.start());
    const std::int64_t t0 = hal::monotonic_now_ns();
    EXPECT_EQ(d.run(), 0);
    out.wall_s = static_cast<double>(hal::monotonic_now_ns() - t0) * 1e-9;
    EXPECT_TRUE(d.mission_done());
    out.late_steps = d.io_counters().sim_late_steps.load();
  }
  std::fclose(log);
  std::istringstream in(read_file(log_path));
  std::string line;
  while (std::getline(in, line)) {
    if (line.find("\"event\":\"sim_pace\"") != std::string::npos) {
      const std::size_t k = line.find("\"mission_s\":");
      out.mission_s = std::strtod(line.c_str() + k + 12, nullptr);
    }
    if (line.find("\"event\":\"tile\"") == std::string::npos) continue;
    const std::size_t lat = line.find(",\"latency_ms\":");
    EXPECT_NE(lat, std::string::npos) << line;
    out.tiles += line.substr(0, lat) + "\n";
    ++out.tile_lines;
    out.repeat_tiles += line.find("\"mode\":\"repeat\"") != std::string::npos;
  }
  out.route = read_file(dir + "/route_1.qroute");
  return out;
}

TEST(QnavdPacing, TheSameMissionFastAndAtTwentyTimesGivesTheSameTilesAndRoute) {
  const Flown fast = fly(SimSpeed::kFast);
  const Flown paced = fly(20.0);
  ASSERT_GE(fast.tile_lines, 5u);
  EXPECT_GE(fast.repeat_tiles, 2u);
  EXPECT_FALSE(fast.route.empty());
  EXPECT_EQ(paced.tiles, fast.tiles);  // seq, mission time, estimate, p, entropy, inliers, status, side, cross-track, sigma ...
  EXPECT_EQ(paced.route, fast.route);
  // Paced: the mission took at least its mission time / 20 of wall time (the pacer waited), and the
  // sim_pace line reported the whole mission.
  EXPECT_GT(paced.mission_s, 270.0);
  EXPECT_GE(paced.wall_s, paced.mission_s / 20.0 * 0.99);
  std::printf("fast: %.2f s wall; 20x: %.2f s wall for %.1f s of mission, %u late steps\n", fast.wall_s, paced.wall_s, paced.mission_s,
              paced.late_steps);
}

TEST(QnavdPacing, AMissingCanInterfaceIsAStartUpErrorThatNamesIt) {
  DaemonConfig c = short_mission(temp_dir(), 1.0);
  c.log = LogFormat::kOff;
  c.sim_can_interface = "qnavnone7";  // no such interface (nor, on this host, CAN sockets at all)
  Daemon d(c);
  const Status s = d.init(nullptr);
  ASSERT_FALSE(s);
  EXPECT_NE(std::string(s.message()).find("sim.can_interface"), std::string::npos) << s.message();
}

}  // namespace
}  // namespace qnav::daemon
