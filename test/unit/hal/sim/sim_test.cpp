#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "hal/sim/can_log_replay.hpp"
#include "hal/sim/manual_clock.hpp"
#include "hal/sim/sim_can.hpp"
#include "hal/sim/sim_gpio.hpp"
#include "hal/sim/sim_serial.hpp"
#include "test/support/alloc_guard.hpp"

using namespace qnav;
using namespace qnav::hal;

TEST(SimCan, DeliversToOtherNodesThroughFiltersWithClockStamps) {
  ManualClock clock(1000);
  SimCanNetwork net(clock);
  SimCanBus a, b, c;
  ASSERT_TRUE(a.attach(net).is_ok());
  ASSERT_TRUE(b.attach(net).is_ok());
  ASSERT_TRUE(c.attach(net).is_ok());
  CanFilter only_100;
  only_100.id = 0x100;
  only_100.mask = kCanSffMask;
  ASSERT_TRUE(c.add_filter(only_100).is_ok());
  CanFrame f;
  f.id = 0x200;
  f.len = 2;
  f.data[0] = 0xAB;
  clock.set_ns(5000);
  CanRxFrame rx;
  QNAV_EXPECT_NO_ALLOC(ASSERT_TRUE(a.send(f).is_ok()));
  EXPECT_EQ(a.receive(rx, 0), StatusCode::kTimeout);  // own frames are not received
  ASSERT_TRUE(b.receive(rx, 0).is_ok());
  EXPECT_EQ(rx.frame.id, 0x200u);
  EXPECT_EQ(rx.frame.data[0], 0xAB);
  EXPECT_EQ(rx.stamp.sample_ns, 5000);
  EXPECT_EQ(c.receive(rx, 0), StatusCode::kTimeout);  // filtered out
  f.id = 0x100;
  ASSERT_TRUE(a.send(f).is_ok());
  EXPECT_TRUE(c.receive(rx, 0).is_ok());
}

TEST(SimCan, OverflowCountsDropsAndErrorFramesNeedSubscription) {
  ManualClock clock;
  SimCanNetwork net(clock);
  SimCanBus tx, rx;
  ASSERT_TRUE(tx.attach(net).is_ok());
  ASSERT_TRUE(rx.attach(net).is_ok());
  CanFrame f;
  f.id = 1;
  for (std::size_t i = 0; i < SimCanBus::kRxDepth + 5; ++i) ASSERT_TRUE(tx.send(f).is_ok());
  EXPECT_EQ(rx.stats().rx_dropped, 5u);
  EXPECT_EQ(rx.stats().rx_frames, SimCanBus::kRxDepth);
  CanRxFrame out;
  while (rx.receive(out, 0).is_ok()) {
  }
  const std::uint8_t d[8] = {};
  net.inject_error(can_error::kBusOff, d);
  EXPECT_EQ(rx.receive(out, 0), StatusCode::kTimeout);
  rx.set_error_frames(true);
  net.inject_error(can_error::kBusOff, d);
  ASSERT_TRUE(rx.receive(out, 0).is_ok());
  EXPECT_TRUE(out.frame.error);
  EXPECT_EQ(rx.stats().bus_off, 1u);
  CanFrame fd;
  fd.fd = true;
  fd.len = 12;
  EXPECT_EQ(tx.send(fd), StatusCode::kUnsupported);
}

TEST(SimSerial, PipeCarriesBytesBothWaysAndReportsShortWrites) {
  ManualClock clock(42);
  SimSerialPipe pipe(clock);
  const std::uint8_t msg[] = {'w', 'c', 'v', '\n'};
  auto w = pipe.a().write(Span<const std::uint8_t>(msg, sizeof msg));
  ASSERT_TRUE(w.is_ok());
  EXPECT_EQ(w.value(), 4u);
  std::uint8_t buf[16];
  auto r = pipe.b().read(Span<std::uint8_t>(buf, sizeof buf), 0);
  ASSERT_TRUE(r.is_ok());
  EXPECT_EQ(r.value().bytes, 4u);
  EXPECT_EQ(r.value().arrival_ns, 42);
  EXPECT_EQ(std::memcmp(buf, msg, 4), 0);
  EXPECT_EQ(pipe.a().read(Span<std::uint8_t>(buf, sizeof buf), 0).value().bytes, 0u);
  static std::uint8_t big[SimSerialPipe::kCapacity + 10];
  auto w2 = pipe.b().write(Span<const std::uint8_t>(big, sizeof big));
  EXPECT_EQ(w2.value(), SimSerialPipe::kCapacity);
  EXPECT_EQ(pipe.b().stats().tx_short, 1u);
}

