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
//  - the map mode's CAN output, from the autopilot's side of the bus: one QNAV_MAP_POSE and one
//    QNAV_MAP_STATUS per frame (FrameSeq 0, 1, ... without a gap, the pair sharing its Counter), the
//    last pose the worker's chained pose to the signals' resolution, the node count the map's, every
//    node created announced once (NewNode); a black, a saturated and a textureless frame flagged on
//    CAN with the pose and the node held (the worker alone).
// The real snippet and bad frames against `qnav map` and the daemon's log, CAN decoded by
// `qnav can decode`: test/unit/firmware/qnavd_cli/qnavd_map_test.sh.
#include <gtest/gtest.h>
#include <algorithm>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <unistd.h>
#include <vector>

#include "drivers/downward_sim/seabed_scene.hpp"
#include "drivers/qnavcan/messages.hpp"
#include "firmware/qnavd/daemon.hpp"
#include "firmware/qnavd/linux_downward.hpp"
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

// What the autopilot heard in Mode = Map (bus observer, io thread; read after run() joined it).
struct MapRecorder {
  std::uint32_t poses = 0, statuses = 0, seq_gaps = 0, counter_mismatches = 0, not_registered = 0, not_metric = 0, new_nodes = 0;
  std::uint32_t map_state_frames = 0;
  int last_seq = -1, last_pose_counter = -1;
  qc::MapPose last_pose;
  qc::MapStatus last_status;
};

