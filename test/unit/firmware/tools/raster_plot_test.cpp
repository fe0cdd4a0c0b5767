#include "firmware/tools/raster_plot.hpp"

#include <gtest/gtest.h>
#include <png.h>

#include <cstdio>
#include <string>
#include <vector>

namespace qnav::tools {
namespace {

struct Rgb {
  std::vector<std::uint8_t> px;
  int w = 0, h = 0;
  int at(int x, int y, int k) const { return px[(static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x)) * 3 + static_cast<std::size_t>(k)]; }
};

Rgb read_rgb(const std::string& path) {
  Rgb r;
  png_image img{};
  img.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&img, path.c_str())) return r;
  img.format = PNG_FORMAT_RGB;
  r.px.resize(PNG_IMAGE_SIZE(img));
  if (!png_image_finish_read(&img, nullptr, r.px.data(), 0, nullptr)) return Rgb{};
  r.w = static_cast<int>(img.width);
  r.h = static_cast<int>(img.height);
  return r;
}

// Where the image's top-left pixel landed in the canvas, by matching its whole first row; -1 if nowhere.
bool find_image(const Rgb& c, const std::vector<std::uint8_t>& img, int iw, int& ox, int& oy) {
  for (int y = 0; y < c.h; ++y)
    for (int x = 0; x + iw <= c.w; ++x) {
      bool ok = true;
      for (int i = 0; i < iw && ok; ++i)
        ok = c.at(x + i, y, 0) == img[static_cast<std::size_t>(i)] && c.at(x + i, y, 1) == img[static_cast<std::size_t>(i)];
      if (ok) {
        ox = x;
        oy = y;
        return true;
      }
    }
  return false;
}

int dark_pixels(const Rgb& c, int x0, int y0, int x1, int y1) {
  int n = 0;
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) n += c.at(x, y, 0) < 128;
  return n;
}

TEST(RasterPlot, NiceStepsAndTickLabels) {
  EXPECT_DOUBLE_EQ(nice_step(102.4, 5), 20.0);
  EXPECT_DOUBLE_EQ(nice_step(2.5, 5), 0.5);
  EXPECT_DOUBLE_EQ(nice_step(80.0, 8), 10.0);
  EXPECT_NEAR(nice_step(0.03, 3), 0.01, 1e-12);
  EXPECT_EQ(tick_label(1500.0, 500.0), "1500");
  EXPECT_EQ(tick_label(2.5, 0.5), "2.5");
  EXPECT_EQ(tick_label(-1e-12, 0.1), "0.0");  // no "-0.0"
  EXPECT_EQ(tick_label(-40.0, 10.0), "-40");
  EXPECT_EQ(tick_label(0.02, 0.01), "0.02");
}

