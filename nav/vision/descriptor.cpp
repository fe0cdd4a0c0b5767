#include "nav/vision/descriptor.hpp"

#include <cmath>
#include <cstring>

// The histogram's per-row loop: two passes, the first vectorised, where there is SIMD; one scalar
// pass over the window's samples where there is not (cell_histograms). The same values either way.
#if defined(__SSE2__) || defined(__ARM_NEON) || defined(__aarch64__)
#define QNAV_DESCRIPTOR_SIMD 1
#else
#define QNAV_DESCRIPTOR_SIMD 0
#endif

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

namespace {

// atan2 of integer gradients by a minimax polynomial on [0, 1] (max error ~1e-5 rad), in [0, 2 pi).
// Deterministic and much cheaper than libm's atan2. The octant tests are integer compares and the
// float steps are unconditional (selects of constants: base + 1 * r and base - r are exactly the
// values of the branchy form), so the gradient loop vectorises under the default -ftrapping-math.
// For integer inputs r stays in [0, 2 pi) (r >= 2 pi would need y < 0 and r = 0 before the last
// step, but y < 0 gives r >= min(|y| / max, pi / 4) > 0), so no final wrap is needed.
// The octant offsets pi / 2, pi, 2 pi: literals by default; without SIMD the gradient loops read them
// through an opaque pointer (angle_constants()), as position-independent SPARC code otherwise rebuilds
// a literal's address (three instructions and a load) in each taken select of the loop.
struct AngleConstants {
  float half_pi = 1.57079637f, pi = 3.14159274f, two_pi = kTwoPi;
};
#if !QNAV_DESCRIPTOR_SIMD
// 0 .. 1020 as floats (the range of a Sobel sum's magnitude): without SIMD fast_angle looks its two
// integers up here (one load) instead of converting them (through memory on SPARC: store, load, fitos).
constexpr int kSobelMax = 4 * 255;
struct SobelFloats {
  float v[kSobelMax + 1];
  constexpr SobelFloats() : v() {
    for (int i = 0; i <= kSobelMax; ++i) v[i] = static_cast<float>(i);
  }
};
constexpr SobelFloats kSobelFloats{};
#endif
// x and y are Sobel sums (|x|, |y| <= 1020).
inline float fast_angle(int y, int x, const AngleConstants& k = AngleConstants{}) noexcept {
  const int ax = x < 0 ? -x : x, ay = y < 0 ? -y : y;
  const bool swap = ay > ax;
  const int mx = swap ? ay : ax, mn = swap ? ax : ay;
#if QNAV_DESCRIPTOR_SIMD
  const float a = static_cast<float>(mn) / static_cast<float>(mx > 0 ? mx : 1), s = a * a;
#else
  const float a = kSobelFloats.v[mn] / kSobelFloats.v[mx > 0 ? mx : 1], s = a * a;
#endif
  float r = ((-0.0464964749f * s + 0.15931422f) * s - 0.327622764f) * s * a + a;
  r = (swap ? k.half_pi : 0.0f) + (swap ? -1.0f : 1.0f) * r;
  r = (x < 0 ? k.pi : 0.0f) + (x < 0 ? -1.0f : 1.0f) * r;
  r = (y < 0 ? k.two_pi : 0.0f) + (y < 0 ? -1.0f : 1.0f) * r;
  return r;
}
inline AngleConstants angle_constants() noexcept {
#if QNAV_DESCRIPTOR_SIMD
  return AngleConstants{};
#else
  static const AngleConstants kConsts{};
  const AngleConstants* k = &kConsts;
  __asm__("" : "+r"(k));
  return *k;
#endif
}

}  // namespace

inline std::int32_t bits_of(float f) noexcept {
  std::int32_t i;
  std::memcpy(&i, &f, sizeof i);
  return i;
}
#if QNAV_DESCRIPTOR_SIMD
constexpr std::uint32_t kBits5 = 0x40a00000u;  // bits of 5.0f
#endif

