// qnavd's downward V4L2 camera (linux backend, map.device) on devices that are not there or are not
// cameras: the failure is counted, flagged (downward_device_down, which the nav worker reports as
// FaultCameraLost in Mode = Map), logged once with the OS's reason, and retried once a second,
// without blocking the io thread or touching the frame pool. (On vivid:
// QnavdMap.LinuxDownwardCameraOnVividFeedsTheMapMode in qnavd_map_test.cpp.)
#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include "test/integration/qnavd/test_frame_pool.hpp"
#include "firmware/qnavd/linux_downward.hpp"

namespace qnav::daemon {
namespace {

void expect_down_and_retried(const char* device) {
  DaemonConfig c;
  c.backend = Backend::kLinux;
  c.vo_enabled = false;
  c.map_enabled = true;
  c.map_device = device;
  ASSERT_TRUE(map_runs(c));
  TestFramePool pool(c);
  FILE* log = std::tmpfile();
  ASSERT_NE(log, nullptr);
  IoCounters io;
  LinuxDownwardSource src(c, pool.view, log);
  const std::int64_t t0 = 5000000000;
  EXPECT_FALSE(src.poll(t0, io));
  EXPECT_TRUE(io.downward_device_down.load());
  EXPECT_FALSE(io.camera_device_down.load());  // the stereo pair's flag is its own
  EXPECT_EQ(io.device_errors.load(), 1u);
  EXPECT_FALSE(src.poll(t0 + 500000000, io));  // not retried within the second
  EXPECT_EQ(io.device_errors.load(), 1u);
  EXPECT_FALSE(src.poll(t0 + 1000000000, io));  // retried after it
  EXPECT_EQ(io.device_errors.load(), 2u);
  EXPECT_TRUE(io.downward_device_down.load());
  EXPECT_EQ(io.frames_in.load(), 0u);
  EXPECT_EQ(pool.frames.size(), 0u);
  EXPECT_EQ(pool.free.size(), 4u);  // no slot taken while the device is down
  EXPECT_EQ(src.fd(), -1);
  EXPECT_FALSE(src.is_open());
  const std::string text = read_all(log);
  std::fclose(log);
  EXPECT_NE(text.find("\"event\":\"device\""), std::string::npos) << text;
  EXPECT_NE(text.find(device), std::string::npos) << text;
  EXPECT_EQ(text.find("\"event\":\"device\""), text.rfind("\"event\":\"device\"")) << "logged once until the device is back:\n" << text;
}

TEST(LinuxDownward, MissingCameraIsDownCountedLoggedAndRetried) { expect_down_and_retried("/dev/qnav-no-such-downward-camera"); }

TEST(LinuxDownward, ADeviceThatIsNotACameraIsRefused) { expect_down_and_retried("/dev/null"); }

}  // namespace
}  // namespace qnav::daemon
