#include "nav/vision/downsample.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "test/support/alloc_guard.hpp"

namespace qnav::vision {
namespace {

TEST(Downsample, Factor2AveragesBlocksWithRounding) {
  std::uint8_t src[4 * 2] = {0, 1, 10, 20, 2, 2, 30, 41};
  std::uint8_t dst[2] = {};
  ASSERT_TRUE(downsample(ConstImageViewU8::make(src, 4, 2).value(), 2, ImageViewU8::make(dst, 2, 1).value()).is_ok());
  EXPECT_EQ(dst[0], 1);   // 5/4 = 1.25 -> 1
  EXPECT_EQ(dst[1], 25);  // 101/4 = 25.25 -> 25
}

TEST(Downsample, Factor4OfARampAndOddSizesDropTheRemainder) {
  const int W = 18, H = 9;  // -> 4 x 2, last 2 columns and last row ignored
  std::vector<std::uint8_t> src(W * H);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) src[y * W + x] = static_cast<std::uint8_t>(4 * x + y);
  std::uint8_t dst[8] = {};
  ASSERT_TRUE(downsample(ConstImageViewU8::make(src.data(), W, H).value(), 4, ImageViewU8::make(dst, 4, 2).value()).is_ok());
  for (int oy = 0; oy < 2; ++oy)
    for (int ox = 0; ox < 4; ++ox) {
      // mean of 4x+y over the block: 4*(4ox+1.5) + (4oy+1.5) -> exact .5 rounds up
      const double mean = 4.0 * (4 * ox + 1.5) + (4 * oy + 1.5);
      EXPECT_EQ(dst[oy * 4 + ox], static_cast<int>(mean + 0.5)) << ox << "," << oy;
    }
}

TEST(Downsample, EveryFactorMatchesTheBlockMean) {
  const int W = 1100, H = 37;  // wider than one 1024-column chunk
  std::vector<std::uint8_t> src(W * H);
  for (std::size_t i = 0; i < src.size(); ++i) src[i] = static_cast<std::uint8_t>((i * 2654435761u) >> 24);
  for (int f = 1; f <= 16; ++f) {
    const int ow = W / f, oh = H / f;
    if (oh == 0) break;
    std::vector<std::uint8_t> dst(static_cast<std::size_t>(ow * oh));
    ASSERT_TRUE(downsample(ConstImageViewU8::make(src.data(), W, H).value(), f, ImageViewU8::make(dst.data(), ow, oh).value()).is_ok());
    for (int y = 0; y < oh; ++y)
      for (int x = 0; x < ow; ++x) {
        unsigned s = 0;
        for (int j = 0; j < f; ++j)
          for (int i = 0; i < f; ++i) s += src[static_cast<std::size_t>((y * f + j) * W + x * f + i)];
        ASSERT_EQ(dst[static_cast<std::size_t>(y * ow + x)], (s + static_cast<unsigned>(f * f / 2)) / static_cast<unsigned>(f * f))
            << "factor " << f << " at " << x << "," << y;
      }
  }
}

TEST(Downsample, StridedViewsAndFloat) {
  std::vector<float> src(10 * 4, 0.0f);
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 6; ++x) src[y * 10 + x] = static_cast<float>(x + 10 * y);
  std::vector<float> dst(3 * 2, -1.0f);
  ASSERT_TRUE(downsample(ConstImageViewF32::make(src.data(), 6, 4, 10).value(), 2,
                         ImageViewF32::make(dst.data(), 3, 2).value())
                  .is_ok());
  EXPECT_FLOAT_EQ(dst[0], 5.5f);
  EXPECT_FLOAT_EQ(dst[5], 4.5f + 25.0f);  // block x 4..5, y 2..3
}

TEST(Downsample, RejectsBadSizesAndFactors) {
  std::uint8_t src[16] = {}, dst[4] = {};
  const ConstImageViewU8 s = ConstImageViewU8::make(src, 4, 4).value();
  EXPECT_EQ(downsample(s, 2, ImageViewU8::make(dst, 1, 4).value()), StatusCode::kInvalidArgument);
  EXPECT_EQ(downsample(s, 0, ImageViewU8::make(dst, 2, 2).value()), StatusCode::kInvalidArgument);
  EXPECT_EQ(downsample(s, 17, ImageViewU8::make(dst, 2, 2).value()), StatusCode::kInvalidArgument);
  EXPECT_EQ(downsample(s, 8, ImageViewU8::make(dst, 1, 1).value()), StatusCode::kInvalidArgument);
  EXPECT_EQ(downsample(ConstImageViewU8(), 2, ImageViewU8::make(dst, 2, 2).value()), StatusCode::kInvalidArgument);
}

TEST(Pyramid, LevelsHaveHalvedSizesAndAreBuiltWithoutAllocation) {
  PyramidConfig c;
  c.max_width = 100;
  c.max_height = 70;
  c.levels = 5;
  ArenaStorage arena(100 * 70 * 2);
  ImagePyramid p;
  EXPECT_EQ(p.build(ConstImageViewU8()), StatusCode::kNotReady);
  ASSERT_TRUE(p.init(c, arena).is_ok());
  std::vector<std::uint8_t> img(99 * 70);
  for (std::size_t i = 0; i < img.size(); ++i) img[i] = static_cast<std::uint8_t>((i * 7) % 256);
  Status s;
  QNAV_EXPECT_NO_ALLOC(s = p.build(ConstImageViewU8::make(img.data(), 99, 70).value()));
  ASSERT_TRUE(s.is_ok());
  ASSERT_EQ(p.levels_built(), 4);  // 99x70, 49x35, 24x17, 12x8; 6x4 is too small
  EXPECT_EQ(p.level(1).width(), 49);
  EXPECT_EQ(p.level(1).height(), 35);
  EXPECT_EQ(p.level(3).width(), 12);
  EXPECT_EQ(p.level(3).height(), 8);
  EXPECT_TRUE(p.level(4).empty());
  EXPECT_EQ(p.level(0)(5, 3), img[3 * 99 + 5]);
  const int m = (img[0] + img[1] + img[99] + img[100] + 2) / 4;
  EXPECT_EQ(p.level(1)(0, 0), m);
  std::vector<std::uint8_t> big(101 * 70);
  EXPECT_EQ(p.build(ConstImageViewU8::make(big.data(), 101, 70).value()), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace qnav::vision