void on_map_bus(void* ctx, const hal::CanRxFrame& f) {
  auto* rec = static_cast<MapRecorder*>(ctx);
  if (f.frame.id == qc::kIdNavStatus) {
    qc::NavStatus ns;
    if (qc::decode(f.frame, ns) && ns.state == qc::Mode::kMap) ++rec->map_state_frames;
  } else if (f.frame.id == qc::kIdMapPose) {
    if (qc::decode(f.frame, rec->last_pose)) ++rec->poses, rec->last_pose_counter = rec->last_pose.counter;
  } else if (f.frame.id == qc::kIdMapStatus) {
    qc::MapStatus m;
    if (!qc::decode(f.frame, m)) return;
    ++rec->statuses;
    if (m.frame_seq != rec->last_seq + 1) ++rec->seq_gaps;
    if (m.counter != rec->last_pose_counter) ++rec->counter_mismatches;  // MAP_POSE right before, same Counter
    rec->last_seq = m.frame_seq;
    rec->not_registered += !m.registered;
    rec->not_metric += !m.metric;
    rec->new_nodes += m.new_node;
    rec->last_status = m;
  }
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
  MapRecorder rec;
  d.set_bus_observer(on_map_bus, &rec);
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
  EXPECT_EQ(nav.map().frames(), static_cast<std::uint32_t>(kFrames));
  EXPECT_EQ(nav.map().bad_frames(), 0u);
  EXPECT_EQ(nav.map().save_errors(), 0u);

  // The last frame's pose against the truth, in frame 0's camera axes (as `qnav map eval` scores it).
  const dw::CameraPose p0 = dw::loop_pose(0, 90), pk = dw::loop_pose(kFrames - 1, 90);
  const double cs = std::cos(p0.yaw_rad), sn = std::sin(p0.yaw_rad);
  const Vec2d dt(pk.x_m - p0.x_m, pk.y_m - p0.y_m);
  const Vec2d truth(cs * dt.x() + sn * dt.y(), -sn * dt.x() + cs * dt.y());
  const topo::ChainPose& pose = nav.map().mapper().chain().pose();
  ASSERT_TRUE(pose.metric);
  const double path = 2.0 * 3.14159265358979323846 * 0.8 * (kFrames - 1) / 90.0;
  const double err = (pose.position_m - truth).norm();
  const topo::TopoMap& map = nav.map().mapper().map();
  std::printf("qnavd map: %u frames, path %.2f m, end error %.4f m (%.3f %% of path); map %zu nodes, %zu edges, %u revisits; %u saves; "
              "%llu heap allocations after start; %u deadline misses\n",
              nav.map().frames(), path, err, 100.0 * err / path, map.node_count(), map.edge_count(), map.revisits(), nav.map().saves(),
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

  // CAN: one MAP_POSE + MAP_STATUS per frame, in order, each pair with one Counter; the last pose the
  // worker's (1 cm / 0.0004 rad signals: within half a step), in metres, the map's node count.
  std::printf("qnavd map CAN: %u MAP_POSE, %u MAP_STATUS, last X %.2f m Y %.2f m heading %.4f rad, node %u of %u\n", rec.poses,
              rec.statuses, rec.last_pose.x, rec.last_pose.y, rec.last_pose.heading_rad, rec.last_status.node_id, rec.last_status.node_count);
  EXPECT_EQ(rec.poses, static_cast<std::uint32_t>(kFrames));
  EXPECT_EQ(rec.statuses, static_cast<std::uint32_t>(kFrames));
  EXPECT_EQ(rec.seq_gaps, 0u);
  EXPECT_EQ(rec.counter_mismatches, 0u);
  EXPECT_EQ(rec.not_registered, 0u);
  EXPECT_EQ(rec.not_metric, 0u);
  EXPECT_GT(rec.map_state_frames, 0u);
  EXPECT_NEAR(rec.last_pose.x, pose.position_m.x(), 0.005 + 1e-9);
  EXPECT_NEAR(rec.last_pose.y, pose.position_m.y(), 0.005 + 1e-9);
  EXPECT_NEAR(rec.last_pose.heading_rad, std::remainder(pose.heading_rad, 2.0 * 3.14159265358979323846), 0.0002 + 1e-9);
  EXPECT_LT(std::hypot(rec.last_pose.x - truth.x(), rec.last_pose.y - truth.y()), 0.02 * path);  // the autopilot's pose: the 2 % goal too
  EXPECT_EQ(rec.last_status.node_count, map.node_count());
  EXPECT_EQ(rec.new_nodes, map.node_count());  // every node announced once, when it was created
  EXPECT_LT(rec.last_status.node_id, map.node_count());
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

  // The sim backend, or (device given) the linux backend's downward camera map.device of W x H.
  explicit Worker(bool map_enabled, const char* device = nullptr, int width = 320, int height = 240) {
    cfg.backend = device ? Backend::kLinux : Backend::kSim;
    if (device) cfg.map_device = device;
    cfg.map_width = width;
    cfg.map_height = height;
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
  // The frame pool as a camera source sees it, its slots free (the hand-fed frames above use slot 0
  // and return it to the free queue themselves: not both in one test).
  FramePool pool_view() {
    for (std::uint32_t slot = 0; slot < 4; ++slot) EXPECT_TRUE(free_frames.try_push(slot).is_ok());
    FramePool p;
    p.frames = &frames;
    p.free = &free_frames;
    p.pool = frame_pool.data();
    p.map_width = cfg.map_width;
    p.map_height = cfg.map_height;
    p.slot_bytes = static_cast<std::size_t>(cfg.map_width) * static_cast<std::size_t>(cfg.map_height);
    return p;
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
  // One downward frame of a single grey level (0 black, 255 saturated, 128 textureless).
  void flat_frame(std::uint8_t level) {
    std::fill(frame_pool.begin(), frame_pool.begin() + static_cast<std::ptrdiff_t>(cfg.map_width) * cfg.map_height, level);
    black_frame();
  }
  // The MAP_POSE and MAP_STATUS the worker queued since the last call (the last of each).
  int take_map_frames(qc::MapPose& pose, qc::MapStatus& status) {
    int n = 0;
    hal::CanFrame f;
    while (can_tx.try_pop(f)) {
      if (f.id == qc::kIdMapPose && qc::decode(f, pose)) ++n;
      if (f.id == qc::kIdMapStatus && qc::decode(f, status)) ++n;
    }
    return n;
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
  SoftwareFaults::reset_for_tests();
  Worker w(true);
  w.command(qc::Mode::kMap);
  ASSERT_EQ(w.nav->last_reject(), ModeReject::kNone);
  ASSERT_EQ(w.nav->mode(), qc::Mode::kMap);
  qc::MapPose pose;
  qc::MapStatus st;
  w.take_map_frames(pose, st);
  w.black_frame();
  ASSERT_EQ(w.take_map_frames(pose, st), 2);  // one MAP_POSE and one MAP_STATUS for the frame
  EXPECT_TRUE(st.black);
  EXPECT_FALSE(st.registered);
  EXPECT_FALSE(st.lost);
  EXPECT_EQ(st.node_id, qc::kMapNoNode);
  EXPECT_EQ(st.node_count, 0u);
  EXPECT_EQ(st.frame_seq, 0u);
  EXPECT_EQ(pose.x, 0.0);
  EXPECT_EQ(pose.y, 0.0);
  EXPECT_EQ(w.nav->map().frames(), 1u);
  EXPECT_EQ(w.nav->map().bad_frames(), 1u);
  EXPECT_EQ(w.nav->map().mapper().map().node_count(), 0u);
  EXPECT_FALSE(w.store.exists("r/map_1.qmap"));  // nothing learnt yet, nothing written
  w.flat_frame(255);
  ASSERT_EQ(w.take_map_frames(pose, st), 2);
  EXPECT_TRUE(st.saturated);
  EXPECT_FALSE(st.black);
  EXPECT_FALSE(st.registered);
  w.flat_frame(128);
  ASSERT_EQ(w.take_map_frames(pose, st), 2);
  EXPECT_TRUE(st.textureless);
  EXPECT_FALSE(st.black || st.saturated || st.registered || st.lost);
  EXPECT_EQ(st.node_id, qc::kMapNoNode);
  EXPECT_EQ(w.nav->map().bad_frames(), 3u);
  w.command(qc::Mode::kIdle);
  EXPECT_EQ(w.nav->mode(), qc::Mode::kIdle);
  EXPECT_TRUE(w.store.exists("r/map_1.qmap"));   // written (empty) when the mode was left
  EXPECT_EQ(w.nav->map().saves(), 1u);
  EXPECT_EQ(w.nav->map().save_errors(), 0u);
  EXPECT_EQ(SoftwareFaults::count(), 0u) << (SoftwareFaults::first().what ? SoftwareFaults::first().what : "");
}

// The linux backend: Mode = Map is accepted when the downward camera is configured (map.device) and
// refused (UnsupportedMode) without one, as the config's map_runs() says.
TEST(QnavdMap, LinuxBackendAcceptsModeMapOnlyWithADownwardCamera) {
  Worker without(true, "");  // the linux backend, map.enabled, no map.device
  EXPECT_FALSE(map_runs(without.cfg));
  without.command(qc::Mode::kMap);
  EXPECT_EQ(without.nav->last_reject(), ModeReject::kUnsupportedMode);
  EXPECT_EQ(without.nav->mode(), qc::Mode::kIdle);
  Worker with(true, "/dev/qnav-no-such-camera");  // the worker does not open it: the io thread's source does
  EXPECT_TRUE(map_runs(with.cfg));
  with.command(qc::Mode::kMap);
  EXPECT_EQ(with.nav->last_reject(), ModeReject::kNone);
  EXPECT_EQ(with.nav->mode(), qc::Mode::kMap);
  // The camera's device reported down: FaultCameraLost in Mode = Map.
  with.io.downward_device_down.store(true);
  with.command(qc::Mode::kMap);
  hal::CanFrame f;
  std::uint16_t faults = 0;
  while (with.can_tx.try_pop(f)) {
    qc::NavStatus ns;
    if (f.id == qc::kIdNavStatus && qc::decode(f, ns)) faults = ns.fault_flags;
  }
  EXPECT_NE(faults & qc::fault::kCameraLost, 0u);
}

// The camera falling silent in Mode = Map (no downward frame for map.stale_s) is FaultCameraLost in
// NAV_STATUS, and the next frame clears it; in Idle the silence is no fault.
TEST(QnavdMap, ASilentDownwardCameraIsCameraLostInModeMap) {
  SoftwareFaults::reset_for_tests();
  Worker w(true);
  auto last_faults = [&w] {
    std::uint16_t faults = 0;
    hal::CanFrame f;
    while (w.can_tx.try_pop(f)) {
      qc::NavStatus ns;
      if (f.id == qc::kIdNavStatus && qc::decode(f, ns)) faults = ns.fault_flags;
    }
    return faults;
  };
  w.clock.advance_ns(static_cast<std::int64_t>(3 * w.cfg.map_stale_s * 1e9));  // silent in Idle
  for (int i = 0; i < 4; ++i) w.nav->run_once();
  EXPECT_EQ(last_faults() & qc::fault::kCameraLost, 0u);
  w.command(qc::Mode::kMap);
  ASSERT_EQ(w.nav->mode(), qc::Mode::kMap);
  w.black_frame();  // a frame 0.2 s after entering
  EXPECT_EQ(last_faults() & qc::fault::kCameraLost, 0u);
  w.clock.advance_ns(static_cast<std::int64_t>((w.cfg.map_stale_s + 0.5) * 1e9));
  for (int i = 0; i < 4; ++i) w.nav->run_once();
  EXPECT_NE(last_faults() & qc::fault::kCameraLost, 0u);
  w.black_frame();
  EXPECT_EQ(last_faults() & qc::fault::kCameraLost, 0u);
  EXPECT_EQ(SoftwareFaults::count(), 0u) << (SoftwareFaults::first().what ? SoftwareFaults::first().what : "");
}

// /dev/videoN of the first vivid capture node, or "" when vivid is not loaded.
std::string find_vivid() {
  for (int n = 0; n < 64; ++n) {
    char path[96];
    std::snprintf(path, sizeof path, "/sys/class/video4linux/video%d/name", n);
    FILE* f = std::fopen(path, "r");
    if (!f) continue;
    char name[128] = {};
    const bool ok = std::fgets(name, sizeof name, f) != nullptr;
    std::fclose(f);
    if (ok && std::strncmp(name, "vivid", 5) == 0 && std::strstr(name, "vid-cap") != nullptr) return "/dev/video" + std::to_string(n);
  }
  return "";
}

// The linux backend's downward camera on vivid (the bench's hil_v4l2_gpio_hal loads it; skipped
// without it): LinuxDownwardSource opens it, its frames reach the nav worker in Mode = Map as
// downward frames of map.width x map.height with increasing kernel stamps, each answered on CAN by
// a MAP_POSE + MAP_STATUS with FrameSeq counting up, and the device is not reported down.
TEST(QnavdMap, LinuxDownwardCameraOnVividFeedsTheMapMode) {
  const std::string dev = find_vivid();
  if (dev.empty()) GTEST_SKIP() << "no vivid capture node (modprobe vivid; the bench's hil_v4l2_gpio_hal loads it)";
  SoftwareFaults::reset_for_tests();
  Worker w(true, dev.c_str(), 320, 180);  // a size vivid's webcam input offers
  w.command(qc::Mode::kMap);
  ASSERT_EQ(w.nav->mode(), qc::Mode::kMap);
  LinuxDownwardSource src(w.cfg, w.pool_view(), nullptr);
  constexpr int kFrames = 6;
  int statuses = 0, last_seq = -1;
  std::int64_t last_stamp = -1;
  // Bounded by vivid's frame rate (10-60 frames/s): at most 20 s of 5 ms polls, never a timing assertion.
  for (int i = 0; i < 4000 && statuses < kFrames; ++i) {
    const std::int64_t now = w.clock.now_ns();
    if (!src.poll(now, w.io)) {
      usleep(5000);
      w.clock.advance_ns(5000000);
      continue;
    }
    const FrameMsg* f = w.frames.front();
    if (f == nullptr) continue;  // corrupt or dropped: counted
    EXPECT_TRUE(f->downward);
    EXPECT_EQ(f->width, 320);
    EXPECT_EQ(f->height, 180);
    EXPECT_GT(f->stamp.sample_ns, last_stamp);
    last_stamp = f->stamp.sample_ns;
    // The worker runs on the camera's (monotonic) time: its clock is moved to the frame's.
    if (w.clock.now_ns() < f->stamp.arrival_ns) w.clock.set_ns(f->stamp.arrival_ns);
    for (int k = 0; k < 2; ++k) w.nav->run_once();
    qc::MapPose pose;
    qc::MapStatus st;
    if (w.take_map_frames(pose, st) == 2) {
      EXPECT_EQ(st.frame_seq, last_seq + 1);
      last_seq = st.frame_seq;
      ++statuses;
    }
  }
  EXPECT_TRUE(src.is_open());
  EXPECT_GE(src.fd(), 0);
  EXPECT_FALSE(w.io.downward_device_down.load());
  EXPECT_EQ(w.io.device_errors.load(), 0u);
  EXPECT_EQ(statuses, kFrames);
  EXPECT_EQ(SoftwareFaults::count(), 0u) << (SoftwareFaults::first().what ? SoftwareFaults::first().what : "");
  EXPECT_GE(w.nav->map().frames(), static_cast<std::uint32_t>(kFrames));
  std::printf("vivid %s: %d map frames, %u bad (vivid's test pattern), format %s\n", dev.c_str(), statuses, w.nav->map().bad_frames(),
              src.format() == hal::PixelFormat::kGrey ? "GREY" : "YUYV");
}

}  // namespace
}  // namespace qnav::daemon
