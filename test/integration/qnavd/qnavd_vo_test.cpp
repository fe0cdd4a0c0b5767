// qnavd's vo mode on the sim backend: the simulated autopilot commands Mode = Vo, the rover drives
// the Mars yard (drivers/stereo_sim, the scene `qnav vo eval` measures on) and the daemon's
// QNAV_VO_STEP frames are checked from the autopilot's side of the bus:
//  - summed, the increments give the rover's path (truth from the simulator) within 1 % of its length,
//    every frame carries a new counter (an increment is never repeated), NAV_STATUS reports State = Vo
//    with no camera fault, and nothing is allocated on the heap after start;
//  - the camera falling silent is reported as FaultCameraLost while it lasts, and visual steps resume.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <unistd.h>

#include "drivers/qnavcan/messages.hpp"
#include "firmware/qnavd/daemon.hpp"
#include "firmware/qnavd/software_fault.hpp"
#include "test/support/alloc_guard.hpp"

namespace qnav::daemon {
namespace {

namespace qc = drivers::qnavcan;

// What the autopilot saw (bus observer, io thread) and what the nav worker reported (nav thread);
// read after run() has joined both.
struct VoRecorder {
  // VO_STEP increments summed as an autopilot would: in the level frame of its own heading.
  double north_m = 0.0, east_m = 0.0, heading_rad = 0.0;
  bool heading_set = false;
  std::uint32_t vo_frames = 0, counter_repeats = 0, dead_reckoned_frames = 0;
  int last_counter = -1;
  std::uint32_t vo_state_frames = 0, camera_lost_in_vo = 0;
  std::uint16_t last_faults_in_vo = 0;
  bool camera_lost_seen = false;
  // Nav worker reports.
  std::uint32_t pairs = 0, visual = 0, visual_after_loss = 0;
  Pose3 first_truth, last_truth, last_vo;
  double last_path_m = 0.0;
  bool have_first = false;
};

void on_pair(void* ctx, const FrameReport& r) {
  auto* rec = static_cast<VoRecorder*>(ctx);
  ++rec->pairs;
  rec->visual += r.visual;
  if (rec->camera_lost_seen && r.visual) ++rec->visual_after_loss;
  if (!rec->have_first && r.has_truth) {
    rec->first_truth = r.truth_world_T_body;
    rec->have_first = true;
  }
  rec->last_truth = r.truth_world_T_body;
  rec->last_vo = r.world_T_body;
  rec->last_path_m = r.truth_path_m;
}

void on_bus(void* ctx, const hal::CanRxFrame& f) {
  auto* rec = static_cast<VoRecorder*>(ctx);
  if (f.frame.id == qc::kIdNavStatus) {
    qc::NavStatus ns;
    if (qc::decode(f.frame, ns) && ns.state == qc::Mode::kVo) {
      ++rec->vo_state_frames;
      rec->last_faults_in_vo = ns.fault_flags;
      if (ns.fault_flags & qc::fault::kCameraLost) {
        ++rec->camera_lost_in_vo;
        rec->camera_lost_seen = true;
      }
    }
    return;
  }
  if (f.frame.id != qc::kIdVoStep) return;
  qc::VoStep v;
  if (!qc::decode(f.frame, v)) return;
  ++rec->vo_frames;
  if (rec->last_counter >= 0 && v.counter == rec->last_counter) ++rec->counter_repeats;
  rec->last_counter = v.counter;
  if (v.inliers == 0) ++rec->dead_reckoned_frames;
  const double c = std::cos(rec->heading_rad), s = std::sin(rec->heading_rad);
  rec->north_m += c * v.dx_m - s * v.dy_m;
  rec->east_m += s * v.dx_m + c * v.dy_m;
  rec->heading_rad += v.dyaw_rad;
}

std::string temp_dir() {
  char t[] = "/tmp/qnavd_vo_test_XXXXXX";
  const char* d = mkdtemp(t);
  return d ? std::string(d) : std::string("/tmp");
}

DaemonConfig vo_config(double length_m) {
  DaemonConfig c;
  c.backend = Backend::kSim;
  c.route_dir = temp_dir();
  c.log = LogFormat::kOff;
  c.realtime = false;
  c.sim_speed = SimSpeed::kFast;
  c.sim_length_m = 200.0;       // the side-scan survey is built but not flown
  c.vo_budget_us = 10000000;    // timing is measured by the benchmark, not asserted (ASan is slow)
  SimPass p;
  p.mode = qc::Mode::kVo;
  p.length_m = length_m;
  static_cast<void>(c.sim_mission.push_back(p));
  return c;
}

// Watches d's stereo pairs and bus frames with rec, and starts it.
void start_watched(Daemon& d, VoRecorder& rec) {
  d.set_frame_observer(on_pair, &rec);
  d.set_bus_observer(on_bus, &rec);
  ASSERT_TRUE(d.init(nullptr));
  ASSERT_TRUE(d.start());
}

// Flies d's whole mission: it must end by itself, with no software fault.
void fly(Daemon& d, VoRecorder& rec) {
  start_watched(d, rec);
  if (::testing::Test::HasFatalFailure()) return;
  ASSERT_EQ(d.run(), 0);
  EXPECT_TRUE(d.mission_done());
  EXPECT_EQ(SoftwareFaults::count(), 0u) << (SoftwareFaults::first().what ? SoftwareFaults::first().what : "");
}

// The autopilot starts its sum at the rover's true heading (it knows where it points at the start).
double start_heading(const Pose3& truth) { return std::atan2(truth.R(1, 0), truth.R(0, 0)); }

TEST(QnavdVo, VoStepFramesSumToTheRoversPath) {
  SoftwareFaults::reset_for_tests();
  const DaemonConfig c = vo_config(8.0);
  auto rec = std::make_unique<VoRecorder>();
  Daemon d(c);
  start_watched(d, *rec);
  if (HasFatalFailure()) return;
  test::AllocationGuard guard;
  std::uint64_t allocs = 0;
  {
    test::EigenMallocForbidden no_eigen_malloc;
    ASSERT_EQ(d.run(), 0);
    allocs = guard.allocations();
  }
  EXPECT_TRUE(d.mission_done());
  EXPECT_EQ(SoftwareFaults::count(), 0u) << (SoftwareFaults::first().what ? SoftwareFaults::first().what : "");
  ASSERT_TRUE(rec->have_first);
  // The sum was started at heading 0; turn it into the start heading (a rotation about the origin).
  const double h0 = start_heading(rec->first_truth);
  const double n = std::cos(h0) * rec->north_m - std::sin(h0) * rec->east_m;
  const double e = std::sin(h0) * rec->north_m + std::cos(h0) * rec->east_m;
  const Vec3d truth_end = rec->last_truth.t;
  const double bus_err = std::hypot(n - truth_end.x(), e - truth_end.y());
  const double vo_err = (rec->last_vo.t - truth_end).norm();
  const double path = rec->last_path_m;
  std::printf("qnavd vo: %u pairs (%u visual), %.2f m path; VO pose end error %.4f m (%.3f %%); %u VO_STEP frames summed by the "
              "autopilot: end error %.4f m (%.3f %%); %llu heap allocations after start; %u deadline misses\n",
              rec->pairs, rec->visual, path, vo_err, 100.0 * vo_err / path, rec->vo_frames, bus_err, 100.0 * bus_err / path,
              static_cast<unsigned long long>(allocs), d.nav().deadline_misses());
  ASSERT_GT(path, 7.5);
  EXPECT_GE(rec->pairs, 30u);
  EXPECT_GE(rec->visual, rec->pairs * 9 / 10) << "the Mars yard is textured: nearly every pair is a visual step";
  EXPECT_LT(vo_err, 0.005 * path);
  EXPECT_LT(bus_err, 0.01 * path) << "the increments on the bus must add up to the path (none lost, none repeated)";
  EXPECT_GE(rec->vo_frames, rec->visual / 2);
  EXPECT_EQ(rec->counter_repeats, 0u) << "an increment is sent once";
  EXPECT_GT(rec->vo_state_frames, 5u);
  EXPECT_EQ(rec->camera_lost_in_vo, 0u);
  EXPECT_EQ(d.nav().vo().no_attitude(), 0u);
  if (test::malloc_counted()) {
    EXPECT_EQ(allocs, 0u) << guard.report();
  }
}

// The attitude from a DroneCAN AHRS (uavcan.equipment.ahrs.Solution: the full quaternion) instead of
// QNAV_ATTITUDE_IN: the same odometry.
TEST(QnavdVo, DroneCanAhrsGivesTheAttitude) {
  SoftwareFaults::reset_for_tests();
  DaemonConfig c = vo_config(4.0);
  c.sim_ahrs = "dronecan";
  auto rec = std::make_unique<VoRecorder>();
  Daemon d(c);
  fly(d, *rec);
  if (HasFatalFailure()) return;
  ASSERT_TRUE(rec->have_first);
  const double err = (rec->last_vo.t - rec->last_truth.t).norm();
  std::printf("qnavd vo, DroneCAN AHRS: %u pairs (%u visual), %.2f m path, end error %.4f m\n", rec->pairs, rec->visual,
              rec->last_path_m, err);
  EXPECT_EQ(d.nav().vo().no_attitude(), 0u);
  EXPECT_GE(rec->visual, rec->pairs * 9 / 10);
  EXPECT_LT(err, 0.005 * rec->last_path_m);
}

TEST(QnavdVo, CameraLossIsReportedAndVisualStepsResume) {
  SoftwareFaults::reset_for_tests();
  DaemonConfig c = vo_config(8.0);
  c.sim_stall = "camera";
  c.sim_stall_pass = 0;
  c.sim_stall_start_s = 6.0;  // mission time after the start of the pass (about 2.4 m in)
  c.sim_stall_s = 4.0;        // longer than vo.stale_s (2 s)
  auto rec = std::make_unique<VoRecorder>();
  Daemon d(c);
  fly(d, *rec);
  if (HasFatalFailure()) return;
  std::printf("qnavd vo, camera silent 4 s: %u pairs (%u visual, %u after the loss), %u NAV_STATUS frames with FaultCameraLost\n",
              rec->pairs, rec->visual, rec->visual_after_loss, rec->camera_lost_in_vo);
  EXPECT_TRUE(rec->camera_lost_seen) << "no pair for longer than vo.stale_s must be reported";
  // (How many NAV_STATUS frames say so depends on how the fast simulation batches the attitude frames
  // of the silent stretch: at least one, in State = Vo.)
  EXPECT_GE(rec->visual_after_loss, 5u) << "the odometry resumes when pairs return";
  EXPECT_EQ(rec->last_faults_in_vo & qc::fault::kCameraLost, 0) << "cleared once pairs return";
}

}  // namespace
}  // namespace qnav::daemon
