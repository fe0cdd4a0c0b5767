#include "drivers/sidescan/sim_seabed.hpp"

#include <cmath>

namespace qnav::sidescan {

namespace {
std::uint64_t mix64(std::uint64_t z) noexcept {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}
std::uint64_t hash3(std::int64_t x, std::int64_t y, std::uint64_t salt) noexcept {
  return mix64(static_cast<std::uint64_t>(x) * 0x9E3779B97F4A7C15ULL ^ mix64(static_cast<std::uint64_t>(y) + salt));
}
float unit(std::uint64_t h) noexcept { return static_cast<float>(h >> 40) * (1.0f / 16777216.0f); }  // [0, 1)
float smooth(float t) noexcept { return t * t * (3.0f - 2.0f * t); }
float clampf(float v, float lo, float hi) noexcept { return v < lo ? lo : (v > hi ? hi : v); }
}  // namespace

Status Seabed::init(const SeabedConfig& c) noexcept {
  if (!(c.patch_scale_m > 0.0f && c.texture_scale_m > 0.0f)) return Status(StatusCode::kInvalidArgument, "seabed scales must be > 0");
  if (!(c.ripple_wavelength_m >= 0.0f) || !(c.rock_cell_m >= 0.0f)) return Status(StatusCode::kInvalidArgument, "negative ripple wavelength or rock cell");
  if (c.rock_cell_m > 0.0f && !(c.rock_radius_min_m > 0.0f && c.rock_radius_max_m >= c.rock_radius_min_m &&
                                 2.0f * c.rock_radius_max_m < c.rock_cell_m))
    return Status(StatusCode::kInvalidArgument, "rock radii must satisfy 0 < min <= max < cell/2");
  cfg_ = c;
  ripple_cn_ = std::cos(c.ripple_heading_rad);
  ripple_ce_ = std::sin(c.ripple_heading_rad);
  return Status::ok();
}

float Seabed::value_noise(double x, double y, std::uint64_t salt, SeabedCache* cache, int slot) const noexcept {
  const double fx = std::floor(x), fy = std::floor(y);
  const auto ix = static_cast<std::int64_t>(fx), iy = static_cast<std::int64_t>(fy);
  const float tx = smooth(static_cast<float>(x - fx)), ty = smooth(static_cast<float>(y - fy));
  float v00, v10, v01, v11;
  if (cache != nullptr && cache->ix[slot] == ix && cache->iy[slot] == iy) {
    v00 = cache->v[slot][0];
    v10 = cache->v[slot][1];
    v01 = cache->v[slot][2];
    v11 = cache->v[slot][3];
  } else {
    v00 = unit(hash3(ix, iy, salt));
    v10 = unit(hash3(ix + 1, iy, salt));
    v01 = unit(hash3(ix, iy + 1, salt));
    v11 = unit(hash3(ix + 1, iy + 1, salt));
    if (cache != nullptr) {
      cache->ix[slot] = ix;
      cache->iy[slot] = iy;
      cache->v[slot][0] = v00;
      cache->v[slot][1] = v10;
      cache->v[slot][2] = v01;
      cache->v[slot][3] = v11;
    }
  }
  const float a = v00 + tx * (v10 - v00), b = v01 + tx * (v11 - v01);
  return a + ty * (b - a);  // [0, 1)
}

SeabedSample Seabed::sample(double n, double e) const noexcept {
  SeabedCache fresh;
  return sample(n, e, fresh);
}

SeabedSample Seabed::sample(double n, double e, SeabedCache& cache) const noexcept {
  const std::uint64_t s = cfg_.seed * 0x2545F4914F6CDD1DULL;
  // Sediment patches and texture (zero-mean fields).
  const float patch = value_noise(n / static_cast<double>(cfg_.patch_scale_m), e / static_cast<double>(cfg_.patch_scale_m), s + 1, &cache, 0) - 0.5f;
  float tex = 0.0f, amp = 0.5f;
  double scale = static_cast<double>(cfg_.texture_scale_m);
  for (int o = 0; o < 3; ++o) {
    tex += amp * (value_noise(n / scale, e / scale, s + 10 + static_cast<std::uint64_t>(o), &cache, o + 1) - 0.5f);
    amp *= 0.5f;
    scale *= 0.5;
  }
  float refl = cfg_.base_reflectivity + 2.0f * cfg_.patch_contrast * patch + 2.0f * cfg_.texture_contrast * tex;
  float height = 0.0f;
  // Changed seabed: soft discs of changed reflectivity in a fraction of change_scale_m cells.
  if (cfg_.change_fraction > 0.0f && cfg_.change_scale_m > 0.0f) {
    const double cs = static_cast<double>(cfg_.change_scale_m);
    const double fn = std::floor(n / cs), fe = std::floor(e / cs);
    const std::uint64_t h = hash3(static_cast<std::int64_t>(fn), static_cast<std::int64_t>(fe), cfg_.change_seed * 0x9E3779B97F4A7C15ULL + 300);
    if (unit(h) < cfg_.change_fraction) {
      double cn = 0.5, ce = 0.5, rad = 0.45;
      if (cfg_.change_irregular) {  // radius and centre drawn per cell: no lattice of equal discs
        const std::uint64_t g = mix64(h ^ 0x5bd1e995ULL);
        rad = 0.2 + 0.25 * static_cast<double>(g & 0xffff) / 65535.0;
        cn = 0.5 + (0.5 - rad) * (2.0 * static_cast<double>((g >> 16) & 0xffff) / 65535.0 - 1.0);
        ce = 0.5 + (0.5 - rad) * (2.0 * static_cast<double>((g >> 32) & 0xffff) / 65535.0 - 1.0);
      }
      const double dn = n / cs - (fn + cn), de = e / cs - (fe + ce);
      const float w = clampf((static_cast<float>(rad) - static_cast<float>(std::sqrt(dn * dn + de * de))) * 10.0f, 0.0f, 1.0f);
      refl += ((mix64(h) & 1u) ? 1.0f : -1.0f) * cfg_.change_contrast * w;
    }
  }
  // Ripples where the patch field is "sandy" (patch > 0), fading in smoothly.
  if (cfg_.ripple_wavelength_m > 0.0f && patch > -0.05f) {
    const float w = clampf((patch + 0.05f) * 8.0f, 0.0f, 1.0f);
    double ph = (n * static_cast<double>(ripple_cn_) + e * static_cast<double>(ripple_ce_)) /
                static_cast<double>(cfg_.ripple_wavelength_m);
    if (cfg_.change_ripple_shift_m != 0.0f) ph -= static_cast<double>(cfg_.change_ripple_shift_m) / static_cast<double>(cfg_.ripple_wavelength_m);
    const float sn = static_cast<float>(std::sin(2.0 * 3.14159265358979323846 * ph));
    height += w * cfg_.ripple_height_m * sn;
    refl += w * cfg_.ripple_contrast * sn;
  }
  // Rocks: at most one per cell, fully inside its cell.
  if (cfg_.rock_cell_m > 0.0f) {
    const double cell = static_cast<double>(cfg_.rock_cell_m);
    const double fn = std::floor(n / cell), fe = std::floor(e / cell);
    const auto kn = static_cast<std::int64_t>(fn), ke = static_cast<std::int64_t>(fe);
    if (cache.rock_fn != kn || cache.rock_fe != ke) {
      const std::uint64_t h = hash3(kn, ke, s + 100);
      cache.rock_fn = kn;
      cache.rock_fe = ke;
      cache.rock = unit(h) < cfg_.rock_probability;
      // Changed seabed: a rock vanished from this cell, or one appeared.
      if (cfg_.change_fraction > 0.0f && unit(hash3(kn, ke, cfg_.change_seed * 0x9E3779B97F4A7C15ULL + 200)) < cfg_.change_fraction)
        cache.rock = !cache.rock;
      if (cache.rock) {
        const std::uint64_t h2 = mix64(h);
        const std::uint64_t h3 = mix64(h2);
        const float r = cfg_.rock_radius_min_m + unit(h2) * (cfg_.rock_radius_max_m - cfg_.rock_radius_min_m);
        const double span = cell - 2.0 * static_cast<double>(r);
        cache.rock_r = r;
        cache.rock_cn = fn * cell + static_cast<double>(r) + span * static_cast<double>(unit(h3));
        cache.rock_ce = fe * cell + static_cast<double>(r) + span * static_cast<double>(unit(mix64(h3)));
      }
    }
    if (cache.rock) {
      const float r = cache.rock_r;
      const double cn = cache.rock_cn, ce = cache.rock_ce;
      const double dn = n - cn, de = e - ce;
      const double d2 = dn * dn + de * de, r2 = static_cast<double>(r) * static_cast<double>(r);
      if (d2 < r2) {
        const float hh = cfg_.rock_height_ratio * r * static_cast<float>(std::sqrt(1.0 - d2 / r2));
        if (hh > height) height = hh;
        refl = cfg_.rock_reflectivity + 0.1f * tex;
      }
    }
  }
  // Placed objects.
  for (const SeabedObject& o : cfg_.objects) {
    const double dn = n - o.north_m, de = e - o.east_m;
    bool inside = false;
    if (o.kind == SeabedObject::Kind::kCylinder) {
      const double rr = 0.5 * static_cast<double>(o.width_m);
      inside = dn * dn + de * de <= rr * rr;
    } else {
      const double c = std::cos(static_cast<double>(o.heading_rad)), sn = std::sin(static_cast<double>(o.heading_rad));
      const double along = dn * c + de * sn, across = -dn * sn + de * c;
      inside = std::fabs(along) <= 0.5 * static_cast<double>(o.length_m) && std::fabs(across) <= 0.5 * static_cast<double>(o.width_m);
    }
    if (inside) {
      if (o.height_m > height) height = o.height_m;
      refl = o.reflectivity;
    }
  }
  return SeabedSample{clampf(refl, 0.02f, 1.0f), height};
}

}  // namespace qnav::sidescan
