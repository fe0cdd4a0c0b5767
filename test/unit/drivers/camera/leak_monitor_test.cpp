#include "drivers/camera/leak_monitor.hpp"

#include <gtest/gtest.h>

#include "hal/sim/manual_clock.hpp"
#include "hal/sim/sim_gpio.hpp"

using namespace qnav;
using namespace qnav::drivers::camera;

TEST(LeakMonitor, EdgeLatchesFaultUntilAcknowledgedWhenDry) {
  hal::ManualClock clock(0);
  hal::SimGpioLine line(clock, hal::GpioEdge::kBoth, false);
  LeakMonitor leak(line, true);
  ASSERT_TRUE(leak.start().is_ok());
  EXPECT_FALSE(leak.fault());
  EXPECT_FALSE(leak.poll(0).value());
  line.inject_level(true, 5000);
  EXPECT_TRUE(leak.poll(0).value());
  EXPECT_TRUE(leak.fault());
  EXPECT_EQ(leak.first_leak_ns(), 5000);
  line.inject_level(false, 6000);
  line.inject_level(true, 7000);
  EXPECT_FALSE(leak.poll(0).value());  // already latched: not a new fault
  EXPECT_EQ(leak.leak_events(), 2u);
  EXPECT_EQ(leak.acknowledge(), StatusCode::kNotReady);  // still wet
  line.inject_level(false, 8000);
  leak.poll(0).status().ignore();
  ASSERT_TRUE(leak.acknowledge().is_ok());
  EXPECT_FALSE(leak.fault());
  EXPECT_EQ(leak.first_leak_ns(), 5000);
}

TEST(LeakMonitor, WetAtStartIsAFault) {
  hal::ManualClock clock(0);
  hal::SimGpioLine line(clock, hal::GpioEdge::kBoth, false);  // active-low sensor: false = wet
  LeakMonitor leak(line, false);
  ASSERT_TRUE(leak.start().is_ok());
  EXPECT_TRUE(leak.fault());
}
