// qnavd's map mode on the sim backend: the simulated autopilot commands Mode = Map and the vehicle's
// downward camera flies the synthetic seabed loop (drivers/downward_sim, the loop `qnav map eval`
// measures) into the frame pool. The nav worker runs the shared mapper (pipeline::TopoMapper):
//  - every frame registers, the chained pose ends within 2 % of the path of the truth (the issue's
//    goal), the map grows about one node per node spacing, nothing is allocated on the heap after
//    start (the frames are rendered in place), and the map file the daemon saved through its
//    FileStore reads back with the nodes the worker holds.
//  - the mode-command rules: Mode = Map without map.enabled is refused (UnsupportedMode) and the
//    worker stays in Idle; with it, a black frame is counted as bad and the map (empty) is still
//    written through the worker's FileStore when the mode is left (NavWorker alone, a memory store).
// The real snippet and bad frames against `qnav map`: test/unit/firmware/qnavd_cli/qnavd_map_test.sh.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <unistd.h>
#include <vector>

#include "drivers/downward_sim/seabed_scene.hpp"
#include "firmware/qnavd/daemon.hpp"
#include "firmware/qnavd/software_fault.hpp"
#include "firmware/qnavd/nav_worker.hpp"
#include "firmware/tools/map_file.hpp"
#include "hal/sim/manual_clock.hpp"
#include "hal/sim/memory_file_store.hpp"
#include "test/support/alloc_guard.hpp"

