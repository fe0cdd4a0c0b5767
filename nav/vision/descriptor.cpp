#include "nav/vision/descriptor.hpp"

#include <cmath>

namespace qnav::vision {

namespace {

constexpr float kTwoPi = 6.28318530717958647692f;

template <typename Pixel>
inline float bilinear(ImageView<const Pixel> img, float x, float y) noexcept {
  const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);  // caller guarantees x, y >= 0
  const float fx = x - static_cast<float>(x0), fy = y - static_cast<float>(y0);
  const Pixel* r0 = img.row(y0) + x0;
  const Pixel* r1 = img.row(y0 + 1) + x0;
  const float top = static_cast<float>(r0[0]) + fx * (static_cast<float>(r0[1]) - static_cast<float>(r0[0]));
  const float bot = static_cast<float>(r1[0]) + fx * (static_cast<float>(r1[1]) - static_cast<float>(r1[0]));
  return top + fy * (bot - top);
}

template <typename Pixel>
Status patch_impl(ImageView<const Pixel> img, float x, float y, float rot, float scale, PatchDescriptor& out,
                  float min_stddev) noexcept {
  out.valid = false;
  if (img.empty()) return Status(StatusCode::kInvalidArgument, "descriptor: empty image");
  if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(rot) || !(scale > 0.0f) || !std::isfinite(scale) ||
      scale > 64.0f)
    return Status(StatusCode::kInvalidArgument, "descriptor: non-finite position, rotation or bad scale");
  const float half = 0.5f * static_cast<float>(kPatchSide - 1);
  const float reach = half * scale * 1.41422f + 1.0f;
  if (x - reach < 0.0f || y - reach < 0.0f || x + reach > static_cast<float>(img.width() - 1) ||
      y + reach > static_cast<float>(img.height() - 1))
    return Status(StatusCode::kOutOfRange, "descriptor: patch leaves the image");
  const float c = std::cos(rot) * scale, s = std::sin(rot) * scale;
  float sum = 0.0f;
  int k = 0;
  for (int j = 0; j < kPatchSide; ++j) {
    const float dy = static_cast<float>(j) - half;
    for (int i = 0; i < kPatchSide; ++i, ++k) {
      const float dx = static_cast<float>(i) - half;
      const float v = bilinear(img, x + c * dx - s * dy, y + s * dx + c * dy);
      out.v[k] = v;
      sum += v;
    }
  }
  const float mean = sum / static_cast<float>(kPatchSize);
  float ss = 0.0f;
  for (float& v : out.v) {
    v -= mean;
    ss += v * v;
  }
  if (!(ss > min_stddev * min_stddev * static_cast<float>(kPatchSize)))
    return Status(StatusCode::kDegenerate, "descriptor: patch has no texture");
  const float inv = 1.0f / std::sqrt(ss);
  for (float& v : out.v) v *= inv;
  out.valid = true;
  return Status::ok();
}

inline float wrap_2pi(float a) noexcept {
  while (a < 0.0f) a += kTwoPi;
  while (a >= kTwoPi) a -= kTwoPi;
  return a;
}

}  // namespace

Status compute_patch_descriptor(ConstImageViewU8 image, float x, float y, float rotation_rad, float scale, PatchDescriptor& out,
                                float min_stddev) noexcept {
  return patch_impl(image, x, y, rotation_rad, scale, out, min_stddev);
}
Status compute_patch_descriptor(ConstImageViewF32 image, float x, float y, float rotation_rad, float scale,
                                PatchDescriptor& out, float min_stddev) noexcept {
  return patch_impl(image, x, y, rotation_rad, scale, out, min_stddev);
}

float zncc(const PatchDescriptor& a, const PatchDescriptor& b) noexcept {
  if (!a.valid || !b.valid) return -2.0f;
  float d = 0.0f;
  for (int i = 0; i < kPatchSize; ++i) d += a.v[i] * b.v[i];
  return d;
}

