// The receiver over a candump log: accepted samples, and one named counter per rejected kind.
#include "drivers/qnavcan/receiver.hpp"

#include <gtest/gtest.h>

#include "hal/sim/can_log_replay.hpp"
#include "test/support/alloc_guard.hpp"

using namespace qnav;
using namespace qnav::drivers::qnavcan;

TEST(QnavCanReceiver, CountsEveryRejectedKindFromALog) {
  const char log[] =
      "(10.000000) can0 100#18FCF40130752A01\n"   // attitude ok, counter 0x2A
      "(10.020000) can0 100#18FCF40130752A01\n"   // same counter again -> stale
      "(10.040000) can0 100#18FCF40130752B00\n"   // Valid = 0 -> invalid
      "(10.060000) can0 100#007DF40130752C01\n"   // roll 3.2 rad -> range
      "(10.080000) can0 100#18FC\n"               // short -> length
      "(10.100000) can0 123#00\n"                 // not ours -> unknown_id
      "(10.120000) can0 00000100#18FCF40130752D01\n"  // extended -> format
      "(10.140000) can0 20000040#0000000000000000\n"  // bus-off error frame
      "(10.160000) can0 102#12D68704D207C000\n"   // depth ok
      "(10.180000) can0 100#18FCF40130752E01\n";  // attitude ok again
  hal::CanLogReplay replay(log, sizeof log - 1, 1000000000LL);
  QnavCanReceiver rx;
  hal::CanRxFrame f;
  int frames = 0;
  QNAV_EXPECT_NO_ALLOC(while (replay.receive(f, 0).is_ok()) {
    rx.on_frame(f).ignore();
    ++frames;
  });
  EXPECT_EQ(frames, 10);
  const auto& c = rx.counters();
  EXPECT_EQ(c.get(RxCounter::kStale), 1u);
  EXPECT_EQ(c.get(RxCounter::kInvalid), 1u);
  EXPECT_EQ(c.get(RxCounter::kRange), 1u);
  EXPECT_EQ(c.get(RxCounter::kLength), 1u);
  EXPECT_EQ(c.get(RxCounter::kUnknownId), 1u);
  EXPECT_EQ(c.get(RxCounter::kFormat), 1u);
  EXPECT_EQ(c.get(RxCounter::kErrorFrame), 1u);
  EXPECT_EQ(rx.accepted(), 3u);
  Stamped<AttitudeIn> att;
  const std::int64_t t_last = 1000000000LL + 180000000LL;
  ASSERT_TRUE(rx.latest_attitude(t_last + 10000000, 50000000, att).is_ok());
  EXPECT_EQ(att.value.counter, 0x2E);
  EXPECT_EQ(att.stamp.sample_ns, t_last);
  EXPECT_EQ(rx.latest_attitude(t_last + 60000000, 50000000, att), StatusCode::kTimeout);
  Stamped<RatesIn> rates;
  EXPECT_EQ(rx.latest_rates(t_last, 50000000, rates), StatusCode::kNotReady);
  Stamped<DepthIn> depth;
  ASSERT_TRUE(rx.latest_depth(t_last, 50000000, depth).is_ok());
  EXPECT_NEAR(depth.value.depth_m, 1234.567, 1e-9);
}
