#include "drivers/camera/stereo_pairer.hpp"

#include <gtest/gtest.h>

#include "test/support/alloc_guard.hpp"

using namespace qnav;
using namespace qnav::drivers::camera;

namespace {
FrameRef ref(std::uint32_t seq, std::int64_t t, std::uint8_t slot) {
  FrameRef f;
  f.sequence = seq;
  f.stamp.sample_ns = t;
  f.slot = slot;
  return f;
}
}  // namespace

TEST(StereoPairer, PairsWithinToleranceAndDropsOrphans) {
  StereoPairer p(2000000);  // 2 ms
  PairRef out;
  std::uint8_t dropped[StereoPairer::kDepth + 1];
  std::size_t nd = 0;
  // 20 Hz stream; right lags 0.8 ms; right frame 3 is lost; left frame 6 is lost.
  int pairs = 0;
  QNAV_EXPECT_NO_ALLOC(for (int i = 0; i < 10; ++i) {
    const std::int64_t t = 1000000000LL + i * 50000000LL;
    if (i != 6 && p.push(Side::kLeft, ref(i, t, static_cast<std::uint8_t>(i % 4)), out, dropped, nd)) ++pairs;
    if (i != 3 && p.push(Side::kRight, ref(i, t + 800000, static_cast<std::uint8_t>(i % 4)), out, dropped, nd)) {
      ++pairs;
      EXPECT_EQ(out.left.sequence, out.right.sequence);
      EXPECT_EQ(out.skew_ns, 800000);
    }
  });
  EXPECT_EQ(pairs, 8);
  EXPECT_EQ(p.pairs(), 8u);
  // Left 3 and right 6 could never pair: dropped when newer frames proved it.
  EXPECT_EQ(p.counters().get(PairCounter::kUnmatched), 2u);
}

TEST(StereoPairer, RejectsOutOfOrderAndPicksTheClosest) {
  StereoPairer p(5000000);
  PairRef out;
  std::uint8_t dropped[StereoPairer::kDepth + 1];
  std::size_t nd = 0;
  EXPECT_FALSE(p.push(Side::kLeft, ref(1, 100000000, 0), out, dropped, nd));
  EXPECT_FALSE(p.push(Side::kLeft, ref(2, 104000000, 1), out, dropped, nd));
  EXPECT_FALSE(p.push(Side::kLeft, ref(0, 90000000, 2), out, dropped, nd));  // older than left 2
  EXPECT_EQ(nd, 1u);
  EXPECT_EQ(dropped[0], 2);
  EXPECT_EQ(p.counters().get(PairCounter::kOutOfOrder), 1u);
  // Right at 103.5 ms: both lefts are within 5 ms; the closest (104) wins, the older one is dropped.
  ASSERT_TRUE(p.push(Side::kRight, ref(7, 103500000, 0), out, dropped, nd));
  EXPECT_EQ(out.left.sequence, 2u);
  EXPECT_EQ(out.skew_ns, -500000);
  EXPECT_EQ(nd, 1u);
  EXPECT_EQ(dropped[0], 0);
  EXPECT_EQ(p.queued_slots(Side::kLeft), 0u);
}
