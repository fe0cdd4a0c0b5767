// qnavd's V4L2 stereo source on devices that are not there or are not cameras: the failure is
// counted, flagged (camera_device_down, which the nav worker reports as FaultCameraLost in Vo mode),
// logged once with the OS's reason, and retried once a second, without blocking the io thread.
// (Real V4L2 devices: the hardware-in-the-loop bench, docs/hil.md.)
#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include "test/integration/qnavd/test_frame_pool.hpp"
#include "firmware/qnavd/linux_stereo.hpp"

namespace qnav::daemon {
namespace {

void expect_down_and_retried(const char* left, const char* right, const char* reason) {
  DaemonConfig c;
  c.backend = Backend::kLinux;
  c.vo_enabled = true;
  c.vo_camera = CameraSource::kV4l2;
  c.vo_left_device = left;
  c.vo_right_device = right;
  TestFramePool pool(c);
  FILE* log = std::tmpfile();
  ASSERT_NE(log, nullptr);
  IoCounters io;
  LinuxStereoSource src(c, pool.view, log);
  const std::int64_t t0 = 5000000000;
  EXPECT_FALSE(src.poll(t0, io));
  EXPECT_TRUE(io.camera_device_down.load());
  EXPECT_EQ(io.device_errors.load(), 1u);
  EXPECT_FALSE(src.poll(t0 + 500000000, io));  // not retried within the second
  EXPECT_EQ(io.device_errors.load(), 1u);
  EXPECT_FALSE(src.poll(t0 + 1000000000, io));  // retried after it
  EXPECT_EQ(io.device_errors.load(), 2u);
  EXPECT_TRUE(io.camera_device_down.load());
  EXPECT_EQ(io.frames_in.load(), 0u);
  EXPECT_EQ(pool.frames.size(), 0u);
  EXPECT_EQ(src.left_fd(), -1);
  const std::string text = read_all(log);
  std::fclose(log);
  EXPECT_NE(text.find("\"event\":\"device\""), std::string::npos) << text;
  EXPECT_NE(text.find(reason), std::string::npos) << text;
  EXPECT_EQ(text.find("\"event\":\"device\""), text.rfind("\"event\":\"device\"")) << "logged once until the device is back:\n" << text;
}

TEST(LinuxStereo, MissingCameraIsDownCountedLoggedAndRetried) {
  expect_down_and_retried("/dev/qnav-no-such-camera0", "/dev/qnav-no-such-camera1", "/dev/qnav-no-such-camera0");
}

TEST(LinuxStereo, ADeviceThatIsNotACameraIsRefused) {
  expect_down_and_retried("/dev/null", "/dev/null", "/dev/null");
}

}  // namespace
}  // namespace qnav::daemon
