#include "nav/route/tile_features.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

namespace qnav::route {
namespace {

// The plane extract() finds corners on, computed the plain way (every pixel with its clamps and
// std::isfinite, as the extractor did before its loops were specialised): the reference the
// extractor's plane must equal bit for bit.
std::vector<float> reference_plane(const std::vector<float>& in, const std::vector<std::uint8_t>& cov, int W, int H, int f, int r) {
  const int w = W / f, h = H / f;
  std::vector<float> wk(static_cast<std::size_t>(w) * h), tp(wk.size());
  std::vector<std::uint8_t> cv(wk.size());
  const auto fine_covered = [&](int x, int y) {
    const std::size_t i = static_cast<std::size_t>(y) * W + x;
    return cov[i] != 0 && std::isfinite(in[i]);
  };
  double sum = 0.0;
  std::size_t n = 0;
  const int need = (f * f + 1) / 2;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      float s = 0.0f;
      int k = 0;
      for (int yy = y * f; yy < (y + 1) * f; ++yy)
        for (int xx = x * f; xx < (x + 1) * f; ++xx)
          if (fine_covered(xx, yy)) {
            s += in[static_cast<std::size_t>(yy) * W + xx];
            ++k;
          }
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      cv[i] = k >= need ? 1 : 0;
      wk[i] = k > 0 ? s / static_cast<float>(k) : 0.0f;
      if (k >= need) {
        sum += static_cast<double>(wk[i]);
        ++n;
      }
    }
  const float mean = static_cast<float>(sum / static_cast<double>(n));
  for (std::size_t i = 0; i < wk.size(); ++i)
    if (cv[i] == 0) wk[i] = mean;
  if (r == 0) return wk;
  const float inv = 1.0f / static_cast<float>(2 * r + 1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      float s = 0.0f;
      for (int k = -r; k <= r; ++k) {
        const int xx = x + k < 0 ? 0 : (x + k >= w ? w - 1 : x + k);
        s += wk[static_cast<std::size_t>(y) * w + xx];
      }
      tp[static_cast<std::size_t>(y) * w + x] = s * inv;
    }
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      float s = 0.0f;
      for (int k = -r; k <= r; ++k) {
        const int yy = y + k < 0 ? 0 : (y + k >= h ? h - 1 : y + k);
        s += tp[static_cast<std::size_t>(yy) * w + x];
      }
      wk[static_cast<std::size_t>(y) * w + x] = s * inv;
    }
  return wk;
}

// A speckled tile with a gap (the nadir), scattered holes, NaN and inf pixels, and a size that is no
// multiple of any factor tried.
struct Tile {
  int W = 0, H = 0;
  std::vector<float> intensity;
  std::vector<std::uint8_t> coverage;
};

Tile speckled_tile(int W, int H, unsigned seed) {
  Tile t;
  t.W = W;
  t.H = H;
  t.intensity.resize(static_cast<std::size_t>(W) * H);
  t.coverage.resize(t.intensity.size());
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> level(0.0f, 255.0f);
  std::uniform_int_distribution<int> pick(0, 99);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * W + x;
      t.intensity[i] = level(rng) * (1.0f + 0.5f * std::sin(0.3f * static_cast<float>(x)) * std::cos(0.2f * static_cast<float>(y)));
      const int p = pick(rng);
      if (p == 0) t.intensity[i] = std::numeric_limits<float>::quiet_NaN();
      if (p == 1) t.intensity[i] = std::numeric_limits<float>::infinity();
      const bool gap = x >= W / 2 - 6 && x < W / 2 + 5;
      t.coverage[i] = gap || p == 2 || p == 3 ? 0 : 1;
    }
  return t;
}

TEST(TileFeatures, ThePlaneEqualsThePlainBlockAverageAndBlurForEveryFactorAndRadius) {
  const Tile t = speckled_tile(203, 187, 7);
  for (int f = 1; f <= 5; ++f)
    for (int r : {0, 1, 2, 3, 8}) {
      TileFeatureConfig c;
      c.max_width = 256;
      c.max_height = 256;
      c.max_keypoints = 32;
      c.downsample = f;
      c.blur_radius_px = r;
      ArenaStorage arena(TileFeatureExtractor::arena_bytes(c));
      TileFeatureExtractor ex;
      ASSERT_TRUE(ex.init(c, arena).is_ok());
      RouteNode node;
      TileGeometry g;
      const Status st = ex.extract(ConstImageViewF32::unchecked(t.intensity.data(), t.W, t.H, t.W),
                                   ConstImageViewU8::unchecked(t.coverage.data(), t.W, t.H, t.W), g, node);
      ASSERT_TRUE(st.is_ok()) << "f " << f << " r " << r << ": " << st.message();
      const std::vector<float> ref = reference_plane(t.intensity, t.coverage, t.W, t.H, f, r);
      const ConstImageViewF32 plane = ex.plane();
      ASSERT_EQ(plane.width(), t.W / f);
      ASSERT_EQ(plane.height(), t.H / f);
      std::size_t differ = 0;
      for (int y = 0; y < plane.height(); ++y)
        differ += std::memcmp(plane.row(y), ref.data() + static_cast<std::size_t>(y) * plane.width(), sizeof(float) * plane.width()) != 0;
      EXPECT_EQ(differ, 0u) << "rows differing from the reference at downsample " << f << ", blur radius " << r;
    }
}

TEST(TileFeatures, ATileWithNoCoveredPixelIsEmptyAndLeavesNoPlane) {
  Tile t = speckled_tile(96, 96, 3);
  for (auto& c : t.coverage) c = 0;
  TileFeatureConfig c;
  c.max_width = c.max_height = 128;
  c.downsample = 3;
  ArenaStorage arena(TileFeatureExtractor::arena_bytes(c));
  TileFeatureExtractor ex;
  ASSERT_TRUE(ex.init(c, arena).is_ok());
  RouteNode node;
  const Status st = ex.extract(ConstImageViewF32::unchecked(t.intensity.data(), t.W, t.H, t.W),
                               ConstImageViewU8::unchecked(t.coverage.data(), t.W, t.H, t.W), TileGeometry{}, node);
  EXPECT_EQ(st.code(), StatusCode::kEmpty);
  EXPECT_EQ(ex.counters().get(FeatureCounter::kEmptyTile), 1u);
  EXPECT_TRUE(ex.plane().empty());
  EXPECT_TRUE(node.keypoints.empty());
}

}  // namespace
}  // namespace qnav::route