namespace qnav::daemon {
namespace {

namespace qc = drivers::qnavcan;
namespace dw = qnav::sim::downward;

std::string temp_dir() {
  char t[] = "/tmp/qnavd_map_test_XXXXXX";
  const char* d = mkdtemp(t);
  return d ? std::string(d) : std::string("/tmp");
}

TEST(QnavdMap, SyntheticLoopMapsWithinTwoPercentOfPathWithoutHeap) {
  SoftwareFaults::reset_for_tests();
  constexpr int kFrames = 100;
  DaemonConfig c;
  c.backend = Backend::kSim;
  c.route_dir = temp_dir();
  c.log = LogFormat::kOff;
  c.realtime = false;
  c.sim_speed = SimSpeed::kFast;
  c.sim_length_m = 200.0;          // the side-scan survey is built but not flown
  c.vo_enabled = false;
  c.map_enabled = true;
  c.map_width = 320;
  c.map_height = 240;
  c.map_focal_px = 300.0;          // the synthetic camera: metres from its focal length and altitude
  c.map_cu_px = 159.5;
  c.map_cv_px = 119.5;
  c.map_altitude_m = 2.0;
  c.map_budget_us = 10000000;      // timing is measured by the benchmark, not asserted (ASan is slow)
  SimPass p;
  p.mode = qc::Mode::kMap;
  p.max_frames = kFrames;
  static_cast<void>(c.sim_mission.push_back(p));
  c.route_id = 7;

  Daemon d(c);
  ASSERT_TRUE(d.init(nullptr));
  ASSERT_TRUE(d.start());
  test::AllocationGuard guard;
  std::uint64_t allocs = 0;
  {
    test::EigenMallocForbidden no_eigen_malloc;
    ASSERT_EQ(d.run(), 0);
    allocs = guard.allocations();
  }
  EXPECT_TRUE(d.mission_done());
  EXPECT_EQ(SoftwareFaults::count(), 0u) << (SoftwareFaults::first().what ? SoftwareFaults::first().what : "");
  const NavWorker& nav = d.nav();
  EXPECT_EQ(nav.map_frames(), static_cast<std::uint32_t>(kFrames));
  EXPECT_EQ(nav.map_bad_frames(), 0u);
  EXPECT_EQ(nav.map_save_errors(), 0u);

  // The last frame's pose against the truth, in frame 0's camera axes (as `qnav map eval` scores it).
  const dw::CameraPose p0 = dw::loop_pose(0, 90), pk = dw::loop_pose(kFrames - 1, 90);
  const double cs = std::cos(p0.yaw_rad), sn = std::sin(p0.yaw_rad);
  const Vec2d dt(pk.x_m - p0.x_m, pk.y_m - p0.y_m);
  const Vec2d truth(cs * dt.x() + sn * dt.y(), -sn * dt.x() + cs * dt.y());
  const topo::ChainPose& pose = nav.mapper().chain().pose();
  ASSERT_TRUE(pose.metric);
  const double path = 2.0 * 3.14159265358979323846 * 0.8 * (kFrames - 1) / 90.0;
  const double err = (pose.position_m - truth).norm();
  const topo::TopoMap& map = nav.mapper().map();
  std::printf("qnavd map: %u frames, path %.2f m, end error %.4f m (%.3f %% of path); map %zu nodes, %zu edges, %u revisits; %u saves; "
              "%llu heap allocations after start; %u deadline misses\n",
              nav.map_frames(), path, err, 100.0 * err / path, map.node_count(), map.edge_count(), map.revisits(), nav.map_saves(),
              static_cast<unsigned long long>(allocs), nav.deadline_misses());
  EXPECT_LT(err, 0.02 * path);
  EXPECT_GE(map.node_count(), 15u);  // ~5.6 m at 0.2 m spacing, a loop closed: 20-30 nodes
  EXPECT_LE(map.node_count(), 40u);
  EXPECT_EQ(allocs, 0u);

  // The saved map: the worker's map, read back from route_dir/map_7.qmap.
  const std::string path_file = c.route_dir + "/map_7.qmap";
  topo::MapHeader h;
  ASSERT_TRUE(tools::read_map_header(path_file.c_str(), h).is_ok());
  topo::TopoMapConfig mc = pipeline::topo_map_config(h.node_spacing, h.capacity);
  mc.max_edges_per_node = h.max_edges_per_node;
  ArenaStorage arena(topo::TopoMap::arena_bytes(mc));
  topo::TopoMap loaded;
  ASSERT_TRUE(loaded.init(mc, arena).is_ok());
  tools::MapFileInfo info;
  ASSERT_TRUE(tools::load_map(path_file.c_str(), loaded, &info).is_ok());
  EXPECT_TRUE(info.metric);
  EXPECT_EQ(loaded.node_count(), map.node_count());
  EXPECT_EQ(loaded.edge_count(), map.edge_count());
}


// A NavWorker on its own queues (what Daemon::init_pipeline builds), fed by hand.
struct Worker {
  DaemonConfig cfg;
  std::vector<PingMsg> ping_store = std::vector<PingMsg>(4);
  std::vector<std::uint32_t> free_store = std::vector<std::uint32_t>(4), free_frame_store = std::vector<std::uint32_t>(4);
  std::vector<hal::CanRxFrame> rx_store = std::vector<hal::CanRxFrame>(16);
  std::vector<hal::CanFrame> tx_store = std::vector<hal::CanFrame>(64);
  std::vector<drivers::dvl::DvlVelocity> dvl_store = std::vector<drivers::dvl::DvlVelocity>(64);
  std::vector<FrameMsg> frame_store = std::vector<FrameMsg>(4);
  SpscRing<PingMsg> pings;
  SpscRing<std::uint32_t> free_slots, free_frames;
  SpscRing<hal::CanRxFrame> can_rx;
  SpscRing<hal::CanFrame> can_tx;
  SpscRing<drivers::dvl::DvlVelocity> dvl;
  SpscRing<FrameMsg> frames;
  std::vector<float> ping_pool;
  std::vector<std::uint8_t> frame_pool;
  IoCounters io;
  hal::ManualClock clock{1000000000};
  std::vector<std::uint8_t> mem = std::vector<std::uint8_t>(1 << 20);
  hal::MemoryFileStore store{Span<std::uint8_t>(mem.data(), mem.size())};
  std::unique_ptr<NavWorker> nav;
  std::uint8_t counter = 0;