// w[i] = exp(-(d0 + i)^2 k), i in [0, n), by the exact recurrence g(i+1) = g(i) r(i),
// r(i+1) = r(i) exp(-2k): three exp() per table instead of n (relative error ~n * 1e-7).
inline void gaussian_table(float d0, float k, int n, float* w) noexcept {
  float g = std::exp(-d0 * d0 * k), r = std::exp(-(2.0f * d0 + 1.0f) * k);
  const float q = std::exp(-2.0f * k);
  for (int i = 0; i < n; ++i) {
    w[i] = g;
    g *= r;
    r *= q;
  }
}

// The steps of compute_oriented_descriptor, each its own function (not inlined: the caller holds the
// 40 KB of scratch planes, and a step whose frame stays small reaches its spill and conversion slots
// with one instruction on SPARC, whose load/store offsets are 13 bits).
namespace {

// Sobel gradient magnitude and angle of the side x side support centred on (xi, yi).
[[gnu::noinline]] void support_gradients(ConstImageViewU8 img, int xi, int yi, int radius, float* __restrict mag,
                                         float* __restrict ang) noexcept {
  const int side = 2 * radius + 1;
  for (int j = 0; j < side; ++j) {
    const std::uint8_t* a = img.row(yi - radius + j - 1) + (xi - radius);
    const std::uint8_t* b = img.row(yi - radius + j) + (xi - radius);
    const std::uint8_t* c = img.row(yi - radius + j + 1) + (xi - radius);
    float* __restrict m = mag + j * side;
    float* __restrict t = ang + j * side;
    // Sobel gx, gy (integers, exact in float) per row; the angle and magnitude below run over the
    // whole support as one flat loop (vectorised, without a scalar remainder per row).
    for (int i = 0; i < side; ++i) {
      m[i] = static_cast<float>((a[i + 1] - a[i - 1]) + 2 * (b[i + 1] - b[i - 1]) + (c[i + 1] - c[i - 1]));
      t[i] = static_cast<float>((c[i - 1] + 2 * c[i] + c[i + 1]) - (a[i - 1] + 2 * a[i] + a[i + 1]));
    }
  }
  const int n = side * side;
  const AngleConstants kc = angle_constants();
  for (int k = 0; k < n; ++k) {
    const int gx = static_cast<int>(mag[k]), gy = static_cast<int>(ang[k]);
    mag[k] = static_cast<float>(gx * gx + gy * gy);  // exact: at most 2 * 1020^2
    ang[k] = fast_angle(gy, gx, kc);
  }
  // The sqrt in a separate scalar pass: libm sqrt keeps its errno path, which does not vectorise.
  for (int k = 0; k < n; ++k) mag[k] = std::sqrt(mag[k]);
}

// Row y (1 .. height-2) of the gradient planes: the values support_gradients computes, pixel by pixel
// (integer Sobel sums, the magnitude as sqrt of their exact square sum, the angle by fast_angle), for
// x in 1 .. width-2; the border columns are not written.
[[gnu::noinline]] void plane_row(ConstImageViewU8 img, int y, float* __restrict mag, float* __restrict ang) noexcept {
  const std::uint8_t* a = img.row(y - 1);
  const std::uint8_t* b = img.row(y);
  const std::uint8_t* c = img.row(y + 1);
  const int w = img.width();
  const AngleConstants kc = angle_constants();
  for (int i = 1; i < w - 1; ++i) {
    const int gx = (a[i + 1] - a[i - 1]) + 2 * (b[i + 1] - b[i - 1]) + (c[i + 1] - c[i - 1]);
    const int gy = (c[i - 1] + 2 * c[i] + c[i + 1]) - (a[i - 1] + 2 * a[i] + a[i + 1]);
    mag[i] = static_cast<float>(gx * gx + gy * gy);
    ang[i] = fast_angle(gy, gx, kc);
  }
  // The sqrt in a separate pass: libm sqrt keeps its errno path, which does not vectorise.
  for (int i = 1; i < w - 1; ++i) mag[i] = std::sqrt(mag[i]);
}

// Dominant orientation: 36-bin histogram of Gaussian-weighted gradients (weights wxo x wyo, inside a
// circle of radius ro), smoothed, peak interpolated. False when there is no gradient.
[[gnu::noinline]] bool dominant_orientation(const float* mag, const float* ang, std::ptrdiff_t stride, int radius, int ro,
                                            const float* wxo, const float* wyo, float& ori) noexcept {
  constexpr int kOriBins = 36;
  float hist[kOriBins] = {};
  float total = 0.0f;
  for (int dy = -ro; dy <= ro; ++dy) {
    int hx = 0;  // half-width of the circle on this row
    while ((hx + 1) * (hx + 1) + dy * dy <= ro * ro) ++hx;
    const float wy = wyo[dy + radius];
    const float* mrow = mag + (dy + radius) * stride + radius;
    const float* arow = ang + (dy + radius) * stride + radius;
    // Two samples a step (in order: the same sums), then the odd one out.
    const auto add = [&](int dx) noexcept {
      const float wm = mrow[dx] * wxo[dx + radius] * wy;
      int b = static_cast<int>(arow[dx] * (kOriBins / kTwoPi));
      b = b >= kOriBins ? kOriBins - 1 : b;
      hist[b] += wm;
      total += wm;
    };
    int dx = -hx;
    for (; dx < hx; dx += 2) {
      add(dx);
      add(dx + 1);
    }
    if (dx == hx) add(dx);
  }
  if (!(total > 1e-3f)) return false;
  float smooth[kOriBins];
  for (int i = 0; i < kOriBins; ++i)
    smooth[i] = 0.25f * hist[(i + kOriBins - 1) % kOriBins] + 0.5f * hist[i] + 0.25f * hist[(i + 1) % kOriBins];
  int best = 0;
  for (int i = 1; i < kOriBins; ++i)
    if (smooth[i] > smooth[best]) best = i;
  const float l = smooth[(best + kOriBins - 1) % kOriBins], c0 = smooth[best], r = smooth[(best + 1) % kOriBins];
  const float den = l - 2.0f * c0 + r;
  const float off = den < 0.0f ? 0.5f * (l - r) / den : 0.0f;
  ori = wrap_2pi((static_cast<float>(best) + 0.5f + off) * (kTwoPi / kOriBins));
  return true;
}

#if QNAV_DESCRIPTOR_SIMD
// One sample's trilinear scatter into the 6 x 6 x 8 histogram copy h (bin coordinates bx, by in
// 0 < b < 5, orientation bin bo in [0, 8], weight m > 0).
inline void scatter_sample(float* h6, float m, float bx, float by, float bo) noexcept {
  const int x0 = static_cast<int>(bx), y0 = static_cast<int>(by), oi = static_cast<int>(bo);
  const float wx = bx - static_cast<float>(x0), wyy = by - static_cast<float>(y0), wo = bo - static_cast<float>(oi);
  const int o0 = oi & 7, o1 = (oi + 1) & 7;
  const float m1 = m * wyy, m0 = m - m1;        // rows y0, y0 + 1
  const float m00 = m0 - m0 * wx, m01 = m0 * wx;  // (y0, x0), (y0, x0 + 1)
  const float m10 = m1 - m1 * wx, m11 = m1 * wx;
  float* h = h6 + (y0 * 6 + x0) * 8;
  const float v00 = m00 * wo, v01 = m01 * wo, v10 = m10 * wo, v11 = m11 * wo;
  h[o0] += m00 - v00;
  h[o1] += v00;
  h[8 + o0] += m01 - v01;
  h[8 + o1] += v01;
  h[48 + o0] += m10 - v10;
  h[48 + o1] += v10;
  h[56 + o0] += m11 - v11;
  h[56 + o1] += v11;
}
#endif

#if !QNAV_DESCRIPTOR_SIMD
// 0 < bx < 5 and 0 < by < 5 (k5 = 5).
inline bool in_window(float bx, float by, float k5) noexcept { return bx > 0.0f && bx < k5 && by > 0.0f && by < k5; }

// The constants of the one-pass loop, read through a pointer the compiler cannot see through (see
// cell_histograms): 2 pi, the angle-bin factor 8 / (2 pi) and the histogram's row length 6.
struct HistConstants {
  float two_pi, obin, six;
};

// One sample of the window (bin coordinates bx, by): its weight, angle bin and trilinear scatter into
// the histogram copy h6, the values of scatter_sample, bit for bit. The eight bins are reached from
// two pointers (orientation bins o0 and o1 of cell (y0, x0)) with constant offsets, which SPARC
// addresses in the load and store themselves.
inline void window_sample(float* h6, const float* mrow, const float* arow, int radius, int i, float bx, float by,
                          float wx, float wy, float ori, const HistConstants& k) noexcept {
  const float m = mrow[i - radius] * wx * wy;
  if (!(m > 0.0f)) return;
  const float da = arow[i - radius] - ori;
  // da < 0 as a float compare (one instruction fewer on SPARC than the sign bit through memory):
  // the same test, as da is never -0 (angles and ori are >= +0, and a - a = +0).
  const float bo = (da + (da < 0.0f ? k.two_pi : 0.0f)) * k.obin;
  // The cell's integer coordinates stay in float registers (fstoi then fitos, no trip through
  // memory); only the cell index y0 * 6 + x0 (exact in float) and the angle bin go to integers.
  const float x0f = static_cast<float>(static_cast<int>(bx)), y0f = static_cast<float>(static_cast<int>(by));
  const int cell = static_cast<int>(y0f * k.six + x0f), oi = static_cast<int>(bo);
  const float wxf = bx - x0f, wyy = by - y0f, wo = bo - static_cast<float>(oi);
  const float m1 = m * wyy, m0 = m - m1;
  const float m00 = m0 - m0 * wxf, m01 = m0 * wxf;
  const float m10 = m1 - m1 * wxf, m11 = m1 * wxf;
  float* h = h6 + cell * 8;
  float* p0 = h + (oi & 7);
  float* p1 = h + ((oi + 1) & 7);
  const float v00 = m00 * wo, v01 = m01 * wo, v10 = m10 * wo, v11 = m11 * wo;
  p0[0] += m00 - v00;
  p1[0] += v00;
  p0[8] += m01 - v01;
  p1[8] += v01;
  p0[48] += m10 - v10;
  p1[48] += v10;
  p0[56] += m11 - v11;
  p1[56] += v11;
}
#endif

// The 4 x 4 x 8 histogram in the frame rotated by ori, trilinear binning, Gaussian weights wxd x wyd,
// cells of `cell` px, (ox, oy) = support centre - sub-pixel position. Accumulated in a 6 x 6 x 8
// histogram with a one-cell border (cells -1..4) so the trilinear scatter needs no bounds tests; the
// border (weights of samples beyond the outer cell centres) is dropped by the caller, as the bounds
// tests did. Even and odd samples of a row go to two copies (h6[0..287], h6[288..575], summed by the
// caller), which halves the chains of read-modify-write updates of the same bins by neighbours.
[[gnu::noinline]] void cell_histograms(const float* mag, const float* ang, std::ptrdiff_t stride, int radius, float ox,
                                       float oy, float ori, float cell, const float* wxd, const float* wyd,
                                       float* h6) noexcept {
  const int side = 2 * radius + 1;
  const float co = std::cos(ori), so = std::sin(ori);
  const float inv_cell = 1.0f / cell;
  const float cx = co * inv_cell, sx = so * inv_cell;
  constexpr float kOBin = 8.0f / kTwoPi;
#if !QNAV_DESCRIPTOR_SIMD
  float cfx[kOrientedMaxSide], sfx[kOrientedMaxSide];
  // The constants through an opaque pointer: as literals the compiler rebuilds their addresses
  // (position-independent code on SPARC: three instructions and a load) inside the loop.
  static const HistConstants kConsts = {kTwoPi, kOBin, 6.0f};
  const HistConstants* kc = &kConsts;
  __asm__("" : "+r"(kc));
  const HistConstants k = *kc;
  const float k5 = 5.0f;
  int prev_lo = -1, prev_hi = -1;  // the previous row's run of window samples (-1: none)
  for (int i = 0; i < side; ++i) {
    const float fx = static_cast<float>(i - radius) + ox;
    cfx[i] = cx * fx;
    sfx[i] = sx * fx;
  }
#endif
  for (int dy = -radius; dy <= radius; ++dy) {
    const float fy = static_cast<float>(dy) + oy;
    const float wy = wyd[dy + radius];
    const float* mrow = mag + (dy + radius) * stride + radius;
    const float* arow = ang + (dy + radius) * stride + radius;
    // Shifted bin coordinates: cell centres at 1..4, the window is 0 < b < 5.
    const float bx0 = sx * fy + 2.5f, by0 = cx * fy + 2.5f;
#if QNAV_DESCRIPTOR_SIMD
    // Pass A (vectorised): bin coordinates and weight of every sample of the row; samples outside
    // the window get weight 0 and clamped coordinates. Pass B: scatter of the non-zero samples.
    float pbx[kOrientedMaxSide], pby[kOrientedMaxSide], pbo[kOrientedMaxSide], pm[kOrientedMaxSide];
    for (int i = 0; i < side; ++i) {
      const float fx = static_cast<float>(i - radius) + ox;
      const float bx = cx * fx + bx0, by = by0 - sx * fx;
      // 0 < b < 5 tested on the IEEE bit patterns (the uint32 order of the bits is the value order
      // on positive floats; -0 and negatives wrap to large values after - 1): exactly the float
      // test, but integer arithmetic, which the compiler vectorises (float compares it will not
      // if-convert under -ftrapping-math).
      const std::uint32_t inx = static_cast<std::uint32_t>(bits_of(bx)) - 1u < kBits5 - 1u ? 1u : 0u;
      const std::uint32_t iny = static_cast<std::uint32_t>(bits_of(by)) - 1u < kBits5 - 1u ? 1u : 0u;
      const float keep = static_cast<float>(static_cast<int>(inx & iny));
      pm[i] = mrow[i - radius] * wxd[i] * wy * keep;
      pbx[i] = bx * keep;
      pby[i] = by * keep;
      const float da = arow[i - radius] - ori;
      pbo[i] = (da + (bits_of(da) < 0 ? kTwoPi : 0.0f)) * kOBin;  // da < 0 (or -0: same bin)
    }
    for (int i = 0; i < side; ++i) {
      const float m = pm[i];
      if (!(m > 0.0f)) continue;
      scatter_sample(h6 + (i & 1) * (6 * 6 * 8), m, pbx[i], pby[i], pbo[i]);  // even / odd samples: two copies
    }
#else
    // Without SIMD (LEON3, armhf without NEON) one pass over the row's samples inside the window,
    // from the products cfx[i] = cx fx, sfx[i] = sx fx taken once per descriptor (the same for every
    // row); the weight, angle bin and scatter only inside the window. The same values as the two
    // passes above (a weight times keep = 1 is itself; no FMA on these targets), bit for bit.
    // The window's samples of a row are one run i = lo..hi: fx grows with i, and bx = cx fx + bx0,
    // by = by0 - sx fx are monotone in fx (float rounding is monotone), so each of 0 < bx < 5,
    // 0 < by < 5 holds on one run of i and so does both. The run's ends are found by testing inwards
    // from the previous row's ends (the run moves by a sample or two a row), or from the row's ends
    // after an empty row; the samples between them need no window test.
    const auto inside = [&](int j) noexcept { return in_window(cfx[j] + bx0, by0 - sfx[j], k5); };
    int lo, hi;
    if (prev_lo >= 0) {
      lo = prev_lo;
      if (inside(lo)) {
        while (lo > 0 && inside(lo - 1)) --lo;  // lo in the run: down to its first sample
      } else {
        // lo before the run (the first inside sample above it is the run's first) or after it (none
        // above: scan from 0).
        do ++lo;
        while (lo < side && !inside(lo));
        if (lo == side) {
          lo = 0;
          while (lo < prev_lo && !inside(lo)) ++lo;
          if (lo == prev_lo) lo = side;  // no sample of the row inside
        }
      }
    } else {
      lo = 0;
      while (lo < side && !inside(lo)) ++lo;
    }
    if (lo == side) {
      prev_lo = -1;
      continue;
    }
    // inside(lo): from the previous row's last sample (not before lo; the row's last after an empty
    // row), up while inside, or down to the last inside sample (hi is past the run's end when
    // !inside(hi), as hi >= lo, the run's start).
    hi = prev_lo >= 0 ? (prev_hi > lo ? prev_hi : lo) : side - 1;
    if (inside(hi)) {
      while (hi < side - 1 && inside(hi + 1)) ++hi;
    } else {
      do --hi;
      while (!inside(hi));
    }
    prev_lo = lo;
    prev_hi = hi;
    // Even samples to the first histogram copy, odd to the second (as the SIMD path), two per step.
    int i = lo;
    if (i <= hi && (i & 1) != 0) {
      window_sample(h6 + 6 * 6 * 8, mrow, arow, radius, i, cfx[i] + bx0, by0 - sfx[i], wxd[i], wy, ori, k);
      ++i;
    }
    for (; i < hi; i += 2) {
      window_sample(h6, mrow, arow, radius, i, cfx[i] + bx0, by0 - sfx[i], wxd[i], wy, ori, k);
      window_sample(h6 + 6 * 6 * 8, mrow, arow, radius, i + 1, cfx[i + 1] + bx0, by0 - sfx[i + 1], wxd[i + 1], wy, ori,
                    k);
    }
    if (i == hi) window_sample(h6, mrow, arow, radius, i, cfx[i] + bx0, by0 - sfx[i], wxd[i], wy, ori, k);
#endif
  }
}

// The inner 4 x 4 cells of the two copies summed into out.v, L2-normalised, clipped at 0.2,
// renormalised. False for an empty histogram.
bool normalise_descriptor(const float* h6, OrientedDescriptor& out) noexcept {
  for (int cy = 0; cy < 4; ++cy)
    for (int cxi = 0; cxi < 4; ++cxi)
      for (int o = 0; o < 8; ++o) {
        const int k = ((cy + 1) * 6 + cxi + 1) * 8 + o;
        out.v[(cy * 4 + cxi) * 8 + o] = h6[k] + h6[6 * 6 * 8 + k];
      }
  float ss = 0.0f;
  for (float v : out.v) ss += v * v;
  if (!(ss > 1e-12f)) return false;
  float inv = 1.0f / std::sqrt(ss);
  ss = 0.0f;
  for (float& v : out.v) {
    v *= inv;
    if (v > 0.2f) v = 0.2f;
    ss += v * v;
  }
  inv = 1.0f / std::sqrt(ss);
  for (float& v : out.v) v *= inv;
  return true;
}

// Support of a descriptor at (x, y) with `scale`: radius and rounded centre, checked against a width x
// height image with one pixel of Sobel border.
struct Support {
  float cell = 0.0f, half_w = 0.0f;
  int radius = 0, xi = 0, yi = 0;
};
Status support_of(int width, int height, float x, float y, float scale, Support& s) noexcept {
  if (width <= 0 || height <= 0) return Status(StatusCode::kInvalidArgument, "descriptor: empty image");
  if (!std::isfinite(x) || !std::isfinite(y) || !(scale >= 0.25f) || !(scale <= kOrientedMaxScale))
    return Status(StatusCode::kInvalidArgument, "descriptor: non-finite position or scale outside [0.25, 4]");
  s.cell = kOrientedCellScale * scale;
  s.half_w = 2.0f * s.cell;  // descriptor window half-width
  s.radius = static_cast<int>(std::ceil(s.half_w * 1.41422f)) + 1;
  s.xi = static_cast<int>(std::lround(x));
  s.yi = static_cast<int>(std::lround(y));
  if (s.xi - s.radius < 1 || s.yi - s.radius < 1 || s.xi + s.radius > width - 2 || s.yi + s.radius > height - 2)
    return Status(StatusCode::kOutOfRange, "descriptor: support leaves the image");
  return Status::ok();
}

// Orientation and histogram from the gradient magnitude and angle of the support (mag / ang at its
// top-left sample, rows `stride` floats apart).
Status describe(const float* mag, const float* ang, std::ptrdiff_t stride, const Support& sp, float x, float y,
                float scale, OrientedDescriptor& out) noexcept {
  const int radius = sp.radius, side = 2 * radius + 1;
  // Separable Gaussian weights around the sub-pixel position.
  const float ox = static_cast<float>(sp.xi) - x, oy = static_cast<float>(sp.yi) - y;
  float wxo[kOrientedMaxSide], wyo[kOrientedMaxSide], wxd[kOrientedMaxSide], wyd[kOrientedMaxSide];
  const float sigma_o = 4.5f * scale;
  const float inv2so = 1.0f / (2.0f * sigma_o * sigma_o), inv2sd = 1.0f / (2.0f * sp.half_w * sp.half_w);
  const float d0x = static_cast<float>(-radius) + ox, d0y = static_cast<float>(-radius) + oy;
  gaussian_table(d0x, inv2so, side, wxo);
  gaussian_table(d0y, inv2so, side, wyo);
  gaussian_table(d0x, inv2sd, side, wxd);
  gaussian_table(d0y, inv2sd, side, wyd);
  // 1. Dominant orientation (sigma 4.5 scale, inside a circle of radius 2 sigma).
  const int ro = static_cast<int>(std::ceil(2.0f * sigma_o)) < radius ? static_cast<int>(std::ceil(2.0f * sigma_o)) : radius;
  float ori = 0.0f;
  if (!dominant_orientation(mag, ang, stride, radius, ro, wxo, wyo, ori))
    return Status(StatusCode::kDegenerate, "descriptor: no gradient around the point");
  // 2. 4 x 4 x 8 histogram in the rotated frame, Gaussian weight sigma = half_w.
  float h6[2 * 6 * 6 * 8] = {};
  cell_histograms(mag, ang, stride, radius, ox, oy, ori, sp.cell, wxd, wyd, h6);
  if (!normalise_descriptor(h6, out)) return Status(StatusCode::kDegenerate, "descriptor: empty histogram");
  out.orientation_rad = ori;
  out.valid = true;
  return Status::ok();
}

}  // namespace

