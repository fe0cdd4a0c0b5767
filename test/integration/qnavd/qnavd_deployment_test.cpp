// The deployment table builds the daemon (issue #26): every static buffer qnavd uses comes out of
// one block allocated at start-up, sized by the table and carved by the table's names, so the table
// `qnavd --print-deployment` prints cannot disagree with what runs. Measured, not assumed: the
// allocation counter sees one allocation of exactly the table's static total during init(), the
// block is used to the last byte, and the owned buffers hold the table's bytes.
#include <gtest/gtest.h>

#include <cstdlib>
#include <string>
#include <unistd.h>

#include "firmware/qnavd/daemon.hpp"
#include "firmware/qnavd/deployment.hpp"
#include "firmware/qnavd/static_memory.hpp"
#include "test/support/alloc_guard.hpp"

namespace qnav::daemon {
namespace {

namespace qc = drivers::qnavcan;

std::string temp_dir() {
  char t[] = "/tmp/qnavd_deployment_test_XXXXXX";
  const char* d = mkdtemp(t);
  return d ? std::string(d) : std::string("/tmp");
}

DaemonConfig sim_config(bool vo, bool map) {
  DaemonConfig c;
  c.backend = Backend::kSim;
  c.route_dir = temp_dir();
  c.log = LogFormat::kOff;
  c.realtime = false;
  c.sim_speed = SimSpeed::kFast;
  c.sim_length_m = 200.0;
  c.vo_enabled = vo;
  c.map_enabled = map;
  SimPass p;
  p.mode = qc::Mode::kTeach;
  static_cast<void>(c.sim_mission.push_back(p));
  c.route_id = 3;
  return c;
}

std::size_t static_entries(const Deployment& d) {
  std::size_t n = 0;
  for (std::size_t i = 0; i < d.buffer_count; ++i) n += d.buffers[i].kind == BufferKind::kStatic;
  return n;
}

void expect_table_builds_daemon(const DaemonConfig& c, const char* what) {
  SCOPED_TRACE(what);
  const Deployment table = make_deployment(c);
  ASSERT_GT(table.total_static_bytes(), 0u);
  Daemon d(c);
  const std::size_t before = test::new_bytes();
  test::watch_new_size(table.total_static_bytes());
  ASSERT_TRUE(d.init(nullptr));
  const std::size_t blocks = test::watched_new_count();
  test::watch_new_size(0);
  const std::size_t init_bytes = test::new_bytes() - before;
  // One allocation of exactly the table's static total, and every byte of it handed out by name.
  EXPECT_EQ(blocks, 1u);
  const StaticMemory& mem = d.static_memory();
  EXPECT_EQ(mem.capacity(), table.total_static_bytes());
  EXPECT_EQ(mem.used(), mem.capacity());
  EXPECT_EQ(mem.taken(), static_entries(table));
  EXPECT_GE(init_bytes, table.total_static_bytes());
  // The configuration in force (a simulated survey changes no geometry) gives the same table.
  EXPECT_EQ(make_deployment(d.config()).total_static_bytes(), table.total_static_bytes());
  // Owned buffers: the component holds the table's bytes.
  ASSERT_NE(table.buffer("route_meta"), nullptr);
  EXPECT_EQ(d.nav().repeat().meta_bytes(), table.buffer("route_meta")->bytes);
  // The printed table states the totals it was built with.
  const std::string text = deployment_text(table);
  EXPECT_NE(text.find("static " + std::to_string(table.total_static_bytes()) + " B (one block)"), std::string::npos) << text;
  EXPECT_NE(text.find("log.nav"), std::string::npos);
  EXPECT_NE(text.find("queue.dvl"), std::string::npos);
  EXPECT_NE(text.find("\n  main "), std::string::npos) << "the main thread is in the table";
}

TEST(DeploymentTable, BuildsTheSonarDaemonFromOneStaticBlock) { expect_table_builds_daemon(sim_config(false, false), "sonar only"); }

TEST(DeploymentTable, BuildsTheDaemonWithVoAndMapFromOneStaticBlock) {
  DaemonConfig c = sim_config(true, true);
  c.map_width = 320;
  c.map_height = 240;
  expect_table_builds_daemon(c, "vo + map");
  const Deployment t = make_deployment(c);
  EXPECT_NE(t.buffer("vo"), nullptr);
  EXPECT_NE(t.buffer("map"), nullptr);
  EXPECT_NE(t.buffer("frame_pool"), nullptr);
}

TEST(DeploymentTable, BuildsTheDaemonWithMavlinkFromOneStaticBlock) {
  DaemonConfig c = sim_config(false, false);
  c.mavlink_enabled = true;
  c.mavlink_udp_listen_port = 0;
  c.mavlink_udp_remote = "127.0.0.1:9";  // the discard port: nothing is read from it here
  expect_table_builds_daemon(c, "mavlink");
  const Deployment t = make_deployment(c);
  ASSERT_NE(t.buffer("queue.mav_rx"), nullptr);
  ASSERT_NE(t.buffer("queue.mav_tx"), nullptr);
  EXPECT_GE(t.buffer("queue.mav_tx")->bytes, kMavTxQueue * sizeof(MavBytes));
  EXPECT_EQ(make_deployment(sim_config(false, false)).buffer("queue.mav_rx"), nullptr) << "mavlink off: no MAVLink queues";
}

TEST(DeploymentTable, TheDvlQueueDepthComesFromOneConstant) {
  const Deployment t = make_deployment(sim_config(false, false));
  const QueueSpec* dvl = nullptr;
  for (const QueueSpec& q : t.queues)
    if (std::string(q.name) == "dvl") dvl = &q;
  ASSERT_NE(dvl, nullptr);
  EXPECT_EQ(dvl->depth, kDvlQueueCapacity);
  ASSERT_NE(t.buffer("queue.dvl"), nullptr);
  EXPECT_GE(t.buffer("queue.dvl")->bytes, kDvlQueueCapacity * sizeof(drivers::dvl::DvlVelocity));
}

TEST(DeploymentTable, LinuxBackendListsItsDriverBuffers) {
  DaemonConfig c = sim_config(true, false);
  c.backend = Backend::kLinux;
  c.vo_camera = CameraSource::kV4l2;
  const Deployment t = make_deployment(c);
  ASSERT_NE(t.buffer("jsf_framer"), nullptr);
  EXPECT_EQ(t.buffer("jsf_framer")->bytes, 256u * 1024u);
  EXPECT_NE(t.buffer("dvl_driver_queue"), nullptr);
  EXPECT_NE(t.buffer("stereo_pairer"), nullptr);
  ASSERT_NE(t.buffer("stereo_v4l2"), nullptr);
  EXPECT_EQ(t.buffer("stereo_v4l2")->kind, BufferKind::kKernel);
  EXPECT_GT(t.total_heap_bytes(), t.total_static_bytes());
}

TEST(StaticMemory, RefusesWhatTheTableDoesNotSay) {
  const Deployment t = make_deployment(sim_config(false, false));
  StaticMemory mem(t);
  Result<Span<std::byte>> unknown = mem.take("no_such_buffer");
  EXPECT_FALSE(unknown);
  EXPECT_STREQ(mem.failed_name(), "no_such_buffer");
  EXPECT_FALSE(mem.take("route_meta")) << "an owned buffer is not in the static block";
  Result<Span<std::uint8_t>> pool = mem.take_array<std::uint8_t>("ping_pool", 16);
  ASSERT_TRUE(pool);
  EXPECT_FALSE(mem.take("ping_pool")) << "taken twice";
  Result<Span<double>> too_big = mem.take_array<double>("queue.can_tx", 1u << 20);
  EXPECT_FALSE(too_big);
  EXPECT_STREQ(mem.failed_name(), "queue.can_tx");
  const Status done = mem.complete();
  EXPECT_FALSE(done) << "buffers left untaken";
}

}  // namespace
}  // namespace qnav::daemon
