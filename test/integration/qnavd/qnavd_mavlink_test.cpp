// qnavd as a MAVLink external navigation source, in-process on the sim backend, over real UDP on
// 127.0.0.1: the test is the autopilot (a UDP server qnavd's mavlink.udp_remote points at).
//  - a short teach-and-repeat mission: ODOMETRY at mavlink.odometry_hz in mission time, LOCAL_FRD /
//    BODY_FRD, quality and velocity set; reset_counter changes on route fixes in Repeat;
//    DISTANCE_SENSOR with the DVL altitude; HEARTBEAT; mode commands from the autopilot acknowledged,
//    from another system refused and counted; garbage, foreign systems and unknown messages counted;
//  - a DVL stall: ODOMETRY quality -1 within one period, no VISION_POSITION_DELTA during the loss.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <sys/socket.h>
#include <vector>

#include "drivers/mavlink/messages.hpp"
#include "drivers/mavlink/parser.hpp"
#include "drivers/qnavcan/messages.hpp"
#include "firmware/qnavd/daemon.hpp"
#include "firmware/qnavd/mavlink_endpoint.hpp"
#include "firmware/qnavd/software_fault.hpp"
#include "hal/linux/monotonic_clock.hpp"
#include "hal/linux/udp_port.hpp"
#include "test/support/alloc_guard.hpp"

namespace qnav::daemon {
namespace {

namespace mav = drivers::mavlink;
namespace qc = drivers::qnavcan;

std::string temp_dir() {
  char t[] = "/tmp/qnavd_mav_XXXXXX";
  const char* d = mkdtemp(t);
  return d ? std::string(d) : std::string("/tmp");
}

// The autopilot's side: reads what qnavd sends, sends what the test asks for.
struct Autopilot {
  hal::UdpPort port;
  mav::Parser parser;
  mav::FrameEncoder enc{1, 1};  // ArduSub: system 1, MAV_COMP_ID_AUTOPILOT1
  std::mutex mu;
  std::vector<mav::Odometry> odo;
  std::vector<mav::VisionPositionDelta> vpd;
  std::vector<mav::DistanceSensor> ds;
  std::vector<mav::CommandAck> acks;
  std::vector<std::array<char, 51>> texts;
  std::vector<mav::SetPositionTargetLocalNed> targets;
  std::vector<double> target_dist_m;  // from the newest ODOMETRY position when the target arrived
  int heartbeats = 0, named = 0, from_other = 0;
  std::vector<std::uint8_t> raw;            // every byte qnavd sent (the node-mavlink check reads it)
  std::vector<std::uint32_t> msgids;        // every frame qnav's parser found, in order
  std::atomic<bool> stop{false};
  std::thread reader;
  bool lossless = false;  // the receive buffer holds a whole mission (else a loaded machine may drop datagrams)