Status compute_oriented_descriptor(ConstImageViewU8 img, float x, float y, float scale, OrientedDescriptor& out) noexcept {
  out.valid = false;
  if (img.empty()) return Status(StatusCode::kInvalidArgument, "descriptor: empty image");
  Support sp;
  QNAV_RETURN_IF_ERROR(support_of(img.width(), img.height(), x, y, scale, sp));
  // Gradient magnitude and angle of the whole support, once (Sobel: robust to pixel noise).
  const int side = 2 * sp.radius + 1;
  float mag[kOrientedMaxSide * kOrientedMaxSide];
  float ang[kOrientedMaxSide * kOrientedMaxSide];
  support_gradients(img, sp.xi, sp.yi, sp.radius, mag, ang);
  return describe(mag, ang, side, sp, x, y, scale, out);
}

Status compute_gradient_planes(ConstImageViewU8 img, Span<float> mag, Span<float> ang, GradientPlanes& out) noexcept {
  out = GradientPlanes{};
  const int w = img.width(), h = img.height();
  if (img.empty() || w < 3 || h < 3) return Status(StatusCode::kInvalidArgument, "gradient planes: image smaller than 3 x 3");
  const std::size_t n = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
  if (mag.size() < n || ang.size() < n) return Status(StatusCode::kCapacityExceeded, "gradient planes: planes too small");
  for (int y = 1; y < h - 1; ++y) plane_row(img, y, mag.data() + static_cast<std::size_t>(y) * static_cast<std::size_t>(w),
                                            ang.data() + static_cast<std::size_t>(y) * static_cast<std::size_t>(w));
  out.mag = mag.data();
  out.ang = ang.data();
  out.width = w;
  out.height = h;
  return Status::ok();
}

Status compute_oriented_descriptor(const GradientPlanes& planes, float x, float y, float scale, OrientedDescriptor& out) noexcept {
  out.valid = false;
  if (planes.mag == nullptr || planes.ang == nullptr)
    return Status(StatusCode::kInvalidArgument, "descriptor: empty gradient planes");
  Support sp;
  QNAV_RETURN_IF_ERROR(support_of(planes.width, planes.height, x, y, scale, sp));
  const std::ptrdiff_t stride = planes.width;
  const std::ptrdiff_t top_left = static_cast<std::ptrdiff_t>(sp.yi - sp.radius) * stride + (sp.xi - sp.radius);
  return describe(planes.mag + top_left, planes.ang + top_left, stride, sp, x, y, scale, out);
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
