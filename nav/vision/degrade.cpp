#include "nav/vision/degrade.hpp"

#include <cmath>

namespace qnav::vision {

namespace {

struct Prng {
  std::uint64_t s;
  explicit Prng(std::uint64_t seed) noexcept : s(seed * 0x9E3779B97F4A7C15ull + 0xD1B54A32D192ED03ull) {
    if (s == 0) s = 0x9E3779B97F4A7C15ull;
  }
  std::uint64_t next() noexcept {
    s ^= s >> 12;
    s ^= s << 25;
    s ^= s >> 27;
    return s * 2685821657736338717ull;
  }
  std::uint32_t u32() noexcept { return static_cast<std::uint32_t>(next() >> 32); }
  // Uniform integer in [0, n).
  std::uint32_t below(std::uint32_t n) noexcept { return static_cast<std::uint32_t>((static_cast<std::uint64_t>(u32()) * n) >> 32); }
  // Approximately standard normal: sum of 12 uniforms in [0, 1) minus 6 (variance exactly 1).
  double gauss() noexcept {
    std::uint64_t sum = 0;
    for (int i = 0; i < 12; ++i) sum += u32();
    return static_cast<double>(sum) * (1.0 / 4294967296.0) - 6.0;
  }
};

inline std::uint8_t clamp8(double v) noexcept {
  if (!(v > 0.0)) return 0;  // also NaN
  if (v >= 255.0) return 255;
  return static_cast<std::uint8_t>(v + 0.5);
}

}  // namespace

UnderwaterDegradation table1_filter(int index) noexcept {
  UnderwaterDegradation p;
  // Table 1 columns: light distance (m), attenuation, Gaussian sigma, minimum grey, flakes.
  static const double kTable[5][5] = {
      {0.20, 0.05, 2, 20, 30}, {0.22, 0.05, 2, 30, 30}, {0.25, 0.06, 2, 20, 30}, {0.25, 0.05, 4, 20, 30}, {0.30, 0.05, 4, 20, 30}};
  if (index < 1 || index > 5) return p;
  const double* r = kTable[index - 1];
  p.light_distance_m = r[0];
  p.attenuation = r[1];
  p.noise_sigma = r[2];
  p.min_grey = static_cast<int>(r[3]);
  p.snow_flakes = static_cast<int>(r[4]);
  p.seed = static_cast<std::uint64_t>(index);
  return p;
}

Status degrade_underwater(ConstImageViewU8 src, const UnderwaterDegradation& p, ImageViewU8 dst) noexcept {
  if (src.empty() || dst.empty() || src.width() != dst.width() || src.height() != dst.height())
    return Status(StatusCode::kInvalidArgument, "degrade: empty images or different sizes");
  if (!(p.light_distance_m > 0.0 && p.light_distance_m <= 1000.0) || !(p.scene_width_m > 0.0 && p.scene_width_m <= 1000.0) ||
      !(p.attenuation >= 0.0 && p.attenuation <= 1.0) || !(p.backscatter_grey >= 0.0 && p.backscatter_grey <= 255.0) ||
      !(p.noise_sigma >= 0.0 && p.noise_sigma <= 100.0) || p.min_grey < 0 || p.min_grey > 255 || p.snow_flakes < 0 ||
      p.snow_flakes > 100000)
    return Status(StatusCode::kInvalidArgument, "degrade: parameter out of range");
  const int W = src.width(), H = src.height();
  const double cx = 0.5 * (W - 1), cy = 0.5 * (H - 1);
  const double m_per_px = p.scene_width_m / W;
  const double d0sq = p.light_distance_m * p.light_distance_m;
  const double keep = 1.0 - p.attenuation, haze = p.attenuation * p.backscatter_grey;
  const double lift = static_cast<double>(p.min_grey), span = (255.0 - lift) / 255.0;
  Prng rng(p.seed);
  for (int y = 0; y < H; ++y) {
    const std::uint8_t* s = src.row(y);
    std::uint8_t* d = dst.row(y);
    const double ry = (y - cy) * m_per_px;
    for (int x = 0; x < W; ++x) {
      const double rx = (x - cx) * m_per_px;
      const double gain = d0sq / (d0sq + rx * rx + ry * ry);  // (d0 / d)^2, 1 at the centre
      double v = static_cast<double>(s[x]) * gain;
      v = keep * v + haze;
      if (p.noise_sigma > 0.0) v += p.noise_sigma * rng.gauss();
      if (v < 0.0) v = 0.0;
      if (v > 255.0) v = 255.0;
      d[x] = clamp8(lift + v * span);
    }
  }
  for (int i = 0; i < p.snow_flakes; ++i) {
    const int fx = static_cast<int>(rng.below(static_cast<std::uint32_t>(W)));
    const int fy = static_cast<int>(rng.below(static_cast<std::uint32_t>(H)));
    const int r = 1 + static_cast<int>(rng.below(3));
    const int grey = 200 + static_cast<int>(rng.below(56));
    for (int dy = -r; dy <= r; ++dy)
      for (int dx = -r; dx <= r; ++dx) {
        const int x = fx + dx, y = fy + dy;
        if (x < 0 || y < 0 || x >= W || y >= H || dx * dx + dy * dy > r * r) continue;
        std::uint8_t& px = dst.row(y)[x];
        if (px < grey) px = static_cast<std::uint8_t>(grey);
      }
  }
  return Status::ok();
}

}  // namespace qnav::vision
