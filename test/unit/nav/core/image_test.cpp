#include "nav/core/image.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <type_traits>

#include "test/support/alloc_guard.hpp"

namespace qnav {
namespace {

// A view converts to the read-only view of the same pixel type and to nothing else.
static_assert(std::is_convertible<ImageViewU8, ConstImageViewU8>::value, "u8 -> const u8");
static_assert(std::is_convertible<ImageViewF32, ConstImageViewF32>::value, "f32 -> const f32");
static_assert(!std::is_convertible<ImageViewU8, ConstImageViewF32>::value, "u8 must not reinterpret as float");
static_assert(!std::is_convertible<ImageViewF32, ConstImageViewU8>::value, "float must not reinterpret as u8");
static_assert(!std::is_convertible<ConstImageViewU8, ImageViewU8>::value, "const must not become mutable");

TEST(ImageView, MakeRejectsBadGeometry) {
  std::uint8_t px[16] = {};
  EXPECT_EQ(ImageViewU8::make(nullptr, 4, 4).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(ImageViewU8::make(px, 0, 4).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(ImageViewU8::make(px, 4, -1).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(ImageViewU8::make(px, 4, 4, 3).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(ImageViewU8::make(px, kMaxImageSide + 1, 1).status().code(), StatusCode::kInvalidArgument);
  EXPECT_TRUE(ImageViewU8::make(px, 4, 4).is_ok());
}

TEST(ImageView, StrideAddressesRowsAndSubViewsClip) {
  // 3x2 image stored with stride 4 (one padding byte per row).
  std::uint8_t px[8] = {1, 2, 3, 0xEE, 4, 5, 6, 0xEE};
  auto r = ImageViewU8::make(px, 3, 2, 4);
  ASSERT_TRUE(r.is_ok());
  ImageViewU8 v = *r;
  EXPECT_EQ(v(2, 1), 6);
  EXPECT_EQ(v.at(3, 0), nullptr);
  EXPECT_EQ(v.at(-1, 0), nullptr);
  ASSERT_NE(v.at(0, 1), nullptr);
  auto sub = v.sub(RectI{1, 1, 10, 10});
  ASSERT_TRUE(sub.is_ok());
  EXPECT_EQ(sub->width(), 2);
  EXPECT_EQ(sub->height(), 1);
  EXPECT_EQ((*sub)(0, 0), 5);
  EXPECT_EQ(v.sub(RectI{5, 5, 2, 2}).status().code(), StatusCode::kOutOfRange);
  ConstImageViewU8 cv = v;
  EXPECT_EQ(cv(0, 0), 1);
}

TEST(Image, HeapAllocationHappensOnceAndPixelsAreZero) {
  test::AllocationGuard g;
  auto img = ImageF32::allocate(32, 16);
  ASSERT_TRUE(img.is_ok());
  EXPECT_EQ(g.allocations(), 1u);
  EXPECT_EQ(img->width(), 32);
  EXPECT_EQ(img->view().stride(), 32);
  EXPECT_EQ((*img)(31, 15), 0.0f);
  EXPECT_EQ(ImageF32::allocate(0, 16).status().code(), StatusCode::kInvalidArgument);
}

TEST(Image, ArenaBackedImageNeverTouchesTheHeap) {
  alignas(16) std::byte block[1024];
  Arena arena(Span<std::byte>(block, sizeof block));
  test::AllocationGuard g;
  auto a = ImageU8::allocate(arena, 20, 20);  // 400 bytes
  ASSERT_TRUE(a.is_ok());
  auto b = ImageU8::allocate(arena, 30, 30);  // 900 bytes: does not fit in the 624 left
  EXPECT_EQ(b.status().code(), StatusCode::kCapacityExceeded);
  EXPECT_EQ(g.allocations(), 0u) << g.report();
}

TEST(Image, CopyPixelsChecksSizes) {
  auto a = ImageU8::allocate(4, 3);
  auto b = ImageU8::allocate(4, 3);
  auto c = ImageU8::allocate(3, 4);
  ASSERT_TRUE(a && b && c);
  (*a)(3, 2) = 200;
  ASSERT_TRUE(copy_pixels<std::uint8_t>(a->view(), b->view()).is_ok());
  EXPECT_EQ((*b)(3, 2), 200);
  EXPECT_EQ(copy_pixels<std::uint8_t>(a->view(), c->view()).code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace qnav
