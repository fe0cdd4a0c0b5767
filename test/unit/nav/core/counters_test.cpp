#include "nav/core/counters.hpp"

#include <gtest/gtest.h>

#include <cstdint>

namespace qnav {
namespace {

enum class TestCounter : std::uint8_t { kBadCrc, kTruncated, kCount };
constexpr const char* kNames[] = {"bad_crc", "truncated"};

TEST(CounterSet, CountsByNameAndSaturates) {
  CounterSet<TestCounter> c{kNames};
  EXPECT_EQ(c.size(), 2u);
  c.increment(TestCounter::kBadCrc);
  c.increment(TestCounter::kBadCrc, 4);
  EXPECT_EQ(c.get(TestCounter::kBadCrc), 5u);
  EXPECT_STREQ(c.name_at(1), "truncated");
  EXPECT_STREQ(c.name_at(2), "");
  EXPECT_EQ(c.count_at(2), 0u);
  c.increment(TestCounter::kTruncated, UINT32_MAX - 1);
  c.increment(TestCounter::kTruncated, 10);
  EXPECT_EQ(c.get(TestCounter::kTruncated), UINT32_MAX);
  EXPECT_EQ(c.total(), 5ull + UINT32_MAX);
  c.reset();
  EXPECT_EQ(c.total(), 0u);
}

}  // namespace
}  // namespace qnav