// atan2 by a minimax polynomial on [0, 1] (max error ~1e-5 rad), in [0, 2 pi). Deterministic and
// much cheaper than libm's atan2 in the descriptor's inner loop.
inline float fast_angle(float y, float x) noexcept {
  const float ax = std::fabs(x), ay = std::fabs(y);
  const float mx = ax > ay ? ax : ay, mn = ax > ay ? ay : ax;
  if (!(mx > 0.0f)) return 0.0f;
  const float a = mn / mx, s = a * a;
  float r = ((-0.0464964749f * s + 0.15931422f) * s - 0.327622764f) * s * a + a;
  if (ay > ax) r = 1.57079637f - r;
  if (x < 0.0f) r = 3.14159274f - r;
  if (y < 0.0f) r = kTwoPi - r;
  return r >= kTwoPi ? r - kTwoPi : r;
}

Status compute_oriented_descriptor(ConstImageViewU8 img, float x, float y, float scale, OrientedDescriptor& out) noexcept {
  out.valid = false;
  if (img.empty()) return Status(StatusCode::kInvalidArgument, "descriptor: empty image");
  if (!std::isfinite(x) || !std::isfinite(y) || !(scale >= 0.25f) || !(scale <= kOrientedMaxScale))
    return Status(StatusCode::kInvalidArgument, "descriptor: non-finite position or scale outside [0.25, 4]");
  const float cell = kOrientedCellScale * scale;
  const float half_w = 2.0f * cell;  // descriptor window half-width
  const int radius = static_cast<int>(std::ceil(half_w * 1.41422f)) + 1;
  const int xi = static_cast<int>(std::lround(x)), yi = static_cast<int>(std::lround(y));
  if (xi - radius < 1 || yi - radius < 1 || xi + radius > img.width() - 2 || yi + radius > img.height() - 2) {
    return Status(StatusCode::kOutOfRange, "descriptor: support leaves the image");
  }
  // Gradient magnitude and angle of the whole support, once (Sobel: robust to pixel noise).
  const int side = 2 * radius + 1;
  float mag[kOrientedMaxSide * kOrientedMaxSide];
  float ang[kOrientedMaxSide * kOrientedMaxSide];
  for (int j = 0; j < side; ++j) {
    const std::uint8_t* a = img.row(yi - radius + j - 1) + (xi - radius);
    const std::uint8_t* b = img.row(yi - radius + j) + (xi - radius);
    const std::uint8_t* c = img.row(yi - radius + j + 1) + (xi - radius);
    float* __restrict m = mag + j * side;
    float* __restrict t = ang + j * side;
    for (int i = 0; i < side; ++i) {
      const float gx = static_cast<float>((a[i + 1] - a[i - 1]) + 2 * (b[i + 1] - b[i - 1]) + (c[i + 1] - c[i - 1]));
      const float gy = static_cast<float>((c[i - 1] + 2 * c[i] + c[i + 1]) - (a[i - 1] + 2 * a[i] + a[i + 1]));
      m[i] = std::sqrt(gx * gx + gy * gy);
      t[i] = fast_angle(gy, gx);
    }
  }
  // Separable Gaussian weights around the sub-pixel position.
  const float ox = static_cast<float>(xi) - x, oy = static_cast<float>(yi) - y;
  float wxo[kOrientedMaxSide], wyo[kOrientedMaxSide], wxd[kOrientedMaxSide], wyd[kOrientedMaxSide];
  const float sigma_o = 4.5f * scale;
  const float inv2so = 1.0f / (2.0f * sigma_o * sigma_o), inv2sd = 1.0f / (2.0f * half_w * half_w);
  for (int i = 0; i < side; ++i) {
    const float dx = static_cast<float>(i - radius) + ox, dy = static_cast<float>(i - radius) + oy;
    wxo[i] = std::exp(-dx * dx * inv2so);
    wyo[i] = std::exp(-dy * dy * inv2so);
    wxd[i] = std::exp(-dx * dx * inv2sd);
    wyd[i] = std::exp(-dy * dy * inv2sd);
  }
  // 1. Dominant orientation: 36-bin histogram of Gaussian-weighted gradients (sigma 4.5 scale,
  //    inside a circle of radius 2 sigma).
  constexpr int kOriBins = 36;
  float hist[kOriBins] = {};
  const int ro = static_cast<int>(std::ceil(2.0f * sigma_o)) < radius ? static_cast<int>(std::ceil(2.0f * sigma_o)) : radius;
  float total = 0.0f;
  for (int dy = -ro; dy <= ro; ++dy)
    for (int dx = -ro; dx <= ro; ++dx) {
      if (dx * dx + dy * dy > ro * ro) continue;
      const int k = (dy + radius) * side + (dx + radius);
      const float wm = mag[k] * wxo[dx + radius] * wyo[dy + radius];
      if (!(wm > 0.0f)) continue;
      int b = static_cast<int>(ang[k] * (kOriBins / kTwoPi));
      b = b >= kOriBins ? kOriBins - 1 : b;
      hist[b] += wm;
      total += wm;
    }
  if (!(total > 1e-3f)) return Status(StatusCode::kDegenerate, "descriptor: no gradient around the point");
  float smooth[kOriBins];
  for (int i = 0; i < kOriBins; ++i)
    smooth[i] = 0.25f * hist[(i + kOriBins - 1) % kOriBins] + 0.5f * hist[i] + 0.25f * hist[(i + 1) % kOriBins];
  int best = 0;
  for (int i = 1; i < kOriBins; ++i)
    if (smooth[i] > smooth[best]) best = i;
  const float l = smooth[(best + kOriBins - 1) % kOriBins], c0 = smooth[best], r = smooth[(best + 1) % kOriBins];
  const float den = l - 2.0f * c0 + r;
  const float off = den < 0.0f ? 0.5f * (l - r) / den : 0.0f;
  const float ori = wrap_2pi((static_cast<float>(best) + 0.5f + off) * (kTwoPi / kOriBins));

  // 2. 4 x 4 x 8 histogram in the rotated frame, trilinear binning, Gaussian weight sigma = half_w.
  for (float& v : out.v) v = 0.0f;
  const float co = std::cos(ori), so = std::sin(ori);
  const float inv_cell = 1.0f / cell;
  for (int dy = -radius; dy <= radius; ++dy) {
    const float fy = static_cast<float>(dy) + oy;
    for (int dx = -radius; dx <= radius; ++dx) {
      const float fx = static_cast<float>(dx) + ox;
      const float rx = (co * fx + so * fy) * inv_cell, ry = (-so * fx + co * fy) * inv_cell;
      const float bx = rx + 1.5f, by = ry + 1.5f;  // cell centres at 0..3
      if (bx <= -1.0f || bx >= 4.0f || by <= -1.0f || by >= 4.0f) continue;
      const int k = (dy + radius) * side + (dx + radius);
      const float m = mag[k] * wxd[dx + radius] * wyd[dy + radius];
      if (!(m > 0.0f)) continue;
      const float bo = wrap_2pi(ang[k] - ori) * (8.0f / kTwoPi);
      const int x0 = static_cast<int>(std::floor(bx)), y0 = static_cast<int>(std::floor(by));
      const int o0 = static_cast<int>(bo) & 7;
      const float wx = bx - static_cast<float>(x0), wy = by - static_cast<float>(y0), wo = bo - std::floor(bo);
      for (int iy = 0; iy < 2; ++iy) {
        const int yy = y0 + iy;
        if (yy < 0 || yy > 3) continue;
        const float wyy = iy ? wy : 1.0f - wy;
        for (int ix = 0; ix < 2; ++ix) {
          const int xx = x0 + ix;
          if (xx < 0 || xx > 3) continue;
          const float wxx = ix ? wx : 1.0f - wx;
          float* h = out.v + (yy * 4 + xx) * 8;
          h[o0] += m * wyy * wxx * (1.0f - wo);
          h[(o0 + 1) & 7] += m * wyy * wxx * wo;
        }
      }
    }
  }
  float ss = 0.0f;
  for (float v : out.v) ss += v * v;
  if (!(ss > 1e-12f)) return Status(StatusCode::kDegenerate, "descriptor: empty histogram");
  float inv = 1.0f / std::sqrt(ss);
  ss = 0.0f;
  for (float& v : out.v) {
    v *= inv;
    if (v > 0.2f) v = 0.2f;
    ss += v * v;
  }
  inv = 1.0f / std::sqrt(ss);
  for (float& v : out.v) v *= inv;
  out.orientation_rad = ori;
  out.valid = true;
  return Status::ok();
}

float descriptor_distance_sq(const OrientedDescriptor& a, const OrientedDescriptor& b) noexcept {
  if (!a.valid || !b.valid) return 1e30f;
  float d = 0.0f;
  for (int i = 0; i < kOrientedDims; ++i) {
    const float e = a.v[i] - b.v[i];
    d += e * e;
  }
  return d;
}

}  // namespace qnav::vision
