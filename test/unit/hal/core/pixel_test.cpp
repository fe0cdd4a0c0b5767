#include "hal/core/pixel.hpp"

#include <gtest/gtest.h>

#include <vector>

using namespace qnav;
using namespace qnav::hal;

TEST(PixelConvert, YuyvTakesLumaAndHonoursStride) {
  // 4x2 YUYV with 2 bytes of row padding: Y0 U Y1 V ...
  const int w = 4, h = 2, bpl = 10;
  std::vector<std::uint8_t> src(static_cast<std::size_t>(bpl * h), 0xEE);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      src[static_cast<std::size_t>(y * bpl + 2 * x)] = static_cast<std::uint8_t>(10 * y + x);
      src[static_cast<std::size_t>(y * bpl + 2 * x + 1)] = 128;
    }
  std::uint8_t out[8] = {};
  auto view = ImageView<std::uint8_t>::make(out, w, h).value();
  CameraFormat fmt{w, h, PixelFormat::kYuyv, bpl};
  ASSERT_TRUE(convert_to_gray(src.data(), src.size(), fmt, view).is_ok());
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) EXPECT_EQ(view(x, y), 10 * y + x);
}

TEST(PixelConvert, RejectsShortBufferAndSizeMismatch) {
  std::uint8_t src[15] = {};
  std::uint8_t out[16] = {};
  auto view = ImageView<std::uint8_t>::make(out, 4, 4).value();
  CameraFormat fmt{4, 4, PixelFormat::kGrey, 4};
  EXPECT_EQ(convert_to_gray(src, sizeof src, fmt, view), StatusCode::kInvalidArgument);
  CameraFormat other{4, 3, PixelFormat::kGrey, 4};
  EXPECT_EQ(convert_to_gray(src, sizeof src, other, view), StatusCode::kInvalidArgument);
  CameraFormat bad_stride{4, 4, PixelFormat::kYuyv, 6};
  EXPECT_EQ(convert_to_gray(src, sizeof src, bad_stride, view), StatusCode::kInvalidArgument);
}
