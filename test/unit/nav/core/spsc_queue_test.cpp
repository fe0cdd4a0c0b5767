#include "nav/core/spsc_queue.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <thread>

namespace qnav {
namespace {

TEST(SpscQueue, FullAndEmptyAreReported) {
  SpscQueue<int, 4> q;
  int out = 0;
  EXPECT_EQ(q.try_pop(out).code(), StatusCode::kEmpty);
  for (int i = 0; i < 4; ++i) ASSERT_TRUE(q.try_push(i).is_ok());
  EXPECT_EQ(q.try_push(99).code(), StatusCode::kCapacityExceeded);
  EXPECT_EQ(q.size(), 4u);
  for (int i = 0; i < 4; ++i) {
    ASSERT_TRUE(q.try_pop(out).is_ok());
    EXPECT_EQ(out, i);
  }
  EXPECT_TRUE(q.empty());
}

// Two threads, many items through a small queue: every item arrives once, in order, and nothing
// is invented. (Under qemu-user threads are real host threads, so this runs on every target.)
TEST(SpscQueue, TwoThreadsTransferEverythingInOrder) {
  constexpr std::uint32_t kItems = 200000;
  SpscQueue<std::uint32_t, 64> q;
  std::uint64_t producer_retries = 0;
  std::thread producer([&] {
    for (std::uint32_t i = 0; i < kItems;) {
      if (q.try_push(i).is_ok()) {
        ++i;
      } else {
        ++producer_retries;
        std::this_thread::yield();
      }
    }
  });
  std::uint32_t expected = 0;
  std::uint64_t sum = 0;
  while (expected < kItems) {
    std::uint32_t v = 0;
    if (q.try_pop(v).is_ok()) {
      ASSERT_EQ(v, expected);
      sum += v;
      ++expected;
    } else {
      std::this_thread::yield();
    }
  }
  producer.join();
  EXPECT_EQ(sum, static_cast<std::uint64_t>(kItems) * (kItems - 1) / 2);
  EXPECT_TRUE(q.empty());
}

}  // namespace
}  // namespace qnav
