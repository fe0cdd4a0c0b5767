#include "drivers/stereo_sim/mars_yard.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

namespace qnav::sim {
namespace {

double zncc_at(const Image<std::uint8_t>& a, int xa, const Image<std::uint8_t>& b, int xb, int y, int r) {
  double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
  const int n = (2 * r + 1) * (2 * r + 1);
  for (int dy = -r; dy <= r; ++dy)
    for (int dx = -r; dx <= r; ++dx) {
      const double va = a(xa + dx, y + dy), vb = b(xb + dx, y + dy);
      sa += va;
      sb += vb;
      saa += va * va;
      sbb += vb * vb;
      sab += va * vb;
    }
  const double cov = sab - sa * sb / n, vara = saa - sa * sa / n, varb = sbb - sb * sb / n;
  return cov / std::sqrt(vara * varb + 1e-12);
}

TEST(MarsYard, RenderedPairHasTextureAndTrueDisparities) {
  // Half the paper's resolution (subsample 8, 160x128) keeps this test fast under qemu; the texture
  // still resolves (finest albedo wavelength 8 mm vs ~6 mm pixel footprint).
  const MarsYardTerrain terrain;
  StereoBench bench;
  bench.subsample = 8;
  Result<Image<std::uint8_t>> l = Image<std::uint8_t>::allocate(bench.width(), bench.height());
  Result<Image<std::uint8_t>> r = Image<std::uint8_t>::allocate(bench.width(), bench.height());
  ASSERT_TRUE(l.is_ok() && r.is_ok());
  const Pose3 cam = bench.rover_T_left();
  ASSERT_TRUE(render_stereo(terrain, bench, cam, 1, l->view(), r->view()).is_ok());
  double s = 0, s2 = 0;
  for (int y = 0; y < bench.height(); ++y)
    for (int x = 0; x < bench.width(); ++x) {
      s += (*l)(x, y);
      s2 += double((*l)(x, y)) * (*l)(x, y);
    }
  const double n = bench.width() * bench.height();
  const double stddev = std::sqrt(s2 / n - (s / n) * (s / n));
  EXPECT_GT(stddev, 12.0);
  EXPECT_GT(s / n, 60.0);
  EXPECT_LT(s / n, 200.0);
  // At the true disparity d = f b / Z the right patch matches; 3 px off it does not.
  int good = 0, total = 0;
  for (int y = 15; y < 115; y += 20) {
    for (int x = 30; x < 150; x += 20) {
      Vec3d p;
      ASSERT_TRUE(cast_ray(terrain, bench, cam, x, y, p));
      const double z = cam.inverse().apply(p).z();
      const int d = static_cast<int>(std::lround(bench.focal_px() * bench.baseline_m / z));
      const double at = zncc_at(*l, x, *r, x - d, y, 3);
      const double off = zncc_at(*l, x, *r, x - d - 2, y, 3);
      ++total;
      if (at > 0.8 && at > off + 0.2) ++good;
    }
  }
  EXPECT_GE(good, total * 8 / 10);
  // Deterministic, and the sensor noise depends on the frame seed (a 40x32 bench: cheap).
  bench.subsample = 32;
  ASSERT_TRUE(render_stereo(terrain, bench, cam, 1, l->view().sub({0, 0, 40, 32}).value(),
                            r->view().sub({0, 0, 40, 32}).value()).is_ok());
  Result<Image<std::uint8_t>> l2 = Image<std::uint8_t>::allocate(bench.width(), bench.height());
  Result<Image<std::uint8_t>> r2 = Image<std::uint8_t>::allocate(bench.width(), bench.height());
  ASSERT_TRUE(render_stereo(terrain, bench, cam, 1, l2->view(), r2->view()).is_ok());
  auto same = [&](const Image<std::uint8_t>& b) {
    for (int y = 0; y < 32; ++y)
      if (std::memcmp(l->view().row(y), b.view().row(y), 40) != 0) return false;
    return true;
  };
  EXPECT_TRUE(same(*l2));
  ASSERT_TRUE(render_stereo(terrain, bench, cam, 2, l2->view(), r2->view()).is_ok());
  EXPECT_FALSE(same(*l2));
  Result<Image<std::uint8_t>> small = Image<std::uint8_t>::allocate(10, 10);
  EXPECT_FALSE(render_stereo(terrain, bench, cam, 1, small->view(), r2->view()).is_ok());
}

}  // namespace
}  // namespace qnav::sim
