#include "firmware/tools/image_reader.hpp"
#include "firmware/tools/shared_dir.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include "firmware/tools/png_writer.hpp"

namespace qnav::tools {
namespace {

std::string tmp(const char* name) { return ::testing::TempDir() + "/qnav_image_reader_" + name; }

void write_bytes(const std::string& path, const std::string& bytes) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  ASSERT_NE(f, nullptr);
  std::fwrite(bytes.data(), 1, bytes.size(), f);
  std::fclose(f);
}

TEST(ImageReader, GreyPngRoundTripsExactly) {
  std::vector<std::uint8_t> px(37 * 21);
  for (std::size_t i = 0; i < px.size(); ++i) px[i] = static_cast<std::uint8_t>((i * 13 + 7) % 256);
  const std::string p = tmp("grey.png");
  ASSERT_TRUE(write_png_gray8(p.c_str(), ConstImageViewU8::make(px.data(), 37, 21).value()).is_ok());
  Result<ImageU8> r = read_image_gray8(p.c_str());
  ASSERT_TRUE(r.is_ok()) << r.status().message();
  ASSERT_EQ(r->width(), 37);
  ASSERT_EQ(r->height(), 21);
  for (int y = 0; y < 21; ++y)
    for (int x = 0; x < 37; ++x) ASSERT_EQ((*r)(x, y), px[static_cast<std::size_t>(y * 37 + x)]);
}

TEST(ImageReader, RgbPngIsConvertedWithBt601Luma) {
  const std::uint8_t rgb[] = {255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255, 10, 200, 90, 0, 0, 0};
  const std::string p = tmp("rgb.png");
  ASSERT_TRUE(write_png_rgb8(p.c_str(), rgb, 6, 1, 18).is_ok());
  Result<ImageU8> r = read_png_gray8(p.c_str());
  ASSERT_TRUE(r.is_ok()) << r.status().message();
  EXPECT_EQ((*r)(0, 0), 76);   // 0.299 * 255
  EXPECT_EQ((*r)(1, 0), 150);  // 0.587 * 255
  EXPECT_EQ((*r)(2, 0), 29);   // 0.114 * 255
  EXPECT_EQ((*r)(3, 0), 255);
  EXPECT_EQ((*r)(4, 0), 131);  // 0.299*10 + 0.587*200 + 0.114*90 = 130.65, rounded
  EXPECT_EQ((*r)(5, 0), 0);
}

TEST(ImageReader, PgmRoundTripAndMaxvalScaling) {
  std::vector<std::uint8_t> px(5 * 3);
  for (std::size_t i = 0; i < px.size(); ++i) px[i] = static_cast<std::uint8_t>(i * 17);
  const std::string p = tmp("a.pgm");
  ASSERT_TRUE(write_pgm_gray8(p.c_str(), ConstImageViewU8::make(px.data(), 5, 3).value()).is_ok());
  Result<ImageU8> r = read_image_gray8(p.c_str());
  ASSERT_TRUE(r.is_ok()) << r.status().message();
  EXPECT_EQ((*r)(4, 2), px[14]);
  // maxval 100 with a comment in the header: 50 -> 127, 100 -> 255.
  write_bytes(tmp("b.pgm"), std::string("P5\n# comment\n2 1\n100\n") + char(50) + char(100));
  r = read_pgm_gray8(tmp("b.pgm").c_str());
  ASSERT_TRUE(r.is_ok()) << r.status().message();
  EXPECT_EQ((*r)(0, 0), 127);
  EXPECT_EQ((*r)(1, 0), 255);
}

TEST(ImageReader, BadFilesGiveClearErrors) {
  EXPECT_EQ(read_image_gray8(nullptr).status(), StatusCode::kInvalidArgument);
  EXPECT_EQ(read_image_gray8(tmp("does_not_exist.png").c_str()).status(), StatusCode::kIoError);
  write_bytes(tmp("empty"), "");
  EXPECT_EQ(read_image_gray8(tmp("empty").c_str()).status(), StatusCode::kTruncated);
  write_bytes(tmp("text.png"), "hello world, not an image");
  EXPECT_EQ(read_image_gray8(tmp("text.png").c_str()).status(), StatusCode::kUnsupported);
  write_bytes(tmp("bad.png"), std::string("\x89PNG\r\n\x1a\n", 8) + "garbage garbage garbage");
  EXPECT_EQ(read_image_gray8(tmp("bad.png").c_str()).status(), StatusCode::kCorrupt);
  write_bytes(tmp("bad.jpg"), std::string("\xff\xd8\xff\xe0", 4) + "garbage");
  EXPECT_EQ(read_image_gray8(tmp("bad.jpg").c_str()).status(), StatusCode::kCorrupt);
  write_bytes(tmp("short.pgm"), "P5\n4 4\n255\nabc");
  EXPECT_EQ(read_image_gray8(tmp("short.pgm").c_str()).status(), StatusCode::kTruncated);
  write_bytes(tmp("zero.pgm"), "P5\n0 4\n255\n");
  EXPECT_EQ(read_image_gray8(tmp("zero.pgm").c_str()).status(), StatusCode::kInvalidArgument);
  write_bytes(tmp("wide.pgm"), "P5\n99999 4\n255\n");
  EXPECT_EQ(read_image_gray8(tmp("wide.pgm").c_str()).status(), StatusCode::kInvalidArgument);
  write_bytes(tmp("deep.pgm"), "P5\n1 1\n65535\n\x01\x02");
  EXPECT_EQ(read_image_gray8(tmp("deep.pgm").c_str()).status(), StatusCode::kUnsupported);
  write_bytes(tmp("head.pgm"), "P5\nfour 4\n255\n");
  EXPECT_EQ(read_image_gray8(tmp("head.pgm").c_str()).status(), StatusCode::kCorrupt);
}

TEST(ImageReader, ReadsTheRealJpegAndPngSamples) {
  const std::string base = qnav::tools::shared_dir() + "/data/stereo/";
  Result<ImageU8> aloe = read_image_gray8((base + "middlebury_aloe_opencv/aloeL.jpg").c_str());
  if (!aloe.is_ok() && aloe.status() == StatusCode::kIoError) GTEST_SKIP() << "sample data missing: " << base;
  ASSERT_TRUE(aloe.is_ok()) << aloe.status().message();
  EXPECT_EQ(aloe->width(), 1282);
  EXPECT_EQ(aloe->height(), 1110);
  Result<ImageU8> gt = read_image_gray8((base + "middlebury_aloe_opencv/aloeGT.png").c_str());
  ASSERT_TRUE(gt.is_ok()) << gt.status().message();
  int maxv = 0;
  for (int y = 0; y < gt->height(); ++y)
    for (int x = 0; x < gt->width(); ++x) maxv = std::max(maxv, static_cast<int>((*gt)(x, y)));
  EXPECT_EQ(maxv, 211);  // README: aloeGT values 0..211
  Result<ImageU8> kitti = read_image_gray8((base + "kitti_raw_2011_09_26_0013_city100/left/0000000000.png").c_str());
  ASSERT_TRUE(kitti.is_ok()) << kitti.status().message();
  EXPECT_EQ(kitti->width(), 1242);
  EXPECT_EQ(kitti->height(), 375);
}

// Regression (issue #19): a JPEG cut short was decoded with its missing part grey and no error.
// Every cut of the real JPEG (and of the real PNG) is refused as corrupt or truncated.
TEST(ImageReader, TruncatedRealImagesAreRefusedNotGreyFilled) {
  const std::string base = qnav::tools::shared_dir() + "/data/stereo/";
  for (const char* name : {"middlebury_aloe_opencv/aloeL.jpg", "kitti_raw_2011_09_26_0013_city100/left/0000000000.png"}) {
    std::FILE* f = std::fopen((base + name).c_str(), "rb");
    if (f == nullptr) GTEST_SKIP() << "sample data missing: " << base;
    std::string bytes;
    char buf[65536];
    std::size_t n;
    while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) bytes.append(buf, n);
    std::fclose(f);
    for (double cut : {0.2, 0.5, 0.9, 0.999}) {
      const std::string path = tmp("cut");
      write_bytes(path, bytes.substr(0, static_cast<std::size_t>(static_cast<double>(bytes.size()) * cut)));
      const Result<ImageU8> r = read_image_gray8(path.c_str());
      ASSERT_FALSE(r.is_ok()) << name << " cut at " << cut;
      EXPECT_TRUE(r.status() == StatusCode::kCorrupt || r.status() == StatusCode::kTruncated) << r.status().message();
    }
  }
}

}  // namespace
}  // namespace qnav::tools
