#include "nav/core/arena.hpp"

#include <gtest/gtest.h>

#include <cstdint>

#include "test/support/alloc_guard.hpp"

namespace qnav {
namespace {

TEST(Arena, AllocationsAreAlignedAndDisjoint) {
  alignas(64) std::byte block[256];
  Arena a(Span<std::byte>(block, sizeof block));
  Span<std::uint8_t> bytes = a.allocate<std::uint8_t>(3);
  Span<double> doubles = a.allocate<double>(4);
  ASSERT_EQ(bytes.size(), 3u);
  ASSERT_EQ(doubles.size(), 4u);
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(doubles.data()) % alignof(double), 0u);
  EXPECT_GE(reinterpret_cast<const std::byte*>(doubles.data()), reinterpret_cast<const std::byte*>(bytes.end()));
  for (double d : doubles) EXPECT_EQ(d, 0.0);  // default-initialised
  EXPECT_EQ(a.used(), 8u + 32u);               // 3 bytes, 5 bytes of padding, 32 bytes of doubles
}

TEST(Arena, RequestThatDoesNotFitFailsAndIsCounted) {
  alignas(16) std::byte block[64];
  Arena a(Span<std::byte>(block, sizeof block));
  ASSERT_EQ(a.allocate<std::uint32_t>(10).size(), 10u);  // 40 bytes
  EXPECT_TRUE(a.allocate<std::uint32_t>(7).empty());     // 28 > 24 remaining
  EXPECT_EQ(a.failed_requests(), 1u);
  EXPECT_EQ(a.used(), 40u);                            // a failed request consumes nothing
  EXPECT_EQ(a.allocate<std::uint32_t>(6).size(), 6u);  // exactly fills the block
  EXPECT_EQ(a.remaining(), 0u);
  EXPECT_EQ(a.allocate_bytes(1, 1), nullptr);
}

TEST(Arena, HugeCountsDoNotOverflowSizeArithmetic) {
  alignas(16) std::byte block[64];
  Arena a(Span<std::byte>(block, sizeof block));
  EXPECT_TRUE(a.allocate<std::uint64_t>(static_cast<std::size_t>(-1) / 4).empty());
  EXPECT_EQ(a.allocate_bytes(16, 3), nullptr);  // alignment not a power of two
  EXPECT_EQ(a.failed_requests(), 2u);
  EXPECT_EQ(a.used(), 0u);
}

TEST(Arena, ResetReusesMemoryAndKeepsHighWater) {
  alignas(16) std::byte block[128];
  Arena a(Span<std::byte>(block, sizeof block));
  ASSERT_FALSE(a.allocate<std::uint8_t>(100).empty());
  a.reset();
  EXPECT_EQ(a.used(), 0u);
  EXPECT_EQ(a.high_water(), 100u);
  EXPECT_EQ(a.allocate<std::uint8_t>(120).size(), 120u);
  EXPECT_EQ(a.high_water(), 120u);
}

TEST(ArenaStorage, AllocatesOnceAtConstructionAndNeverAfter) {
  test::AllocationGuard construction;
  ArenaStorage storage(1 << 16);
  ASSERT_TRUE(storage.valid());
  EXPECT_EQ(construction.allocations(), 1u);
  QNAV_EXPECT_NO_ALLOC({
    for (int i = 0; i < 100; ++i) ASSERT_FALSE(storage.allocate<float>(100).empty());
  });
  EXPECT_EQ(storage.used(), 100u * 100u * sizeof(float));
}

}  // namespace
}  // namespace qnav
