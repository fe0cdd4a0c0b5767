#include "firmware/tools/png_writer.hpp"

#include <gtest/gtest.h>
#include <png.h>

#include <cstdio>
#include <string>
#include <vector>

namespace qnav::tools {
namespace {

std::string temp_path(const char* name) { return ::testing::TempDir() + name; }

// Reads back with libpng's simplified API so the test does not trust the writer's own code.
std::vector<std::uint8_t> read_gray(const std::string& path, int& w, int& h) {
  png_image img{};
  img.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&img, path.c_str())) return {};
  img.format = PNG_FORMAT_GRAY;
  std::vector<std::uint8_t> px(PNG_IMAGE_SIZE(img));
  if (!png_image_finish_read(&img, nullptr, px.data(), 0, nullptr)) return {};
  w = static_cast<int>(img.width);
  h = static_cast<int>(img.height);
  return px;
}

TEST(PngWriter, Gray8RoundTripsExactly) {
  std::vector<std::uint8_t> px(37 * 11);
  for (std::size_t i = 0; i < px.size(); ++i) px[i] = static_cast<std::uint8_t>(i * 13);
  auto view = ConstImageViewU8::make(px.data(), 37, 11);
  ASSERT_TRUE(view.is_ok());
  const std::string path = temp_path("qnav_gray.png");
  ASSERT_TRUE(write_png_gray8(path.c_str(), *view).is_ok());
  int w = 0, h = 0;
  EXPECT_EQ(read_gray(path, w, h), px);
  EXPECT_EQ(w, 37);
  EXPECT_EQ(h, 11);
  std::remove(path.c_str());
}

TEST(PngWriter, FloatIsScaledAndClampedNanIsBlack) {
  float px[4] = {-1.0f, 0.5f, 2.0f, std::nanf("")};
  auto view = ConstImageViewF32::make(px, 4, 1);
  ASSERT_TRUE(view.is_ok());
  const std::string path = temp_path("qnav_float.png");
  ASSERT_TRUE(write_png_float(path.c_str(), *view, 0.0f, 1.0f).is_ok());
  int w = 0, h = 0;
  const std::vector<std::uint8_t> got = read_gray(path, w, h);
  ASSERT_EQ(got.size(), 4u);
  EXPECT_EQ(got[0], 0);
  EXPECT_EQ(got[1], 128);
  EXPECT_EQ(got[2], 255);
  EXPECT_EQ(got[3], 0);
  EXPECT_EQ(write_png_float(path.c_str(), *view, 1.0f, 1.0f).code(), StatusCode::kInvalidArgument);
  std::remove(path.c_str());
}

TEST(PngWriter, UnwritablePathIsAnErrorNotACrash) {
  std::uint8_t px[4] = {};
  auto view = ConstImageViewU8::make(px, 2, 2);
  ASSERT_TRUE(view.is_ok());
  EXPECT_EQ(write_png_gray8("/nonexistent-dir/x.png", *view).code(), StatusCode::kIoError);
  EXPECT_EQ(write_png_rgb8("/tmp/x.png", nullptr, 2, 2, 6).code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace qnav::tools
