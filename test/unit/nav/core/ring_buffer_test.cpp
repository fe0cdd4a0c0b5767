#include "nav/core/ring_buffer.hpp"

#include <gtest/gtest.h>

namespace qnav {
namespace {

TEST(RingBuffer, FifoOrderAcrossWrap) {
  RingBuffer<int, 3> r;
  int out = 0;
  for (int round = 0; round < 5; ++round) {
    ASSERT_TRUE(r.push(round * 2).is_ok());
    ASSERT_TRUE(r.push(round * 2 + 1).is_ok());
    ASSERT_TRUE(r.pop(out).is_ok());
    EXPECT_EQ(out, round * 2);
    ASSERT_TRUE(r.pop(out).is_ok());
    EXPECT_EQ(out, round * 2 + 1);
  }
  EXPECT_EQ(r.pop(out).code(), StatusCode::kEmpty);
}

TEST(RingBuffer, PushOnFullIsRejectedAndChangesNothing) {
  RingBuffer<int, 2> r;
  ASSERT_TRUE(r.push(1).is_ok());
  ASSERT_TRUE(r.push(2).is_ok());
  EXPECT_EQ(r.push(3).code(), StatusCode::kCapacityExceeded);
  EXPECT_EQ(*r.at(0), 1);
  EXPECT_EQ(*r.at(1), 2);
  EXPECT_EQ(r.at(2), nullptr);
}

TEST(RingBuffer, PushOverwriteDropsOldestAndReportsIt) {
  RingBuffer<int, 3> r;
  EXPECT_FALSE(r.push_overwrite(1));
  EXPECT_FALSE(r.push_overwrite(2));
  EXPECT_FALSE(r.push_overwrite(3));
  EXPECT_TRUE(r.push_overwrite(4));
  ASSERT_EQ(r.size(), 3u);
  EXPECT_EQ(*r.at(0), 2);
  EXPECT_EQ(*r.newest(), 4);
  r.clear();
  EXPECT_EQ(r.newest(), nullptr);
}

}  // namespace
}  // namespace qnav