  void start() {
    // Room for a whole short mission, so the reader allocates nothing while qnavd runs (the
    // allocation guard counts every thread).
    odo.reserve(20000), vpd.reserve(20000), ds.reserve(20000), acks.reserve(64), texts.reserve(256), targets.reserve(4096);
    target_dist_m.reserve(4096), raw.reserve(8u << 20), msgids.reserve(100000);
    ASSERT_TRUE(port.open_server(0, "127.0.0.1"));
    // The simulated mission runs many times faster than real time (~10,000 datagrams a second): a
    // receive buffer that holds a whole mission, so a reader thread descheduled on a loaded machine
    // loses nothing (FORCE needs CAP_NET_ADMIN; otherwise net.core.rmem_max caps the plain request).
    const int bytes = 64 << 20;
    if (setsockopt(port.fd(), SOL_SOCKET, SO_RCVBUFFORCE, &bytes, sizeof bytes) != 0)
      (void)setsockopt(port.fd(), SOL_SOCKET, SO_RCVBUF, &bytes, sizeof bytes);
    int got = 0;
    socklen_t len = sizeof got;
    if (getsockopt(port.fd(), SOL_SOCKET, SO_RCVBUF, &got, &len) == 0) lossless = got >= (16 << 20);
    reader = std::thread([this] {
      std::uint8_t buf[2048];
      while (!stop.load()) {
        Result<hal::SerialRead> r = port.read(Span<std::uint8_t>(buf, sizeof buf), 20);
        if (!r || r.value().bytes == 0) continue;
        std::lock_guard<std::mutex> lock(mu);
        raw.insert(raw.end(), buf, buf + r.value().bytes);
        parser.feed(Span<const std::uint8_t>(buf, r.value().bytes), [&](const mav::Frame& f) {
          msgids.push_back(f.msgid);
          if (f.sysid != 1 || f.compid != 197) {
            ++from_other;
            return;
          }
          mav::Odometry o;
          mav::VisionPositionDelta d;
          mav::DistanceSensor s;
          mav::CommandAck a;
          mav::StatusText st;
          mav::SetPositionTargetLocalNed p;
          if (mav::decode(f, o)) odo.push_back(o);
          if (mav::decode(f, d)) vpd.push_back(d);
          if (mav::decode(f, s)) ds.push_back(s);
          if (mav::decode(f, a)) acks.push_back(a);
          if (mav::decode(f, st)) {
            std::array<char, 51> t{};
            std::memcpy(t.data(), st.text, sizeof st.text);
            texts.push_back(t);
          }
          if (mav::decode(f, p)) {
            targets.push_back(p);
            target_dist_m.push_back(odo.empty() ? 1e9 : std::hypot(static_cast<double>(p.x - odo.back().x), static_cast<double>(p.y - odo.back().y)));
          }
          heartbeats += f.msgid == mav::Heartbeat::kId;
          named += f.msgid == mav::NamedValueFloat::kId;
        });
      }
    });
  }
  void finish() {
    stop.store(true);
    if (reader.joinable()) reader.join();
  }
  std::uint16_t port_number() const { return port.local_port(); }
  template <typename M>
  void send(const M& m, std::uint8_t sysid = 1, std::uint8_t compid = 1) {
    if (!peer()) return;  // qnavd not heard yet: a UDP server has nowhere to send
    mav::FrameEncoder e(sysid, compid);
    std::uint8_t b[mav::kMaxFrameBytes];
    Result<std::size_t> n = mav::encode(sysid == 1 && compid == 1 ? enc : e, m, Span<std::uint8_t>(b, sizeof b));
    ASSERT_TRUE(n);
    ASSERT_TRUE(port.write(Span<const std::uint8_t>(b, n.value())));
  }
  void send_raw(const std::uint8_t* b, std::size_t n) { (void)port.write(Span<const std::uint8_t>(b, n)); }
  bool peer() const { return port.has_peer(); }
};

DaemonConfig mav_config(const std::string& dir, std::uint16_t ap_port) {
  SoftwareFaults::reset_for_tests();
  DaemonConfig c;
  c.backend = Backend::kSim;
  c.route_dir = dir;
  c.log = LogFormat::kOff;
  c.realtime = false;
  c.sim_length_m = 400.0;
  c.sim_seed = 1;
  c.sim_speed = SimSpeed::kFast;
  c.tile_budget_us = 10000000;
  c.ping_budget_us = 1000000;
  c.mavlink_enabled = true;
  // The sim's mission clock moves from one sensor instant to the next; with mavlink.enabled its AHRS
  // also streams between the 5 Hz pings on the odometry grid (SimVehicle::ahrs_tick), so ODOMETRY
  // keeps mavlink.odometry_hz (the default 10 Hz) in mission time too.
  c.mavlink_udp_remote = "127.0.0.1:" + std::to_string(ap_port);
  SimPass teach, repeat;
  teach.mode = qc::Mode::kTeach;
  repeat.mode = qc::Mode::kRepeat;
  repeat.offset_pct = 10.0;
  EXPECT_TRUE(c.sim_mission.push_back(teach));
  EXPECT_TRUE(c.sim_mission.push_back(repeat));
  return c;
}

// With QNAVD_MAVLINK_CAPTURE=PATH: PATH.bin, every byte qnavd sent, and PATH.json, what qnav's own
// parser found in them (message ids in order, every ODOMETRY's fields), for test/peer/mavlink's
// node-mavlink check of the daemon's output (ctest -L mavlink_peer).
void write_capture(const Autopilot& ap) {
  const char* path = std::getenv("QNAVD_MAVLINK_CAPTURE");
  if (path == nullptr) return;
  const std::string base(path);
  FILE* f = std::fopen((base + ".bin").c_str(), "wb");
  ASSERT_NE(f, nullptr);
  std::fwrite(ap.raw.data(), 1, ap.raw.size(), f);
  std::fclose(f);
  f = std::fopen((base + ".json").c_str(), "w");
  ASSERT_NE(f, nullptr);
  const auto num = [](float v) {
    char b[32];
    if (std::isnan(v)) return std::string("\"NaN\"");
    std::snprintf(b, sizeof b, "\"%.9g\"", static_cast<double>(v));
    return std::string(b);
  };
  std::fprintf(f, "{\"msgids\":[");
  for (std::size_t i = 0; i < ap.msgids.size(); ++i) std::fprintf(f, "%s%u", i ? "," : "", ap.msgids[i]);
  std::fprintf(f, "],\n\"odometry\":[");
  for (std::size_t i = 0; i < ap.odo.size(); ++i) {
    const mav::Odometry& o = ap.odo[i];
    std::fprintf(f, "%s{\"time_usec\":\"%llu\",\"frame_id\":%u,\"child_frame_id\":%u,\"x\":%s,\"y\":%s,\"z\":%s,\"q\":[%s,%s,%s,%s],"
                 "\"vx\":%s,\"vy\":%s,\"vz\":%s,\"reset_counter\":%u,\"estimator_type\":%u,\"quality\":%d}\n",
                 i ? "," : "", static_cast<unsigned long long>(o.time_usec), o.frame_id, o.child_frame_id, num(o.x).c_str(), num(o.y).c_str(),
                 num(o.z).c_str(), num(o.q[0]).c_str(), num(o.q[1]).c_str(), num(o.q[2]).c_str(), num(o.q[3]).c_str(), num(o.vx).c_str(),
                 num(o.vy).c_str(), num(o.vz).c_str(), o.reset_counter, o.estimator_type, o.quality);
  }
  std::fprintf(f, "]}\n");
  std::fclose(f);
}

mav::CommandLong mode_command(qc::Mode m, std::uint16_t route_id) {
  mav::CommandLong c;
  c.target_system = 1;
  c.target_component = 197;
  c.command = kMavCmdSetMode;
  c.param1 = static_cast<float>(static_cast<int>(m));
  c.param2 = route_id;
  return c;
}

TEST(QnavdMavlink, ShortMissionPublishesOdometryAndAnswersOnlyTheAutopilot) {
  Autopilot ap;
  ap.start();
  if (::testing::Test::HasFatalFailure()) return;
  const DaemonConfig c = mav_config(temp_dir(), ap.port_number());
  Daemon d(c);
  ASSERT_TRUE(d.init(nullptr));
  ASSERT_TRUE(d.start());
  // The autopilot's traffic while the mission flies: its heartbeat, then (once qnavd was heard) a
  // mode command from itself and one from another system, garbage, a foreign system, an unknown id.
  std::thread talker([&] {
    bool sent = false;
    for (int i = 0; i < 2000 && !d.mission_done(); ++i) {
      mav::Heartbeat h;
      h.type = 12;  // MAV_TYPE_SUBMARINE
      h.autopilot = 3;
      ap.send(h);
      if (!sent && ap.peer()) {
        ap.send(mode_command(qc::Mode::kTeach, c.route_id));          // the mode it is in: accepted, nothing changes
        ap.send(mode_command(qc::Mode::kIdle, c.route_id), 7, 1);     // another system: refused, never acted on
        const std::uint8_t garbage[] = {0x00, 0x11, 0xFD, 0x09, 0x00, 0x00, 0x00, 0x01, 0x01, 0x00, 0x00, 0x00, 0x55, 0x66, 0x77};
        ap.send_raw(garbage, sizeof garbage);
        const std::uint8_t unknown_id[] = {0xFD, 0x01, 0x00, 0x00, 0x00, 0x01, 0x01, 0x39, 0x30, 0x00, 0x42, 0x12, 0x34};  // msg 12345
        ap.send_raw(unknown_id, sizeof unknown_id);
        ap.send(h, 42, 1);  // a foreign system's heartbeat
        sent = true;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  });
  EXPECT_EQ(d.run(), 0);
  talker.join();
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  ap.finish();
  ASSERT_NE(d.nav().mavlink(), nullptr);
  const MavlinkEndpoint& ep = *d.nav().mavlink();
  std::lock_guard<std::mutex> lock(ap.mu);
  ASSERT_GT(ap.odo.size(), 100u);
  // Rate in mission time (time_usec is the mission clock).
  const double span_s = static_cast<double>(ap.odo.back().time_usec - ap.odo.front().time_usec) * 1e-6;
  const double rate_hz = static_cast<double>(ap.odo.size() - 1) / span_s;
  std::vector<double> gaps;
  for (std::size_t i = 1; i < ap.odo.size(); ++i) gaps.push_back(static_cast<double>(ap.odo[i].time_usec - ap.odo[i - 1].time_usec) * 1e-3);
  std::sort(gaps.begin(), gaps.end());
  const double p50 = gaps[gaps.size() / 2], p99 = gaps[gaps.size() * 99 / 100];
  int good = 0, failed = 0, resets = 0, with_depth = 0;
  std::uint8_t last_reset = ap.odo.front().reset_counter;
  // The jumps at reset_counter changes: the first is the change of frame (the repeat pass's dead
  // reckoning runs on from the end of the teach pass: the simulator puts the vehicle back at the
  // route's start between passes); every later one is a route fix correcting the dead reckoning.
  std::vector<double> later_jumps_m;
  double first_jump_m = -1.0;
  for (const mav::Odometry& o : ap.odo) {
    EXPECT_EQ(o.frame_id, mav::kMavFrameLocalFrd);
    EXPECT_EQ(o.child_frame_id, mav::kMavFrameBodyFrd);
    EXPECT_NEAR(o.q[0] * o.q[0] + o.q[1] * o.q[1] + o.q[2] * o.q[2] + o.q[3] * o.q[3], 1.0f, 1e-3f);
    if (o.quality > 0) {
      ++good;
      EXPECT_TRUE(std::isfinite(o.vx)) << "a usable message carries the DVL velocity";
    }
    failed += o.quality < 0;
    with_depth += o.z != 0.0f;
    if (o.reset_counter != last_reset) {
      ++resets;
      const mav::Odometry& prev = (&o)[-1];
      const double jump = std::hypot(static_cast<double>(o.x - prev.x), static_cast<double>(o.y - prev.y));
      if (first_jump_m < 0.0) first_jump_m = jump; else later_jumps_m.push_back(jump);
    }
    last_reset = o.reset_counter;
  }
  std::printf("mavlink mission: %zu ODOMETRY over %.1f s mission time = %.2f Hz (interval p50 %.0f ms, p99 %.0f ms), %d good, %d quality -1, "
              "%d reset_counter changes, %zu VISION_POSITION_DELTA, %zu DISTANCE_SENSOR, %d HEARTBEAT, %d NAMED_VALUE_FLOAT, %u route fixes, "
              "first jump %.1f m, later jumps max %.2f m, odometry sent %u, tx errors %u\n",
              ap.odo.size(), span_s, rate_hz, p50, p99, good, failed, resets, ap.vpd.size(), ap.ds.size(), ap.heartbeats, ap.named,
              d.nav().estimate().fixes(), first_jump_m,
              later_jumps_m.empty() ? 0.0 : *std::max_element(later_jumps_m.begin(), later_jumps_m.end()), ep.odometry_sent(), d.io_counters().mav_tx_errors.load());
  if (ap.lossless) {
    EXPECT_EQ(ap.odo.size(), ep.odometry_sent()) << "every ODOMETRY sent reached the autopilot (UDP on the loopback)";
  } else {
    std::printf("note: receive buffer capped by net.core.rmem_max: %u of %u ODOMETRY received\n", static_cast<unsigned>(ap.odo.size()),
                ep.odometry_sent());
  }
  EXPECT_NEAR(rate_hz, c.mavlink_odometry_hz, 0.1 * c.mavlink_odometry_hz);
  EXPECT_GE(good, static_cast<int>(ap.odo.size()) * 9 / 10) << "every sensor healthy: the estimate is usable";
  EXPECT_EQ(with_depth, 0) << "the simulated vehicle sends no QNAV_DEPTH_IN: z stays 0";
  EXPECT_GE(resets, 1) << "route fixes in Repeat move the position: reset_counter changes";
  EXPECT_GT(d.nav().estimate().fixes(), 0u);
  ASSERT_FALSE(later_jumps_m.empty());
  // A fix that got the geometry wrong (a cross-track sign, the tile's centre for the vehicle) would
  // jump by the 10 % offset twice over (~20 m) or half a tile (~44 m): the corrections stay small.
  for (double j : later_jumps_m) EXPECT_LT(j, 10.0);
  EXPECT_GT(ap.vpd.size(), ap.odo.size() / 2);
  EXPECT_GT(ap.ds.size(), ap.odo.size() / 2);
  for (const mav::DistanceSensor& s : ap.ds) EXPECT_GT(s.current_distance, 0);
  EXPECT_GE(ap.heartbeats, static_cast<int>(span_s) - 2);
  EXPECT_GT(ap.named, 0) << "route guidance in Repeat";
  EXPECT_EQ(ap.from_other, 0);
  // Commands: the autopilot's acknowledged, the other system's refused, counted, never acted on.
  ASSERT_EQ(ap.acks.size(), 1u);
  EXPECT_EQ(ap.acks[0].command, kMavCmdSetMode);
  EXPECT_EQ(ap.acks[0].result, 0) << "MAV_RESULT_ACCEPTED";
  EXPECT_EQ(ap.acks[0].target_system, 1);
  EXPECT_EQ(ep.commands_accepted(), 1u);
  EXPECT_EQ(ep.counters().get(MavCounter::kCmdWrongSender), 1u);
  EXPECT_GE(ep.counters().get(MavCounter::kForeignSystem), 1u);
  EXPECT_GT(ep.parser_rejects(), 0u) << "garbage and the unknown message are counted by the parser";
  EXPECT_TRUE(d.mission_done()) << "the refused Idle did not stop the mission";
  EXPECT_TRUE(ap.targets.empty()) << "mavlink.guided is off";
  EXPECT_EQ(SoftwareFaults::count(), 0u);
  write_capture(ap);
}

TEST(QnavdMavlink, DvlLossIsQualityMinusOneAndNeverAZeroDelta) {
  Autopilot ap;
  ap.start();
  if (::testing::Test::HasFatalFailure()) return;
  DaemonConfig c = mav_config(temp_dir(), ap.port_number());
  c.sim_stall = "dvl";
  c.sim_stall_pass = 1;
  c.sim_stall_start_s = 40.0;
  c.sim_stall_s = 30.0;
  Daemon d(c);
  ASSERT_TRUE(d.init(nullptr));
  ASSERT_TRUE(d.start());
  std::uint64_t allocs = 0;
  {
    test::AllocationGuard guard;  // the MAVLink path allocates nothing after start either
    EXPECT_EQ(d.run(), 0);
    allocs = guard.allocations();
    if (test::malloc_counted()) {
      EXPECT_EQ(allocs, 0u) << guard.report();
    }
  }
  std::printf("mavlink: %llu heap allocations after start (malloc counted: %s)\n", static_cast<unsigned long long>(allocs),
              test::malloc_counted() ? "yes" : "no");
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  ap.finish();
  std::lock_guard<std::mutex> lock(ap.mu);
  ASSERT_GT(ap.odo.size(), 100u);
  // The loss: the longest run of quality -1 (the first messages, before the first DVL sample, are -1 too).
  std::uint64_t lost_from = 0, lost_to = 0, run_from = 0;
  int lost = 0, run = 0;
  for (const mav::Odometry& o : ap.odo) {
    if (o.quality >= 0) {
      run = 0;
      continue;
    }
    EXPECT_TRUE(std::isnan(o.vx)) << "no velocity while the DVL is lost";
    if (run++ == 0) run_from = o.time_usec;
    if (run > lost) lost = run, lost_from = run_from, lost_to = o.time_usec;
  }
  const double period_us = 1e6 / c.mavlink_odometry_hz;
  std::printf("dvl stall %.0f s: %d ODOMETRY with quality -1 over %.1f s (stale after dvl.stale_s %.2f s)\n", c.sim_stall_s, lost,
              static_cast<double>(lost_to - lost_from) * 1e-6, c.dvl_stale_s);
  ASSERT_GT(lost, 0);
  EXPECT_NEAR(static_cast<double>(lost_to - lost_from) * 1e-6, c.sim_stall_s - c.dvl_stale_s, 2.0);
  int in_loss = 0;
  for (const mav::VisionPositionDelta& v : ap.vpd)
    in_loss += v.time_usec >= lost_from && static_cast<double>(v.time_usec) <= static_cast<double>(lost_to) + period_us;
  EXPECT_EQ(in_loss, 0) << "no VISION_POSITION_DELTA (a zero delta would read as 'stopped') while the DVL is lost";
  EXPECT_EQ(SoftwareFaults::count(), 0u);
}

TEST(QnavdMavlink, GuidedTargetsOnlyInRepeatWhileTheAutopilotIsGuidedAndArmed) {
  Autopilot ap;
  ap.start();
  if (::testing::Test::HasFatalFailure()) return;
  DaemonConfig c = mav_config(temp_dir(), ap.port_number());
  c.mavlink_guided = true;
  Daemon d(c);
  ASSERT_TRUE(d.init(nullptr));
  ASSERT_TRUE(d.start());
  std::atomic<bool> guided{false};
  std::thread talker([&] {
    for (int i = 0; i < 2000 && !d.mission_done(); ++i) {
      mav::Heartbeat h;
      h.type = 12;
      h.autopilot = 3;
      h.custom_mode = guided.load() ? kArduSubGuided : 19;  // GUIDED, else MANUAL
      h.base_mode = guided.load() ? mav::kMavModeFlagSafetyArmed : 0;
      ap.send(h);
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  });
  // MANUAL and disarmed until the repeat pass is under way, then GUIDED and armed.
  std::size_t targets_before_guided = 0;
  for (int i = 0; i < 3000 && !d.mission_done(); ++i) {
    if (d.nav().mode() == qc::Mode::kRepeat) {
      {
        std::lock_guard<std::mutex> lock(ap.mu);
        targets_before_guided = ap.targets.size();
      }
      guided.store(true);
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  EXPECT_EQ(d.run(), 0);
  talker.join();
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  ap.finish();
  std::lock_guard<std::mutex> lock(ap.mu);
  EXPECT_EQ(targets_before_guided, 0u) << "nothing commanded while the autopilot is not GUIDED and armed";
  ASSERT_GT(ap.targets.size(), 0u);
  std::vector<double> dist = ap.target_dist_m;
  std::sort(dist.begin(), dist.end());
  std::printf("guided: %zu SET_POSITION_TARGET_LOCAL_NED, distance from the published position: median %.1f m, max %.1f m\n", ap.targets.size(),
              dist[dist.size() / 2], dist.back());
  for (const mav::SetPositionTargetLocalNed& p : ap.targets) {
    EXPECT_EQ(p.coordinate_frame, mav::kMavFrameLocalNed);
    EXPECT_EQ(p.target_system, 1);
    EXPECT_EQ(p.target_component, 1);
    EXPECT_EQ(p.type_mask & 7, 0) << "position used";
    EXPECT_EQ(p.type_mask & (8 | 16 | 32), 8 | 16 | 32) << "velocity ignored";
  }
  // The waypoint is in the published frame: ahead of the vehicle on the route, not somewhere else.
  EXPECT_LT(dist[dist.size() / 2], 200.0);
}

// The endpoint alone (no daemon): what it answers and counts for each kind of command and input.
struct EndpointRig {
  DaemonConfig c;
  std::vector<MavBytes> rx_items = std::vector<MavBytes>(16), tx_items = std::vector<MavBytes>(64);
  SpscRing<MavBytes> rx, tx;
  std::unique_ptr<MavlinkEndpoint> ep;
  EndpointRig() {
    c.mavlink_enabled = true;
    EXPECT_TRUE(rx.init(Span<MavBytes>(rx_items.data(), rx_items.size())));
    EXPECT_TRUE(tx.init(Span<MavBytes>(tx_items.data(), tx_items.size())));
    ep = std::make_unique<MavlinkEndpoint>(c, nullptr);
  }
  template <typename M>
  void push(const M& m, std::uint8_t sysid = 1, std::uint8_t compid = 1) {
    mav::FrameEncoder e(sysid, compid);
    MavBytes b;
    Result<std::size_t> n = mav::encode(e, m, Span<std::uint8_t>(b.data, kMavBytes));
    ASSERT_TRUE(n);
    b.len = static_cast<std::uint16_t>(n.value());
    ASSERT_TRUE(rx.try_push(b));
  }
  // The COMMAND_ACKs the endpoint queued (after a publish at t_ns).
  std::vector<mav::CommandAck> acks(std::int64_t t_ns = 0) {
    MavSnapshot s;
    s.now_ns = t_ns;
    ep->publish(s, tx);
    std::vector<mav::CommandAck> out;
    mav::Parser p;
    MavBytes b;
    while (tx.try_pop(b))
      p.feed(Span<const std::uint8_t>(b.data, b.len), [&](const mav::Frame& f) {
        mav::CommandAck a;
        if (mav::decode(f, a)) out.push_back(a);
      });
    return out;
  }
};

TEST(QnavdMavlinkEndpoint, RefusesAndCountsEveryCommandThatIsNotTheAutopilotsModeCommand) {
  EndpointRig r;
  // From the autopilot: a good mode command is handed to the worker, answered through ack().
  mav::CommandLong good = mode_command(qc::Mode::kRepeat, 3);
  good.param3 = 1.0f;
  r.push(good);
  MavInputs in = r.ep->drain(r.rx);
  ASSERT_TRUE(in.mode_cmd);
  EXPECT_EQ(in.cmd.mode, qc::Mode::kRepeat);
  EXPECT_EQ(in.cmd.route_id, 3);
  EXPECT_TRUE(in.cmd.reverse);
  r.ep->ack(false, "route_missing", r.tx);
  std::vector<mav::CommandAck> a = r.acks();
  ASSERT_EQ(a.size(), 1u);
  EXPECT_EQ(a[0].result, 4) << "MAV_RESULT_FAILED: qnav refused the mode";
  // Bad parameters: DENIED, not handed on.
  mav::CommandLong bad = mode_command(qc::Mode::kIdle, 0);
  bad.param1 = 9.0f;
  r.push(bad);
  EXPECT_FALSE(r.ep->drain(r.rx).mode_cmd);
  a = r.acks(1);
  ASSERT_EQ(a.size(), 1u);
  EXPECT_EQ(a[0].result, 2) << "MAV_RESULT_DENIED";
  // Another command from the autopilot: UNSUPPORTED.
  mav::CommandLong other = mode_command(qc::Mode::kIdle, 0);
  other.command = 400;  // MAV_CMD_COMPONENT_ARM_DISARM
  r.push(other);
  EXPECT_FALSE(r.ep->drain(r.rx).mode_cmd);
  a = r.acks(2);
  ASSERT_EQ(a.size(), 1u);
  EXPECT_EQ(a[0].result, 3) << "MAV_RESULT_UNSUPPORTED";
  // From another component of the autopilot's system, or addressed to someone else: no answer.
  r.push(mode_command(qc::Mode::kIdle, 0), 1, 190);
  mav::CommandLong elsewhere = mode_command(qc::Mode::kIdle, 0);
  elsewhere.target_system = 2;
  r.push(elsewhere);
  EXPECT_FALSE(r.ep->drain(r.rx).mode_cmd);
  EXPECT_TRUE(r.acks(3).empty());
  // A non-finite attitude is refused; a good one is handed on.
  mav::Attitude att;
  att.yaw = std::nanf("");
  r.push(att);
  mav::Attitude att2;
  att2.yaw = 1.25f;
  r.push(att2);
  in = r.ep->drain(r.rx);
  EXPECT_TRUE(in.attitude);
  EXPECT_NEAR(in.yaw_rad, 1.25, 1e-6);
  const auto& k = r.ep->counters();
  EXPECT_EQ(k.get(MavCounter::kCmdBadParam), 1u);
  EXPECT_EQ(k.get(MavCounter::kCmdUnsupported), 1u);
  EXPECT_EQ(k.get(MavCounter::kCmdWrongSender), 1u);
  EXPECT_EQ(k.get(MavCounter::kCmdNotForUs), 1u);
  EXPECT_EQ(k.get(MavCounter::kBadAttitude), 1u);
  EXPECT_EQ(r.ep->rejected(), 3u) << "wrong sender, bad parameters, bad attitude";
}

// Mode = Vo: the published estimate follows the visual odometry (a rover's 4 m stereo pass).
struct LastPair {
  std::mutex mu;
  Pose3 first, last;
  bool have = false;
};
void on_pair(void* ctx, const FrameReport& r) {
  auto* lp = static_cast<LastPair*>(ctx);
  if (!r.processed) return;
  std::lock_guard<std::mutex> lock(lp->mu);
  if (!lp->have) lp->first = r.world_T_body;
  lp->last = r.world_T_body;
  lp->have = true;
}

TEST(QnavdMavlink, InModeVoTheEstimateFollowsTheVisualOdometry) {
  Autopilot ap;
  ap.start();
  if (::testing::Test::HasFatalFailure()) return;
  SoftwareFaults::reset_for_tests();
  DaemonConfig c;
  c.backend = Backend::kSim;
  c.route_dir = temp_dir();
  c.log = LogFormat::kOff;
  c.realtime = false;
  c.sim_speed = SimSpeed::kFast;
  c.sim_length_m = 200.0;
  c.vo_budget_us = 10000000;
  c.mavlink_enabled = true;
  c.mavlink_udp_remote = "127.0.0.1:" + std::to_string(ap.port_number());
  SimPass p;
  p.mode = qc::Mode::kVo;
  p.length_m = 4.0;
  ASSERT_TRUE(c.sim_mission.push_back(p));
  LastPair lp;
  Daemon d(c);
  d.set_frame_observer(on_pair, &lp);
  ASSERT_TRUE(d.init(nullptr));
  ASSERT_TRUE(d.start());
  EXPECT_EQ(d.run(), 0);
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  ap.finish();
  std::lock_guard<std::mutex> lock(ap.mu);
  std::lock_guard<std::mutex> lock2(lp.mu);
  ASSERT_TRUE(lp.have);
  const mav::Odometry* first = nullptr;
  const mav::Odometry* last = nullptr;
  int vio = 0;
  for (const mav::Odometry& o : ap.odo) {
    if (o.estimator_type != mav::kMavEstimatorTypeVio) continue;
    ++vio;
    if (first == nullptr) first = &o;
    last = &o;
  }
  ASSERT_NE(first, nullptr);
  const double odo_m = std::hypot(static_cast<double>(last->x - first->x), static_cast<double>(last->y - first->y));
  const Vec3d vo = lp.last.t - lp.first.t;
  const double vo_m = std::hypot(vo.x(), vo.y());
  std::printf("mavlink vo: %d ODOMETRY in Mode = Vo, published displacement %.3f m, VO body displacement %.3f m\n", vio, odo_m, vo_m);
  EXPECT_GT(vo_m, 1.5);
  // The ODOMETRY window starts and ends up to one period (0.2 s, ~0.2 m of rover motion) off the pairs: up to 0.4 m.
  EXPECT_NEAR(odo_m, vo_m, 0.12 * vo_m);
  EXPECT_EQ(SoftwareFaults::count(), 0u);
}

// The io thread's links alone: a UDP server on mavlink.udp_listen_port hears a ground station and
// answers it; a full rx queue drops and counts.
// A free UDP port (bind 0, read it, close) and a configuration serving MAVLink on it.
DaemonConfig server_config(std::uint16_t& port) {
  hal::UdpPort probe;
  EXPECT_TRUE(probe.open_server(0, "127.0.0.1"));
  port = probe.local_port();
  probe.close();
  DaemonConfig c;
  c.mavlink_enabled = true;
  c.mavlink_udp_listen_port = port;
  return c;
}

TEST(QnavdMavlinkIo, TheServerPortHearsAGroundStationAndAnswersIt) {
  std::uint16_t port = 0;
  const DaemonConfig c = server_config(port);
  hal::MonotonicClock clock;
  MavlinkIo io_links(c, clock, nullptr);
  ASSERT_TRUE(io_links.open());
  EXPECT_EQ(io_links.server_port(), port);
  std::vector<MavBytes> items(2);
  SpscRing<MavBytes> rx;
  ASSERT_TRUE(rx.init(Span<MavBytes>(items.data(), items.size())));
  IoCounters counters;
  hal::UdpPort gcs;
  ASSERT_TRUE(gcs.open_client("127.0.0.1", port));
  // A ground station's HEARTBEAT (system 255): a valid frame, so its sender becomes the server's peer.
  std::uint8_t frame[64];
  mav::FrameEncoder gcs_enc(255, 190);
  const Result<std::size_t> hn = mav::encode(gcs_enc, mav::Heartbeat{}, Span<std::uint8_t>(frame, sizeof frame));
  ASSERT_TRUE(hn);
  const std::vector<std::uint8_t> hello(frame, frame + hn.value());
  // A poll packs its reads (at most kMaxReadsPerPoll datagrams) into one item: three polls' worth of
  // datagrams, a queue of 2 items.
  constexpr int kDatagrams = 3 * MavlinkIo::kMaxReadsPerPoll;
  for (int i = 0; i < kDatagrams; ++i) ASSERT_TRUE(gcs.write(Span<const std::uint8_t>(hello.data(), hello.size())));
  std::this_thread::sleep_for(std::chrono::milliseconds(20));  // all in the socket's buffer
  bool got = false;
  for (int i = 0; i < 200 && !got; ++i) {
    got = io_links.poll(rx, counters);
    if (!got) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  ASSERT_TRUE(got);
  for (int i = 0; i < 20 && rx.size() + counters.mav_rx_overflow.load() < 3; ++i) {
    (void)io_links.poll(rx, counters);
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  MavBytes m;
  ASSERT_TRUE(rx.try_pop(m));
  EXPECT_EQ(m.link, 1) << "the server link";
  ASSERT_EQ(m.len, MavlinkIo::kMaxReadsPerPoll * hello.size()) << "one poll's datagrams back to back in one item";
  for (int k = 0; k < MavlinkIo::kMaxReadsPerPoll; ++k) EXPECT_EQ(std::memcmp(m.data + k * hello.size(), hello.data(), hello.size()), 0);
  EXPECT_EQ(counters.mav_rx_overflow.load(), 1u) << "a queue of 2 held two of the three polls' items";
  // The answer goes to the ground station (the server's last sender).
  MavBytes out;
  out.len = 4;
  out.data[0] = 0xFD;
  io_links.send(out, counters);
  EXPECT_EQ(counters.mav_tx_errors.load(), 0u);
  std::uint8_t back[16];
  Result<hal::SerialRead> r = gcs.read(Span<std::uint8_t>(back, sizeof back), 1000);
  ASSERT_TRUE(r);
  EXPECT_EQ(r.value().bytes, 4u);
}

// The server's peer is a sender of valid frames, and it stays the peer while it is alive: junk from
// another address, even a stream of it, does not take qnavd's frames away from the ground station.
TEST(QnavdMavlinkIo, AFloodOfJunkDoesNotTakeTheServersRepliesFromTheGroundStation) {
  std::uint16_t port = 0;
  const DaemonConfig c = server_config(port);
  hal::MonotonicClock clock;
  MavlinkIo io_links(c, clock, nullptr);
  ASSERT_TRUE(io_links.open());
  std::vector<MavBytes> items(64);
  SpscRing<MavBytes> rx;
  ASSERT_TRUE(rx.init(Span<MavBytes>(items.data(), items.size())));
  IoCounters counters;
  const auto drain = [&] {
    for (int i = 0; i < 50; ++i) {
      (void)io_links.poll(rx, counters);
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    MavBytes m;
    while (rx.try_pop(m)) {
    }
  };
  hal::UdpPort gcs, flooder;
  ASSERT_TRUE(gcs.open_client("127.0.0.1", port));
  ASSERT_TRUE(flooder.open_client("127.0.0.1", port));
  const std::uint8_t junk[] = {0xFD, 0x09, 0x00, 0x00, 0x00, 0xFF, 0xBE, 0x00, 0x00, 0x00, 0x55, 0x66};
  // Junk first: no valid frame, no peer, nothing sent anywhere.
  ASSERT_TRUE(flooder.write(Span<const std::uint8_t>(junk, sizeof junk)));
  drain();
  MavBytes out;
  out.len = 4;
  out.data[0] = 0xFD;
  io_links.send(out, counters);
  std::uint8_t back[64];
  Result<hal::SerialRead> r = flooder.read(Span<std::uint8_t>(back, sizeof back), 100);
  ASSERT_TRUE(r);
  EXPECT_EQ(r.value().bytes, 0u) << "junk made its sender the peer";
  // The ground station's HEARTBEAT makes it the peer; the flood after it does not move the replies.
  std::uint8_t frame[64];
  mav::FrameEncoder gcs_enc(255, 190);
  const Result<std::size_t> hn = mav::encode(gcs_enc, mav::Heartbeat{}, Span<std::uint8_t>(frame, sizeof frame));
  ASSERT_TRUE(hn);
  ASSERT_TRUE(gcs.write(Span<const std::uint8_t>(frame, hn.value())));
  drain();
  for (int i = 0; i < 40; ++i) ASSERT_TRUE(flooder.write(Span<const std::uint8_t>(junk, sizeof junk)));
  // A valid frame from the flooder too: the live ground station keeps the replies (another sender
  // takes over only after kPeerSilenceNs of silence).
  mav::FrameEncoder other(77, 1);
  const Result<std::size_t> on = mav::encode(other, mav::Heartbeat{}, Span<std::uint8_t>(frame, sizeof frame));
  ASSERT_TRUE(on);
  ASSERT_TRUE(flooder.write(Span<const std::uint8_t>(frame, on.value())));
  drain();
  io_links.send(out, counters);
  r = gcs.read(Span<std::uint8_t>(back, sizeof back), 1000);
  ASSERT_TRUE(r);
  EXPECT_EQ(r.value().bytes, 4u) << "the ground station lost qnavd's frames to the flood";
  r = flooder.read(Span<std::uint8_t>(back, sizeof back), 100);
  ASSERT_TRUE(r);
  EXPECT_EQ(r.value().bytes, 0u);
}

}  // namespace
}  // namespace qnav::daemon