  explicit Worker(bool map_enabled) {
    cfg.backend = Backend::kSim;
    cfg.route_dir = "r";
    cfg.log = LogFormat::kOff;
    cfg.vo_enabled = false;
    cfg.map_enabled = map_enabled;
    cfg.ping_queue = 4;
    cfg.max_samples_per_side = 64;
    ping_pool.assign(4 * 2 * 64, 0.0f);
    frame_pool.assign(4 * static_cast<std::size_t>(cfg.map_width) * static_cast<std::size_t>(cfg.map_height), 0);
    EXPECT_TRUE(pings.init(Span<PingMsg>(ping_store.data(), 4)).is_ok());
    EXPECT_TRUE(free_slots.init(Span<std::uint32_t>(free_store.data(), 4)).is_ok());
    EXPECT_TRUE(free_frames.init(Span<std::uint32_t>(free_frame_store.data(), 4)).is_ok());
    EXPECT_TRUE(can_rx.init(Span<hal::CanRxFrame>(rx_store.data(), rx_store.size())).is_ok());
    EXPECT_TRUE(can_tx.init(Span<hal::CanFrame>(tx_store.data(), tx_store.size())).is_ok());
    EXPECT_TRUE(dvl.init(Span<drivers::dvl::DvlVelocity>(dvl_store.data(), dvl_store.size())).is_ok());
    EXPECT_TRUE(frames.init(Span<FrameMsg>(frame_store.data(), frame_store.size())).is_ok());
    NavQueues q;
    q.pings = &pings;
    q.free_slots = &free_slots;
    q.can_rx = &can_rx;
    q.can_tx = &can_tx;
    q.dvl = &dvl;
    q.ping_pool = ping_pool.data();
    q.ping_pool_stride = 2 * 64;
    q.frames = &frames;
    q.free_frames = &free_frames;
    q.frame_pool = frame_pool.data();
    q.frame_slot_bytes = static_cast<std::size_t>(cfg.map_width) * static_cast<std::size_t>(cfg.map_height);
    q.io = &io;
    nav = std::make_unique<NavWorker>(cfg, clock, clock, store);
    const Status s = nav->init(q, nullptr, nullptr, nullptr);
    EXPECT_TRUE(s.is_ok()) << s.message();
  }
  void command(qc::Mode m) {
    qc::ModeCmd cmd;
    cmd.mode = m;
    cmd.counter = ++counter;
    hal::CanRxFrame rx;
    ASSERT_TRUE(qc::encode(cmd, rx.frame).is_ok());
    clock.advance_ns(100000000);
    rx.stamp.sample_ns = rx.stamp.arrival_ns = clock.now_ns();
    ASSERT_TRUE(can_rx.try_push(rx).is_ok());
    for (int i = 0; i < 4; ++i) nav->run_once();
  }
  void black_frame() {
    clock.advance_ns(200000000);
    FrameMsg f;
    f.slot = 0;
    f.width = static_cast<std::uint16_t>(cfg.map_width);
    f.height = static_cast<std::uint16_t>(cfg.map_height);
    f.downward = true;
    f.stamp.sample_ns = f.stamp.arrival_ns = clock.now_ns();
    ASSERT_TRUE(frames.try_push(f).is_ok());
    for (int i = 0; i < 4; ++i) nav->run_once();
  }
};

TEST(QnavdMap, ModeMapIsRefusedWithoutMapEnabled) {
  Worker w(false);
  w.command(qc::Mode::kMap);
  EXPECT_EQ(w.nav->last_reject(), ModeReject::kUnsupportedMode);
  EXPECT_EQ(w.nav->mode(), qc::Mode::kIdle);
}

TEST(QnavdMap, ABadFrameIsCountedAndTheMapWrittenWhenTheModeIsLeft) {
  Worker w(true);
  w.command(qc::Mode::kMap);
  ASSERT_EQ(w.nav->last_reject(), ModeReject::kNone);
  ASSERT_EQ(w.nav->mode(), qc::Mode::kMap);
  w.black_frame();
  EXPECT_EQ(w.nav->map_frames(), 1u);
  EXPECT_EQ(w.nav->map_bad_frames(), 1u);
  EXPECT_EQ(w.nav->mapper().map().node_count(), 0u);
  EXPECT_FALSE(w.store.exists("r/map_1.qmap"));  // nothing learnt yet, nothing written
  w.command(qc::Mode::kIdle);
  EXPECT_EQ(w.nav->mode(), qc::Mode::kIdle);
  EXPECT_TRUE(w.store.exists("r/map_1.qmap"));   // written (empty) when the mode was left
  EXPECT_EQ(w.nav->map_saves(), 1u);
  EXPECT_EQ(w.nav->map_save_errors(), 0u);
}

}  // namespace
}  // namespace qnav::daemon