TEST(SimGpio, EdgesFollowTheConfiguredSense) {
  ManualClock clock(0);
  SimGpioLine rising(clock, GpioEdge::kRising);
  rising.inject_level(true, 100);
  rising.inject_level(false, 200);
  rising.inject_level(true, 300);
  auto e1 = rising.wait_event(0);
  ASSERT_TRUE(e1.is_ok());
  EXPECT_TRUE(e1.value().rising);
  EXPECT_EQ(e1.value().stamp.sample_ns, 100);
  EXPECT_EQ(rising.wait_event(0).value().stamp.sample_ns, 300);
  EXPECT_EQ(rising.wait_event(0).status(), StatusCode::kTimeout);
  clock.set_ns(77);
  ASSERT_TRUE(rising.set(true).is_ok());
  EXPECT_EQ(rising.last_set_ns(), 77);
}

TEST(CanLogReplay, ReplaysFramesWithRelativeTimesAndCountsBadLines) {
  const char log[] =
      "(100.000000) can0 100#0102\n"
      "garbage line\n"
      "\n"
      "(100.010000) can0 1F334455#AA\n"
      "(100.020000) can0 20000040#0000000000000000\n";
  CanLogReplay rp(log, sizeof log - 1, 1000000);
  CanRxFrame f;
  ASSERT_TRUE(rp.receive(f, 0).is_ok());
  EXPECT_EQ(f.frame.id, 0x100u);
  EXPECT_EQ(f.stamp.sample_ns, 1000000);
  ASSERT_TRUE(rp.receive(f, 0).is_ok());
  EXPECT_TRUE(f.frame.extended);
  EXPECT_EQ(f.stamp.sample_ns, 1000000 + 10000000);
  EXPECT_EQ(rp.bad_lines(), 1u);
  ASSERT_TRUE(rp.receive(f, 0).is_ok());
  EXPECT_TRUE(f.frame.error);
  EXPECT_EQ(rp.stats().bus_off, 1u);
  EXPECT_EQ(rp.receive(f, 0), StatusCode::kTimeout);
  EXPECT_TRUE(rp.finished());
}

// Regression (issue #19): a timestamp far from the first one made (time_us - first_us) * 1000
// overflow (UBSan); it is a counted bad line now. A run of more than kMaxSkipPerCall bad lines
// pauses receive() (kTimeout) but the log is read to its end, and the first bad line is named.
TEST(CanLogReplay, FarTimestampsAndLongGarbageRunsAreCountedNotWrapped) {
  std::string log = "(1436509052.249713) can0 100#01\n";
  for (int i = 0; i < 100; ++i) log += "garbage\n";
  log += "(999999999999.000000) can0 101#02\n";  // 31,000 years later
  log += "(1436509053.249713) can0 102#03\n";
  CanLogReplay rp(log.data(), log.size(), 0);
  CanRxFrame f;
  std::vector<std::uint32_t> ids;
  std::vector<std::int64_t> stamps;
  while (!rp.finished()) {
    if (rp.receive(f, 0).is_ok()) {
      ids.push_back(f.frame.id);
      stamps.push_back(f.stamp.sample_ns);
    }
  }
  ASSERT_EQ(ids.size(), 2u);
  EXPECT_EQ(ids[1], 0x102u);
  EXPECT_EQ(stamps[1], 1000000000);
  EXPECT_EQ(rp.bad_lines(), 101u);
  EXPECT_EQ(rp.first_bad_line(), 2u);
}
