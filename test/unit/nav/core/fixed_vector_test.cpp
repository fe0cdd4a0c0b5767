#include "nav/core/fixed_vector.hpp"

#include <gtest/gtest.h>

namespace qnav {
namespace {

TEST(FixedVector, PushUntilFullThenRejectsWithoutWriting) {
  FixedVector<int, 3> v;
  EXPECT_EQ(v.capacity(), 3u);
  EXPECT_TRUE(v.push_back(1).is_ok());
  EXPECT_TRUE(v.push_back(2).is_ok());
  EXPECT_TRUE(v.push_back(3).is_ok());
  EXPECT_TRUE(v.full());
  const Status s = v.push_back(4);
  EXPECT_EQ(s.code(), StatusCode::kCapacityExceeded);
  ASSERT_EQ(v.size(), 3u);
  EXPECT_EQ(v[0], 1);
  EXPECT_EQ(v[2], 3);
  EXPECT_EQ(v.emplace_back(), nullptr);
}

TEST(FixedVector, OverflowDoesNotTouchNeighbouringMemory) {
  struct Guarded {
    std::uint32_t before = 0xA5A5A5A5u;
    FixedVector<std::uint32_t, 4> v;
    std::uint32_t after = 0x5A5A5A5Au;
  } g;
  for (std::uint32_t i = 0; i < 100; ++i) g.v.push_back(0xFFFFFFFFu).ignore();
  EXPECT_EQ(g.v.size(), 4u);
  EXPECT_EQ(g.before, 0xA5A5A5A5u);
  EXPECT_EQ(g.after, 0x5A5A5A5Au);
}

TEST(FixedVector, EraseKeepsOrderSwapEraseMovesLast) {
  FixedVector<int, 5> v;
  for (int i = 0; i < 5; ++i) ASSERT_TRUE(v.push_back(i * 10).is_ok());
  ASSERT_TRUE(v.erase(1).is_ok());
  EXPECT_EQ(v.size(), 4u);
  EXPECT_EQ(v[1], 20);
  EXPECT_EQ(v[3], 40);
  ASSERT_TRUE(v.swap_erase(0).is_ok());
  EXPECT_EQ(v[0], 40);
  EXPECT_EQ(v.size(), 3u);
  EXPECT_EQ(v.erase(3).code(), StatusCode::kOutOfRange);
  EXPECT_EQ(v.swap_erase(99).code(), StatusCode::kOutOfRange);
}

TEST(FixedVector, ResizeTruncatePopAndClear) {
  FixedVector<int, 4> v;
  EXPECT_EQ(v.pop_back().code(), StatusCode::kEmpty);
  ASSERT_TRUE(v.resize(3).is_ok());
  EXPECT_EQ(v.size(), 3u);
  EXPECT_EQ(v[2], 0);
  EXPECT_EQ(v.resize(5).code(), StatusCode::kCapacityExceeded);
  EXPECT_EQ(v.size(), 3u);
  EXPECT_EQ(v.truncate(4).code(), StatusCode::kOutOfRange);
  ASSERT_TRUE(v.truncate(1).is_ok());
  ASSERT_TRUE(v.pop_back().is_ok());
  EXPECT_TRUE(v.empty());
  ASSERT_TRUE(v.push_back(9).is_ok());
  v.clear();
  EXPECT_TRUE(v.empty());
}

TEST(FixedVector, RangeForAndSpan) {
  FixedVector<int, 8> v;
  for (int i = 1; i <= 4; ++i) ASSERT_TRUE(v.push_back(i).is_ok());
  int sum = 0;
  for (int x : v) sum += x;
  EXPECT_EQ(sum, 10);
  Span<const int> s = static_cast<const FixedVector<int, 8>&>(v).span();
  EXPECT_EQ(s.size(), 4u);
  EXPECT_EQ(s.subspan(2, 100).size(), 2u);
  EXPECT_EQ(s.subspan(10, 1).size(), 0u);
  EXPECT_EQ(s.at(4), nullptr);
}

TEST(BoundedVector, CapacityComesFromCallerStorage) {
  int storage[2] = {-1, -1};
  int sentinel_after = 77;
  BoundedVector<int> v(Span<int>(storage, 2));
  EXPECT_EQ(v.capacity(), 2u);
  EXPECT_TRUE(v.push_back(5).is_ok());
  EXPECT_TRUE(v.push_back(6).is_ok());
  EXPECT_EQ(v.push_back(7).code(), StatusCode::kCapacityExceeded);
  EXPECT_EQ(storage[0], 5);
  EXPECT_EQ(storage[1], 6);
  EXPECT_EQ(sentinel_after, 77);
}

TEST(BoundedVector, DefaultHasNoCapacity) {
  BoundedVector<int> v;
  EXPECT_EQ(v.capacity(), 0u);
  EXPECT_EQ(v.push_back(1).code(), StatusCode::kCapacityExceeded);
}

}  // namespace
}  // namespace qnav
