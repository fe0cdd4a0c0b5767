// V4L2 and libgpiod backends: error paths always; a real device only when present (vivid, gpio-sim).
#include <gtest/gtest.h>

#include "hal/linux/v4l2_camera.hpp"
#ifdef QNAV_HAVE_GPIOD
#include "hal/linux/gpiod_line.hpp"
#endif

using namespace qnav;
using namespace qnav::hal;

TEST(V4l2Camera, OpenErrorsAreValues) {
  V4l2Camera cam;
  CameraConfig c;
  c.device = "/dev/qnav-no-video";
  EXPECT_EQ(cam.open(c), StatusCode::kNotFound);
  c.device = "/dev/null";
  EXPECT_EQ(cam.open(c), StatusCode::kUnsupported);  // not a V4L2 device
  c.buffer_count = 1;
  EXPECT_EQ(cam.open(c), StatusCode::kInvalidArgument);
  std::uint8_t px[4];
  auto v = ImageView<std::uint8_t>::make(px, 2, 2).value();
  EXPECT_EQ(cam.capture(v, 0).status(), StatusCode::kNotReady);
}

#ifdef QNAV_HAVE_GPIOD
TEST(GpiodLine, MissingChipIsAnError) {
  GpiodOutputLine out;
  GpioLineConfig c;
  c.chip = "/dev/qnav-no-gpiochip";
  EXPECT_EQ(out.open(c, false), StatusCode::kNotFound);
  EXPECT_EQ(out.set(true), StatusCode::kNotReady);
  GpiodInputLine in;
  EXPECT_EQ(in.open(c, GpioEdge::kBoth), StatusCode::kNotFound);
  EXPECT_EQ(in.wait_event(0).status(), StatusCode::kNotReady);
}
#endif