// The data are copied pixel for pixel (grey, R = G = B); the ticks' labels sit left of and under the
// image, never on it; a scale bar, north arrow and colour bar add room rather than covering data.
TEST(RasterPlot, DataIntactAxesOutsideIt) {
  const int w = 160, h = 120;
  std::vector<std::uint8_t> img(static_cast<std::size_t>(w * h));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) img[static_cast<std::size_t>(y * w + x)] = static_cast<std::uint8_t>((x * 7 + y * 3) % 251);
  const ConstImageViewU8 view = ConstImageViewU8::unchecked(img.data(), w, h, w);
  RasterPlot p;
  p.title = "test tile";
  p.x = {1000.05, 0.1, "east m"};
  p.y = {511.95, -0.1, "north m"};
  const std::string bare = ::testing::TempDir() + "qnav_plot_bare.png";
  ASSERT_TRUE(write_raster_plot_png(bare.c_str(), view, p).is_ok());
  const Rgb a = read_rgb(bare);
  ASSERT_GT(a.w, w);
  ASSERT_GT(a.h, h);
  int ox = -1, oy = -1;
  ASSERT_TRUE(find_image(a, img, w, ox, oy));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const int v = img[static_cast<std::size_t>(y * w + x)];
      ASSERT_EQ(a.at(ox + x, oy + y, 0), v) << x << "," << y;
      ASSERT_EQ(a.at(ox + x, oy + y, 2), v) << x << "," << y;
    }
  EXPECT_GT(dark_pixels(a, 0, oy, ox - 1, oy + h), 20);       // y tick labels and the axis label
  EXPECT_GT(dark_pixels(a, ox, oy + h + 1, ox + w, a.h), 20);  // x tick labels and the axis label
  EXPECT_GT(dark_pixels(a, 0, 0, a.w, oy - 1), 20);            // the title

  p.scale_bar = p.north_arrow = p.colour_bar = true;
  p.colour_hi = 2.5;
  p.colour_label = "intensity";
  const std::string full = ::testing::TempDir() + "qnav_plot_full.png";
  ASSERT_TRUE(write_raster_plot_png(full.c_str(), view, p).is_ok());
  const Rgb b = read_rgb(full);
  EXPECT_GT(b.w, a.w);  // the arrow and the colour bar to the right
  EXPECT_GT(b.h, a.h);  // the scale bar underneath
  int bx = -1, by = -1;
  ASSERT_TRUE(find_image(b, img, w, bx, by));
  EXPECT_EQ(by, oy);
  EXPECT_GT(dark_pixels(b, bx + w + 2, by, b.w, by + h), 100);  // arrow, bar, its ticks
  std::remove(bare.c_str());
  std::remove(full.c_str());
}

// The disparity colours of `qnav stereo disparity` (blue far .. red near) and its colour bar come
// from one function; an RGB image is copied as it is.
TEST(RasterPlot, ColourMapAndRgbImage) {
  std::uint8_t c[3];
  plot_colour(PlotColourMap::kBlueGreenRed, 0.0, c);
  EXPECT_EQ(c[0], 0);
  EXPECT_EQ(c[1], 0);
  EXPECT_EQ(c[2], 255);
  plot_colour(PlotColourMap::kBlueGreenRed, 1.0, c);
  EXPECT_EQ(c[0], 255);
  EXPECT_EQ(c[2], 0);
  plot_colour(PlotColourMap::kBlueGreenRed, 0.5, c);
  EXPECT_EQ(c[1], 255);
  plot_colour(PlotColourMap::kGrey, 2.0, c);  // clamped
  EXPECT_EQ(c[0], 255);
  const int w = 90, h = 40;
  std::vector<std::uint8_t> rgb(static_cast<std::size_t>(w * h * 3));
  for (std::size_t i = 0; i < rgb.size(); ++i) rgb[i] = static_cast<std::uint8_t>((i * 7) % 251);
  RasterPlot p;
  p.x = {0.0, 1.0, "column px"};
  p.y = {0.0, 1.0, "row px"};
  p.colour_bar = true;
  p.colour_hi = 100.0;
  p.colour_map = PlotColourMap::kBlueGreenRed;
  const std::string path = ::testing::TempDir() + "qnav_plot_rgb.png";
  ASSERT_TRUE(write_raster_plot_png_rgb(path.c_str(), rgb.data(), w, h, w * 3, p).is_ok());
  const Rgb b = read_rgb(path);
  bool found = false;
  for (int y = 0; y < b.h && !found; ++y)
    for (int x = 0; x + w <= b.w && !found; ++x) {
      bool all = true;
      for (int r = 0; r < h && all; ++r)
        for (int k = 0; k < w * 3 && all; ++k)
          all = y + r < b.h && b.at(x + k / 3, y + r, k % 3) == rgb[static_cast<std::size_t>(r * w * 3 + k)];
      found = all;
    }
  EXPECT_TRUE(found);
  EXPECT_EQ(write_raster_plot_png_rgb(path.c_str(), rgb.data(), w, h, w, p).code(), StatusCode::kInvalidArgument);
  std::remove(path.c_str());
}

TEST(RasterPlot, EmptyImageIsAnError) {
  RasterPlot p;
  EXPECT_EQ(write_raster_plot_png("/tmp/never.png", ConstImageViewU8(), p).code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace qnav::tools
