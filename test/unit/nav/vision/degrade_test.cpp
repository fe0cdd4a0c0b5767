#include "nav/vision/degrade.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "test/support/alloc_guard.hpp"
#include "test_images.hpp"

namespace qnav::vision {
namespace {

std::uint64_t fnv1a(const std::vector<std::uint8_t>& v) {
  std::uint64_t h = 1469598103934665603ull;
  for (std::uint8_t b : v) h = (h ^ b) * 1099511628211ull;
  return h;
}

TEST(Degrade, SameSeedSameOutputDifferentSeedDifferentOutput) {
  // Integer-only input (no libm), so the hash below depends on degrade_underwater alone.
  std::vector<std::uint8_t> src(160 * 120), a(src.size()), b(src.size()), c(src.size());
  for (std::size_t i = 0; i < src.size(); ++i) src[i] = static_cast<std::uint8_t>((i * 7 + (i / 160) * 13) % 256);
  const ConstImageViewU8 s = ConstImageViewU8::make(src.data(), 160, 120).value();
  UnderwaterDegradation p = table1_filter(4);
  Status st;
  QNAV_EXPECT_NO_ALLOC(st = degrade_underwater(s, p, ImageViewU8::make(a.data(), 160, 120).value()));
  ASSERT_TRUE(st.is_ok());
  ASSERT_TRUE(degrade_underwater(s, p, ImageViewU8::make(b.data(), 160, 120).value()).is_ok());
  EXPECT_EQ(a, b);
  p.seed = 99;
  ASSERT_TRUE(degrade_underwater(s, p, ImageViewU8::make(c.data(), 160, 120).value()).is_ok());
  EXPECT_NE(a, c);
  // Bit-identical on every target (integer PRNG, IEEE-exact arithmetic): this hash was produced on
  // the x86-64 host and must be reproduced under qemu on aarch64, armhf and big-endian LEON3.
  EXPECT_EQ(fnv1a(a), 0x690eb416418080b5ull) << "hash 0x" << std::hex << fnv1a(a);
}

TEST(Degrade, EachTermDoesWhatTable1Says) {
  const int W = 200, H = 100;
  std::vector<std::uint8_t> src(W * H, 128), out(src.size());
  const ConstImageViewU8 s = ConstImageViewU8::make(src.data(), W, H).value();
  const ImageViewU8 o = ImageViewU8::make(out.data(), W, H).value();
  // Noise only (light far away, no attenuation, no lift, no snow): sample sigma ~ 4.
  UnderwaterDegradation p;
  p.light_distance_m = 1000.0;
  p.attenuation = 0.0;
  p.min_grey = 0;
  p.snow_flakes = 0;
  p.noise_sigma = 4.0;
  ASSERT_TRUE(degrade_underwater(s, p, o).is_ok());
  double sum = 0, ss = 0;
  for (std::uint8_t v : out) sum += v, ss += static_cast<double>(v) * v;
  const double mean = sum / out.size(), sd = std::sqrt(ss / out.size() - mean * mean);
  EXPECT_NEAR(mean, 128.0, 0.2);
  EXPECT_NEAR(sd, std::sqrt(16.0 + 1.0 / 12.0), 0.15);  // + rounding to integers
  // Light fall-off: centre unchanged, corner darker by (d0 / d)^2.
  p = UnderwaterDegradation{};
  p.attenuation = 0.0;
  p.noise_sigma = 0.0;
  p.min_grey = 0;
  p.snow_flakes = 0;
  p.light_distance_m = 0.25;
  p.scene_width_m = 0.5;
  ASSERT_TRUE(degrade_underwater(s, p, o).is_ok());
  EXPECT_NEAR(o(W / 2, H / 2), 128, 1);
  const double rx = (0 - 0.5 * (W - 1)) * 0.5 / W, ry = (0 - 0.5 * (H - 1)) * 0.5 / W;
  EXPECT_NEAR(o(0, 0), 128.0 * 0.0625 / (0.0625 + rx * rx + ry * ry), 1.0);
  // Attenuation blends towards the back-scatter grey; minimum grey lifts black.
  std::vector<std::uint8_t> black(W * H, 0);
  p = UnderwaterDegradation{};
  p.light_distance_m = 1000.0;
  p.noise_sigma = 0.0;
  p.snow_flakes = 0;
  p.attenuation = 0.06;
  p.backscatter_grey = 100.0;
  p.min_grey = 30;
  ASSERT_TRUE(degrade_underwater(ConstImageViewU8::make(black.data(), W, H).value(), p, o).is_ok());
  EXPECT_EQ(o(W / 2, H / 2), static_cast<int>(std::lround(30 + 6.0 * 225.0 / 255.0)));
  // Marine snow: bright flakes on a dark image.
  p.attenuation = 0.0;
  p.min_grey = 0;
  p.snow_flakes = 30;
  ASSERT_TRUE(degrade_underwater(ConstImageViewU8::make(black.data(), W, H).value(), p, o).is_ok());
  int bright = 0;
  for (std::uint8_t v : out) bright += v >= 200 ? 1 : 0;
  EXPECT_GE(bright, 30 * 5 - 40);   // each flake covers >= 5 px (radius 1), minus overlaps/borders
  EXPECT_LE(bright, 30 * 29);       // and at most 29 px (radius 3)
}

TEST(Degrade, InPlaceAndBadParameters) {
  std::vector<std::uint8_t> img(64 * 48, 100);
  ImageViewU8 v = ImageViewU8::make(img.data(), 64, 48).value();
  EXPECT_TRUE(degrade_underwater(v, table1_filter(1), v).is_ok());
  for (std::uint8_t x : img) EXPECT_GE(x, 20);  // filter 1: minimum grey 20
  UnderwaterDegradation p;
  p.noise_sigma = std::nan("");
  EXPECT_EQ(degrade_underwater(v, p, v), StatusCode::kInvalidArgument);
  p = UnderwaterDegradation{};
  p.light_distance_m = 0.0;
  EXPECT_EQ(degrade_underwater(v, p, v), StatusCode::kInvalidArgument);
  p = UnderwaterDegradation{};
  p.min_grey = 300;
  EXPECT_EQ(degrade_underwater(v, p, v), StatusCode::kInvalidArgument);
  std::vector<std::uint8_t> other(10 * 10);
  EXPECT_EQ(degrade_underwater(v, UnderwaterDegradation{}, ImageViewU8::make(other.data(), 10, 10).value()),
            StatusCode::kInvalidArgument);
  EXPECT_EQ(degrade_underwater(ConstImageViewU8(), UnderwaterDegradation{}, v), StatusCode::kInvalidArgument);
  EXPECT_EQ(table1_filter(2).min_grey, 30);
  EXPECT_DOUBLE_EQ(table1_filter(5).light_distance_m, 0.3);
  EXPECT_DOUBLE_EQ(table1_filter(4).noise_sigma, 4.0);
}

}  // namespace
}  // namespace qnav::vision
