#include "nav/vision/harris.hpp"
#include "nav/core/assert.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#include <type_traits>

namespace qnav::vision {

namespace {

constexpr int kMinSide = 8;

Status bad_config(const char* msg) noexcept { return Status(StatusCode::kInvalidArgument, msg); }

Status check_config(const HarrisConfig& c) noexcept {
  if (c.max_width < kMinSide || c.max_height < kMinSide || c.max_width > kMaxImageSide || c.max_height > kMaxImageSide)
    return bad_config("harris: max image size out of range");
  if (c.max_corners < 1 || c.max_corners > 1000000) return bad_config("harris: max_corners out of range");
  if (c.block_radius < 1 || c.block_radius > 7) return bad_config("harris: block_radius must be 1..7");
  if (!(c.k > 0.0f && c.k < 0.25f)) return bad_config("harris: k must be in (0, 0.25)");
  if (c.nms_radius < 1 || c.nms_radius > 15) return bad_config("harris: nms_radius must be 1..15");
  if (c.border_px < c.block_radius + 1 || c.border_px > 256) return bad_config("harris: border_px must be >= block_radius + 1");
  if (!(c.min_response >= 0.0f) || !std::isfinite(c.min_response)) return bad_config("harris: min_response must be finite >= 0");
  if (!(c.quality_level >= 0.0f && c.quality_level < 1.0f)) return bad_config("harris: quality_level must be in [0, 1)");
  if (c.norm_cell_px < 4 || c.norm_cell_px > 512) return bad_config("harris: norm_cell_px must be 4..512");
  if (c.norm_cells < 0 || c.norm_cells > 8) return bad_config("harris: norm_cells must be 0..8");
  if (!(c.norm_floor >= 0.0f) || !std::isfinite(c.norm_floor)) return bad_config("harris: norm_floor must be finite >= 0");
  return Status::ok();
}

struct Sizes {
  std::size_t response, ring, colsum, grad, cells, nms;
};

Sizes sizes_for(const HarrisConfig& c) noexcept {
  const std::size_t w = static_cast<std::size_t>(c.max_width), h = static_cast<std::size_t>(c.max_height);
  const std::size_t rows = static_cast<std::size_t>(2 * c.block_radius + 1);
  const std::size_t cw = (w + static_cast<std::size_t>(c.norm_cell_px) - 1) / static_cast<std::size_t>(c.norm_cell_px);
  const std::size_t ch = (h + static_cast<std::size_t>(c.norm_cell_px) - 1) / static_cast<std::size_t>(c.norm_cell_px);
  // cells: sum, count, neighbourhood mean.
  return Sizes{w * h, 3 * rows * w, 3 * w, 2 * w, 3 * cw * ch, static_cast<std::size_t>(2 * c.nms_radius + 1) * w};
}

// Strict weak order "a is a better corner than b": higher score, then smaller y, then smaller x. With
// SIMD a function object, so that std::push_heap / pop_heap / sort inline it (the host's function pointer
// was an indirect call per comparison); without, a function (the inlined heap counted 1.3 % more leon3
// instructions for harris).
struct Better {
  bool operator()(const Corner& a, const Corner& b) const noexcept {
    if (a.score != b.score) return a.score > b.score;
    if (a.y != b.y) return a.y < b.y;
    return a.x < b.x;
  }
};
#if defined(__SSE2__) || defined(__ARM_NEON) || defined(__aarch64__)  // !kHarrisIntegerTensor
constexpr Better better{};
#else
inline bool better(const Corner& a, const Corner& b) noexcept { return Better{}(a, b); }
#endif

// Sobel gradients of row y over columns [x0, x1) (1 <= x0, x1 <= W-1, 1 <= y <= H-2), scaled by 1/8
// (exact in float), so a unit step gives a gradient of 0.5 per pixel on both sides.
inline void sobel_row(ImageView<const std::uint8_t> img, int y, int x0, int x1, float* __restrict gx,
                      float* __restrict gy) noexcept {
  const std::uint8_t* __restrict a = img.row(y - 1);
  const std::uint8_t* __restrict b = img.row(y);
  const std::uint8_t* __restrict c = img.row(y + 1);
  for (int x = x0; x < x1; ++x) {
    const int dx = (a[x + 1] - a[x - 1]) + 2 * (b[x + 1] - b[x - 1]) + (c[x + 1] - c[x - 1]);
    const int dy = (c[x - 1] + 2 * c[x] + c[x + 1]) - (a[x - 1] + 2 * a[x] + a[x + 1]);
    gx[x] = static_cast<float>(dx) * 0.125f;
    gy[x] = static_cast<float>(dy) * 0.125f;
  }
}

inline void sobel_row(ImageView<const float> img, int y, int x0, int x1, float* __restrict gx,
                      float* __restrict gy) noexcept {
  const float* __restrict a = img.row(y - 1);
  const float* __restrict b = img.row(y);
  const float* __restrict c = img.row(y + 1);
  for (int x = x0; x < x1; ++x) {
    const float dx = (a[x + 1] - a[x - 1]) + 2.0f * (b[x + 1] - b[x - 1]) + (c[x + 1] - c[x - 1]);
    const float dy = (c[x - 1] + 2.0f * c[x] + c[x + 1]) - (a[x - 1] + 2.0f * a[x] + a[x + 1]);
    gx[x] = dx * 0.125f;
    gy[x] = dy * 0.125f;
  }
}

// colsum[c][x] = sum over the ring slots of product c (slot j holds xx, yy, xy rows of width wz).
void vertical_sums(const float* ring, std::size_t wz, int nrows, int x0, int x1, float* __restrict cxx, float* __restrict cyy,
                   float* __restrict cxy) noexcept {
  const float* __restrict a = ring;
  if (nrows == 3) {
    const float* __restrict b = ring + 3 * wz;
    const float* __restrict c = ring + 6 * wz;
    for (int x = x0; x < x1; ++x) {
      cxx[x] = a[x] + b[x] + c[x];
      cyy[x] = a[wz + x] + b[wz + x] + c[wz + x];
      cxy[x] = a[2 * wz + x] + b[2 * wz + x] + c[2 * wz + x];
    }
    return;
  }
  for (int x = x0; x < x1; ++x) {
    cxx[x] = a[x];
    cyy[x] = a[wz + x];
    cxy[x] = a[2 * wz + x];
  }
  for (int j = 1; j < nrows; ++j) {
    const float* __restrict sj = ring + static_cast<std::size_t>(3 * j) * wz;
    for (int x = x0; x < x1; ++x) {
      cxx[x] += sj[x];
      cyy[x] += sj[wz + x];
      cxy[x] += sj[2 * wz + x];
    }
  }
}

// Block radius 1 on an 8-bit image: the structure tensor from integer gradients, one pass per image row.
// Row py's Sobel sums dx, dy (|.| <= 1020: the integers sobel_row scales by 1/8) come from the
// separable column terms v = a + 2b + c and d = c - a kept in registers, and are converted to float
// once each; their products (|.| <= 2^20) and the products' sums over columns x-1..x+1 (|.| < 2^22) are
// integers, exact in float, and go to ring slot py % 3; once three rows are in, output row py-1 sums
// the three slots (|.| <= 9 * 1020^2 < 2^24, exact). The same floats as the float path: there gx = dx / 8,
// so every product and partial box sum is an integer multiple of 1/64 below 2^24 / 64, exact in any
// order; so sxx = Sxx / 64 (exact) etc. The response is taken on the unscaled sums and scaled by 2^-12
// at the end: each product, difference and k * tr of the scaled expression is the unscaled one's times
// a power of two (no operand or result is subnormal: the nonzero ones are at least 0.04 / 4096), so the
// rounding is the same and so is the result. Per pixel: 3 byte loads, 2 int -> float conversions, the
// products in float (a LEON3 converts through memory, and has no SIMD for the float passes this replaces).
//
// Two product rows per pass (kRows 2: rows py and py+1 from image rows a, b, c, e = py-1 .. py+2): the
// ring is two slots, sa holding row py-2's sums and sb row py-1's on entry and rows py and py+1's on
// exit; with kOutput, output rows py-1 (out0) and py (out1) share t = row py-1 + row py: 6 loads and 9
// adds of the ring per column for two rows instead of 12 and 12, and 4 byte loads instead of 6. kRows 1
// (the last row of an odd count, kOutput) gives output row py-1 alone.
template <bool kOutput, int kRows>
inline void tensor_rows_u8_r1(const std::uint8_t* __restrict a, const std::uint8_t* __restrict b, const std::uint8_t* __restrict c,
                              const std::uint8_t* __restrict e, int x0, int x1, float* __restrict sa, float* __restrict sb,
                              float k, float* __restrict out0, float* __restrict out1) noexcept {
  static_assert(kRows == 2 || kOutput, "a single row is only the last output row");
  const auto v1 = [&](int x) { return a[x] + 2 * b[x] + c[x]; };
  const auto d1 = [&](int x) { return c[x] - a[x]; };
  const auto v2 = [&](int x) { return b[x] + 2 * c[x] + e[x]; };
  const auto d2 = [&](int x) { return e[x] - b[x]; };
  const auto response = [k](float sxx, float syy, float sxy) {
    const float tr = sxx + syy;
    return (sxx * syy - sxy * sxy - k * tr * tr) * 0.000244140625f;  // 2^-12
  };
  // Per row: columns x0-2 .. x0+1 give the products at x0-1 (m) and x0 (z).
  struct Row {
    int va, da, vb, db;
    float mxx, myy, mxy, zxx, zyy, zxy;
  };
  const auto start = [x0](auto v, auto d) {
    Row r;
    const int vm2 = v(x0 - 2), dm2 = d(x0 - 2), vm1 = v(x0 - 1), dm1 = d(x0 - 1);
    r.va = v(x0);
    r.da = d(x0);
    r.vb = v(x0 + 1);
    r.db = d(x0 + 1);
    float gx = static_cast<float>(r.va - vm2), gy = static_cast<float>(dm2 + 2 * dm1 + r.da);
    r.mxx = gx * gx;
    r.myy = gy * gy;
    r.mxy = gx * gy;
    gx = static_cast<float>(r.vb - vm1);
    gy = static_cast<float>(dm1 + 2 * r.da + r.db);
    r.zxx = gx * gx;
    r.zyy = gy * gy;
    r.zxy = gx * gy;
    return r;
  };
  Row r1 = start(v1, d1), r2{};
  if (kRows == 2) r2 = start(v2, d2);
  // One row at column x: (v0, d0) = column x, dn = column x+1's d, p0 = products at x-1, p1 at x; the new
  // column x+2 and the products at x+1 overwrite the oldest ones, so two calls with the roles swapped
  // make one step of period 2 without register moves (no copies on an in-order core). h: the products
  // summed over columns x-1..x+1.
  const auto row_step = [](int vn2, int dn2, int& v0, int& d0, int dn, float& p0xx, float& p0yy, float& p0xy, float p1xx,
                           float p1yy, float p1xy, float& hxx, float& hyy, float& hxy) {
    const float gx = static_cast<float>(vn2 - v0), gy = static_cast<float>(d0 + 2 * dn + dn2);
    const float pxx = gx * gx, pyy = gy * gy, pxy = gx * gy;
    hxx = p0xx + p1xx + pxx;
    hyy = p0yy + p1yy + pyy;
    hxy = p0xy + p1xy + pxy;
    v0 = vn2;
    d0 = dn2;
    p0xx = pxx;
    p0yy = pyy;
    p0xy = pxy;
  };
  const auto step = [&](int x, bool odd) {
    float h1xx, h1yy, h1xy, h2xx = 0.0f, h2yy = 0.0f, h2xy = 0.0f;
    if (!odd) {
      row_step(v1(x + 2), d1(x + 2), r1.va, r1.da, r1.db, r1.mxx, r1.myy, r1.mxy, r1.zxx, r1.zyy, r1.zxy, h1xx, h1yy, h1xy);
      if (kRows == 2)
        row_step(v2(x + 2), d2(x + 2), r2.va, r2.da, r2.db, r2.mxx, r2.myy, r2.mxy, r2.zxx, r2.zyy, r2.zxy, h2xx, h2yy, h2xy);
    } else {
      row_step(v1(x + 2), d1(x + 2), r1.vb, r1.db, r1.da, r1.zxx, r1.zyy, r1.zxy, r1.mxx, r1.myy, r1.mxy, h1xx, h1yy, h1xy);
      if (kRows == 2)
        row_step(v2(x + 2), d2(x + 2), r2.vb, r2.db, r2.da, r2.zxx, r2.zyy, r2.zxy, r2.mxx, r2.myy, r2.mxy, h2xx, h2yy, h2xy);
    }
    float* __restrict qa = sa + 3 * x;  // xx yy xy interleaved per column
    float* __restrict qb = sb + 3 * x;
    if (kOutput) {
      if (kRows == 2) {
        const float txx = qb[0] + h1xx, tyy = qb[1] + h1yy, txy = qb[2] + h1xy;  // rows py-1 + py
        out0[x] = response(qa[0] + txx, qa[1] + tyy, qa[2] + txy);
        out1[x] = response(txx + h2xx, tyy + h2yy, txy + h2xy);
      } else {
        out0[x] = response(qa[0] + qb[0] + h1xx, qa[1] + qb[1] + h1yy, qa[2] + qb[2] + h1xy);
      }
    }
    if (kRows == 2) {
      qa[0] = h1xx;
      qa[1] = h1yy;
      qa[2] = h1xy;
      qb[0] = h2xx;
      qb[1] = h2yy;
      qb[2] = h2xy;
    }
  };
  int x = x0;
  for (; x + 2 <= x1; x += 2) {
    step(x, false);
    step(x + 1, true);
  }
  if (x < x1) step(x, false);
}

// Four-lane float / int vectors (GCC and clang vector extensions: SSE2 on x86, NEON on ARM, scalar code
// elsewhere), used only where kHarrisIntegerTensor is false (a target with SIMD). The selections are
// bitwise on the compare masks, so every lane takes exactly the scalar expression's value (NaN and
// signed zeros included): the same results bit for bit as the scalar loops they replace.
using F4 = float __attribute__((vector_size(16)));
using I4 = std::int32_t __attribute__((vector_size(16)));

inline F4 load4(const float* p) noexcept {
  F4 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
// a > b ? a : b per lane (NaN in a gives b): SSE's maxps is exactly this; elsewhere a bitwise select on
// the compare mask (all ones or all zeros per lane).
inline F4 max4(F4 a, F4 b) noexcept {
#if defined(__SSE2__)
  return reinterpret_cast<F4>(_mm_max_ps(reinterpret_cast<__m128>(a), reinterpret_cast<__m128>(b)));
#else
  const I4 c = a > b;
  return reinterpret_cast<F4>((c & reinterpret_cast<I4>(a)) | (~c & reinterpret_cast<I4>(b)));
#endif
}

// Four whole 16-pixel normalisation cells starting at p (cell side 16, aligned): sums[c] is what
// max_and_positive_sum gives for cell c alone (lane k of a cell = v[k] + v[k+8] for its positive values,
// the lanes added in order 0..7 from 0), computed for the 4 cells at once after a 4x4 transpose (lane c
// = cell c); mv takes the running max of the 64 values (the max over a set with the +0 start, in any order:
// see response_statistics).
inline void cells16_x4(const float* __restrict p, F4& mv, float* __restrict sums) noexcept {
  const F4 zero = {0.0f, 0.0f, 0.0f, 0.0f};
  F4 lo[4], hi[4];
  for (int c = 0; c < 4; ++c) {
    const F4 a = load4(p + 16 * c), b = load4(p + 16 * c + 4), d = load4(p + 16 * c + 8), e = load4(p + 16 * c + 12);
    mv = max4(a, mv);
    mv = max4(b, mv);
    mv = max4(d, mv);
    mv = max4(e, mv);
    lo[c] = max4(a, zero) + max4(d, zero);  // lanes 0..3: v[k] + v[k+8] (0 + v[k] is v[k])
    hi[c] = max4(b, zero) + max4(e, zero);  // lanes 4..7
  }
  F4 acc = zero;
  for (const F4* q : {lo, hi}) {
    const F4 t0 = __builtin_shufflevector(q[0], q[1], 0, 4, 1, 5), t1 = __builtin_shufflevector(q[0], q[1], 2, 6, 3, 7);
    const F4 t2 = __builtin_shufflevector(q[2], q[3], 0, 4, 1, 5), t3 = __builtin_shufflevector(q[2], q[3], 2, 6, 3, 7);
    acc += __builtin_shufflevector(t0, t2, 0, 1, 4, 5);  // lane k of every cell, in order
    acc += __builtin_shufflevector(t0, t2, 2, 3, 6, 7);
    acc += __builtin_shufflevector(t1, t3, 0, 1, 4, 5);
    acc += __builtin_shufflevector(t1, t3, 2, 3, 6, 7);
  }
  std::memcpy(sums, &acc, sizeof acc);
}

// Max and sum of the positive values of v[0..n), in 8 independent lanes (lane k: v[k], v[k+8], ...;
// the tail in lane 0; the lanes combined in order 0..7), so the result is deterministic. With SIMD the
// 8 lanes are two 4-lane vectors (the same lanes, the same order: the same floats).
// finite: v holds no NaN (8-bit images' responses), and vmax >= +0 (rmax's start): then x > m is the
// signed integer compare of their bits (for m >= +0: a positive float's bits order like the float, a
// negative one's or -0's are negative integers, below m's, as the float is not above m) and x > 0 is
// bits > 0; no float compare (a LEON3 needs a compare, a nop and a float branch for each).
inline std::int32_t float_bits(const float* p) noexcept {
  // Aligned as a float: one word load (without the hint SPARC gcc copies the 4 bytes one by one).
  const void* q = __builtin_assume_aligned(p, alignof(float));
  std::int32_t b;
  std::memcpy(&b, q, sizeof b);
  return b;
}
inline void max_and_positive_sum(const float* __restrict v, int n, float& vmax, float& psum, bool simd, bool finite) noexcept {
  float m[8] = {vmax, vmax, vmax, vmax, vmax, vmax, vmax, vmax};
  float s[8] = {};
  int i = 0;
  if (!kHarrisIntegerTensor && simd) {  // the vector loops only exist with SIMD (compiled out elsewhere)
    if (n >= 8) {
      F4 m0 = load4(m), m1 = m0, s0 = load4(s), s1 = s0;
      const F4 zero = s0;
      for (; i + 8 <= n; i += 8) {
        const F4 x0 = load4(v + i), x1 = load4(v + i + 4);
        m0 = max4(x0, m0);
        m1 = max4(x1, m1);
        s0 += max4(x0, zero);
        s1 += max4(x1, zero);
      }
      std::memcpy(m, &m0, sizeof m0);
      std::memcpy(m + 4, &m1, sizeof m1);
      std::memcpy(s, &s0, sizeof s0);
      std::memcpy(s + 4, &s1, sizeof s1);
    }
  }
  if (finite) {
    std::int32_t mb[8];
    std::memcpy(mb, m, sizeof mb);
    for (; i + 8 <= n; i += 8)
      for (int k = 0; k < 8; ++k) {
        const std::int32_t xb = float_bits(v + i + k);
        mb[k] = xb > mb[k] ? xb : mb[k];
        if (xb > 0) s[k] += v[i + k];  // adding +0 instead leaves s[k] (>= +0) as it is
      }
    for (; i < n; ++i) {
      const std::int32_t xb = float_bits(v + i);
      mb[0] = xb > mb[0] ? xb : mb[0];
      if (xb > 0) s[0] += v[i];
    }
    std::memcpy(m, mb, sizeof mb);
  }
  {
    for (; i + 8 <= n; i += 8)
      for (int k = 0; k < 8; ++k) {
        const float x = v[i + k];
        m[k] = x > m[k] ? x : m[k];
        s[k] += x > 0.0f ? x : 0.0f;
      }
  }
  for (; i < n; ++i) {
    m[0] = v[i] > m[0] ? v[i] : m[0];
    s[0] += v[i] > 0.0f ? v[i] : 0.0f;
  }
  for (int k = 0; k < 8; ++k) {
    vmax = m[k] > vmax ? m[k] : vmax;
    psum += s[k];
  }
}

}  // namespace

bool harris_response_u8_r1(ConstImageViewU8 img, RectI g, float k, ImageViewF32 resp, Span<float> ring) noexcept {
  const std::size_t wz = ring.size() / 9;  // a slot: 3 products interleaved per column
  if (g.empty() || g.x < 2 || g.y < 2 || g.x + g.width > img.width() - 2 || g.y + g.height > img.height() - 2 ||
      resp.width() < g.x + g.width || resp.height() < g.y + g.height || wz < static_cast<std::size_t>(g.x + g.width))
    return false;
  const int x0 = g.x, x1 = g.x + g.width;
  float* sa = ring.data();
  float* sb = ring.data() + 3 * wz;
  // Product rows g.y-1 .. g.y+g.height, two per pass; the first pass fills the ring, each later one
  // gives output rows py-1 and py; an odd last row alone.
  tensor_rows_u8_r1<false, 2>(img.row(g.y - 2), img.row(g.y - 1), img.row(g.y), img.row(g.y + 1), x0, x1, sa, sb, k, nullptr,
                              nullptr);
  int py = g.y + 1;
  for (; py + 1 <= g.y + g.height; py += 2)
    tensor_rows_u8_r1<true, 2>(img.row(py - 1), img.row(py), img.row(py + 1), img.row(py + 2), x0, x1, sa, sb, k,
                               resp.row(py - 1), resp.row(py));
  if (py == g.y + g.height)
    tensor_rows_u8_r1<true, 1>(img.row(py - 1), img.row(py), img.row(py + 1), img.row(py + 1), x0, x1, sa, sb, k,
                               resp.row(py - 1), nullptr);
  return true;
}

std::size_t HarrisDetector::arena_bytes(const HarrisConfig& config) noexcept {
  const Sizes s = sizes_for(config);
  return (s.response + s.ring + s.colsum + s.grad + s.cells + s.nms) * sizeof(float) + 6 * alignof(float) +
         static_cast<std::size_t>(config.max_corners) * sizeof(Corner) + alignof(Corner);
}

Status HarrisDetector::init(const HarrisConfig& config, Arena& arena) noexcept {
  ready_ = false;
  const Status s = check_config(config);
  if (!s) {
    counters_.increment(VisionCounter::kBadConfig);
    return s;
  }
  const Sizes z = sizes_for(config);
  response_ = arena.allocate<float>(z.response);
  ring_ = arena.allocate<float>(z.ring);
  colsum_ = arena.allocate<float>(z.colsum);
  grad_ = arena.allocate<float>(z.grad);
  cells_ = arena.allocate<float>(z.cells);
  heap_ = arena.allocate<Corner>(static_cast<std::size_t>(config.max_corners));
  nms_ring_ = arena.allocate<float>(z.nms);
  if (response_.empty() || ring_.empty() || colsum_.empty() || grad_.empty() || cells_.empty() || heap_.empty() ||
      nms_ring_.empty()) {
    counters_.increment(VisionCounter::kBadConfig);
    return Status(StatusCode::kCapacityExceeded, "harris: arena too small");
  }
  config_ = config;
  ready_ = true;
  return Status::ok();
}

Status HarrisDetector::detect(ConstImageViewU8 image, BoundedVector<Corner>& out) noexcept {
  return detect_impl<std::uint8_t>(image, RectI{0, 0, image.width(), image.height()}, out);
}
Status HarrisDetector::detect(ConstImageViewF32 image, BoundedVector<Corner>& out) noexcept {
  return detect_impl<float>(image, RectI{0, 0, image.width(), image.height()}, out);
}
Status HarrisDetector::detect(ConstImageViewU8 image, RectI roi, BoundedVector<Corner>& out) noexcept {
  return detect_impl<std::uint8_t>(image, roi, out);
}
Status HarrisDetector::detect(ConstImageViewF32 image, RectI roi, BoundedVector<Corner>& out) noexcept {
  return detect_impl<float>(image, roi, out);
}

namespace {

// Zeroes the part of the grown area gz where the response is not defined (outside g): NMS reads it.
void zero_undefined(ImageViewF32 resp, RectI g, RectI gz) noexcept {
  for (int y = gz.y; y < gz.y + gz.height; ++y) {
    float* row = resp.row(y);
    if (y < g.y || y >= g.y + g.height) {
      for (int x = gz.x; x < gz.x + gz.width; ++x) row[x] = 0.0f;
    } else {
      for (int x = gz.x; x < g.x; ++x) row[x] = 0.0f;
      for (int x = g.x + g.width; x < gz.x + gz.width; ++x) row[x] = 0.0f;
    }
  }
}

// Row maximum over the 2 nms + 1 columns around each x of [dx0, dx1) of row yy.
void nms_row_max(ConstImageViewF32 resp, int nms, int yy, int dx0, int dx1, float* __restrict dst) noexcept {
  const float* __restrict src = resp.row(yy);
  if (nms == 2) {  // the default radius, unrolled (no inner loop: half the instructions without SIMD)
    for (int x = dx0; x < dx1; ++x) {
      const float m01 = src[x - 2] > src[x - 1] ? src[x - 2] : src[x - 1];
      const float m23 = src[x] > src[x + 1] ? src[x] : src[x + 1];
      const float m = m01 > m23 ? m01 : m23;
      dst[x] = m > src[x + 2] ? m : src[x + 2];
    }
    return;
  }
  for (int x = dx0; x < dx1; ++x) {
    float m = src[x - nms];
    for (int j = -nms + 1; j <= nms; ++j) m = src[x + j] > m ? src[x + j] : m;
    dst[x] = m;
  }
}

// The exact window check with the tie rule: (x, y) of value v is the maximum of its (2 nms + 1)^2 window,
// and the earlier pixel in raster order wins a tie.
bool strict_window_max(ConstImageViewF32 resp, int nms, int x, int y, float v) noexcept {
  for (int dy = -nms; dy <= nms; ++dy) {
    const float* nr = resp.row(y + dy);
    for (int dx = -nms; dx <= nms; ++dx) {
      if (dx == 0 && dy == 0) continue;
      const float nv = nr[x + dx];
      if (nv > v || (nv == v && (dy < 0 || (dy == 0 && dx < 0)))) return false;
    }
  }
  return true;
}

// The window check of a pixel known to be at least every value of its window (a finite response whose
// window maximum it equals): it fails only on a tie with an earlier pixel in raster order, so only the
// nms rows above and the nms pixels to its left are compared, for equality. The same answer as
// strict_window_max for such a pixel.
// v is above the threshold (> 0, not -0), so equal floats are equal bits: the compares are integer ones
// (no unordered case to test).
inline bool no_earlier_tie(ConstImageViewF32 resp, int nms, int x, int y, float v) noexcept {
  const std::int32_t vb = float_bits(&v);
  bool tie = false;
  for (int dy = -nms; dy < 0; ++dy) {
    const float* nr = resp.row(y + dy);
    for (int dx = -nms; dx <= nms; ++dx) tie |= float_bits(nr + x + dx) == vb;
  }
  const float* r0 = resp.row(y);
  for (int dx = -nms; dx < 0; ++dx) tie |= float_bits(r0 + x + dx) == vb;
  return !tie;
}

// The window check of a block's maximum (suppress_blocks; a finite response): the other pixels of its
// block [bx, xe) x [by, ye) (inside the window) are below it or equal and later in raster order, so they
// are skipped, and strict_window_max's tie rule is split by region: a neighbour before it in raster order
// fails it when >= v, one after it when > v. The same answer as strict_window_max for a block maximum.
inline bool block_max_wins(ConstImageViewF32 resp, int nms, int x, int y, std::int32_t vb, int bx, int xe, int by,
                           int ye) noexcept {
  // v > 0 (above the threshold) and the response has no NaN: r >= v and r > v are the same compares on
  // the integers of their bits (a negative r or -0 has negative bits).
  const int xa = x - nms, xb = x + nms;
  for (int yy = y - nms; yy <= y + nms; ++yy) {
    const float* __restrict r = resp.row(yy);
    const bool own = yy >= by && yy < ye;
    const int l1 = own ? bx : xb + 1;  // the columns checked: [xa, l1) and [r0, xb]
    const int r0 = own ? xe : xb + 1;
    // Before the maximum in raster order a tie fails it (>=), after it only a greater value (>): the
    // rows above, the left part of its own row; the rows below, the right part of its own row.
    const std::int32_t left_limit = yy <= y ? vb - 1 : vb, right_limit = yy < y ? vb - 1 : vb;
    for (int xx = xa; xx < l1; ++xx)
      if (float_bits(r + xx) > left_limit) return false;
    for (int xx = r0; xx <= xb; ++xx)
      if (float_bits(r + xx) > right_limit) return false;
  }
  return true;
}

// A corner at (x, y) of response v; its score normalised by *mean (when given and positive).
inline Corner make_corner(int x, int y, float v, const float* mean) noexcept {
  Corner c;
  c.x = static_cast<float>(x);
  c.y = static_cast<float>(y);
  c.response = v;
  c.level = 0;
  if (mean != nullptr) {
    const float d = *mean;
    c.score = d > 0.0f ? v / d : v;
  } else {
    c.score = v;
  }
  return c;
}

// Keeps the best cap corners in the min-heap heap[0..hn) (`better` is a total order on distinct
// pixels, so the corners kept do not depend on the order they are offered in, nor on how the heap
// arranges them); dropped: one was not. A corner better than the worst kept (heap[0]) replaces it and
// is sifted down in one pass (std::pop_heap + push_heap took two: the host's __adjust_heap was 8 % of
// the Harris samples).
// A Corner copied field by field: SPARC gcc copies the 20-byte struct with a call to memcpy (3.6 % of a
// leon3 Harris count).
inline void put(Corner& d, const Corner& s) noexcept {
  d.x = s.x;
  d.y = s.y;
  d.score = s.score;
  d.response = s.response;
  d.level = s.level;
}
inline void keep_best(const Corner& c, Corner* heap, std::size_t& hn, std::size_t cap, bool& dropped) noexcept {
  if (hn < cap) {  // sift up from the end (std::push_heap)
    std::size_t i = hn++;
    while (i > 0) {
      const std::size_t p = (i - 1) / 2;
      if (!better(heap[p], c)) break;  // the parent is not better: c (worse or equal) stays below it
      put(heap[i], heap[p]);
      i = p;
    }
    put(heap[i], c);
    return;
  }
  dropped = true;
  if (!better(c, heap[0])) return;
  std::size_t i = 0;
  for (;;) {
    std::size_t w = 2 * i + 1;  // the worse child (heap[0] is the worst kept)
    if (w >= hn) break;
    if (w + 1 < hn && better(heap[w], heap[w + 1])) ++w;
    if (!better(c, heap[w])) break;
    put(heap[i], heap[w]);
    i = w;
  }
  put(heap[i], c);
}

// Parabola through the 3x3 response around each corner: |offset| <= 0.5 px in x and y.
void refine_subpixel(ConstImageViewF32 resp, Corner* corners, std::size_t n) noexcept {
  for (std::size_t i = 0; i < n; ++i) {
    const int x = static_cast<int>(corners[i].x), y = static_cast<int>(corners[i].y);
    const float c0 = resp(x, y);
    const float l = resp(x - 1, y), rr = resp(x + 1, y), u = resp(x, y - 1), d = resp(x, y + 1);
    const float denx = l - 2.0f * c0 + rr, deny = u - 2.0f * c0 + d;
    float ox = denx < 0.0f ? 0.5f * (l - rr) / denx : 0.0f;
    float oy = deny < 0.0f ? 0.5f * (u - d) / deny : 0.0f;
    ox = std::min(0.5f, std::max(-0.5f, ox));
    oy = std::min(0.5f, std::max(-0.5f, oy));
    corners[i].x += ox;
    corners[i].y += oy;
  }
}

}  // namespace

Status HarrisDetector::check_input(int width, int height, std::size_t out_capacity) noexcept {
  if (!ready_) return Status(StatusCode::kNotReady, "harris: detect before init");
  if (width <= 0 || height <= 0) {
    counters_.increment(VisionCounter::kBadImage);
    return Status(StatusCode::kInvalidArgument, "harris: empty image");
  }
  if (width > config_.max_width || height > config_.max_height) {
    counters_.increment(VisionCounter::kBadImage);
    return Status(StatusCode::kInvalidArgument, "harris: image larger than configured");
  }
  if (out_capacity == 0) return Status(StatusCode::kCapacityExceeded, "harris: output has no capacity");
  return Status::ok();
}

template <typename Pixel>
void HarrisDetector::float_tensor_response(ImageView<const Pixel> image, RectI g, ImageViewF32 resp) noexcept {
  // Streaming structure tensor: a ring of 2r+1 product rows, then vertical + horizontal box sums.
  const int r = config_.block_radius;
  const int nrows = 2 * r + 1;
  const std::size_t wz = static_cast<std::size_t>(config_.max_width);
  float* gxr = grad_.data();
  float* gyr = grad_.data() + wz;
  float* csxx = colsum_.data();
  float* csyy = colsum_.data() + wz;
  float* csxy = colsum_.data() + 2 * wz;
  const int px0 = g.x - r, px1 = g.x + g.width + r;  // product columns needed
  const float k = config_.k;
  if constexpr (std::is_same<Pixel, std::uint8_t>::value) {
    if (!kHarrisIntegerTensor && r == 1 && simd_) {
      // 8-bit image, block radius 1, with SIMD: each ring slot holds its row's products already summed over
      // columns x-1..x+1 (from the gradient row, no product row), and the output sums the 3 slots: two
      // passes per row instead of four. gx = dx / 8 with |dx| <= 1020, so every product and partial sum
      // is an integer multiple of 1/64 below 2^24 / 64, exact in any order: the same floats as the passes
      // below (test Harris.VectorLoopsGiveTheSameCornersAsTheScalarLoops compares the response planes).
      for (int py = g.y - 1; py < g.y + g.height + 1; ++py) {
        const int slot = (py - (g.y - 1)) % 3;
        float* __restrict hxx = ring_.data() + static_cast<std::size_t>(3 * slot) * wz;
        float* __restrict hyy = hxx + wz;
        float* __restrict hxy = hyy + wz;
        sobel_row(image, py, px0, px1, gxr, gyr);
        const float* __restrict ax = gxr;
        const float* __restrict ay = gyr;
        for (int x = g.x; x < g.x + g.width; ++x) {
          const float a0 = ax[x - 1], a1 = ax[x], a2 = ax[x + 1], c0 = ay[x - 1], c1 = ay[x], c2 = ay[x + 1];
          hxx[x] = a0 * a0 + a1 * a1 + a2 * a2;
          hyy[x] = c0 * c0 + c1 * c1 + c2 * c2;
          hxy[x] = a0 * c0 + a1 * c1 + a2 * c2;
        }
        if (py < g.y + 1) continue;  // window not full yet
        const float* __restrict s0 = ring_.data();
        const float* __restrict s1 = s0 + 3 * wz;
        const float* __restrict s2 = s0 + 6 * wz;
        float* __restrict out_row = resp.row(py - 1);
        for (int x = g.x; x < g.x + g.width; ++x) {
          const float sxx = s0[x] + s1[x] + s2[x];
          const float syy = s0[wz + x] + s1[wz + x] + s2[wz + x];
          const float sxy = s0[2 * wz + x] + s1[2 * wz + x] + s2[2 * wz + x];
          const float tr = sxx + syy;
          out_row[x] = sxx * syy - sxy * sxy - k * tr * tr;
        }
      }
      return;
    }
  }
  for (int py = g.y - r; py < g.y + g.height + r; ++py) {
    const int slot = (py - (g.y - r)) % nrows;
    float* __restrict pxx = ring_.data() + static_cast<std::size_t>(3 * slot) * wz;
    float* __restrict pyy = pxx + wz;
    float* __restrict pxy = pyy + wz;
    sobel_row(image, py, px0, px1, gxr, gyr);
    for (int x = px0; x < px1; ++x) {
      const float a = gxr[x], c = gyr[x];
      pxx[x] = a * a;
      pyy[x] = c * c;
      pxy[x] = a * c;
    }
    if (py < g.y + r) continue;  // window not full yet
    const int y = py - r;
    // Vertical sums over the ring (all 2r+1 slots hold rows y-r..y+r).
    vertical_sums(ring_.data(), wz, nrows, px0, px1, csxx, csyy, csxy);
    float* __restrict out_row = resp.row(y);
    if (r == 1) {
      for (int x = g.x; x < g.x + g.width; ++x) {
        const float sxx = csxx[x - 1] + csxx[x] + csxx[x + 1];
        const float syy = csyy[x - 1] + csyy[x] + csyy[x + 1];
        const float sxy = csxy[x - 1] + csxy[x] + csxy[x + 1];
        const float tr = sxx + syy;
        out_row[x] = sxx * syy - sxy * sxy - k * tr * tr;
      }
    } else {
      for (int x = g.x; x < g.x + g.width; ++x) {
        float sxx = 0.0f, syy = 0.0f, sxy = 0.0f;
        for (int dx = -r; dx <= r; ++dx) {
          sxx += csxx[x + dx];
          syy += csyy[x + dx];
          sxy += csxy[x + dx];
        }
        const float tr = sxx + syy;
        out_row[x] = sxx * syy - sxy * sxy - k * tr * tr;
      }
    }
  }
}

float HarrisDetector::response_statistics(ConstImageViewF32 resp, RectI det, bool finite) noexcept {
  const int W = resp.width(), H = resp.height();
  const int cell = config_.norm_cell_px;
  const int cw = (W + cell - 1) / cell, ch = (H + cell - 1) / cell;
  float* csum = cells_.data();
  float* ccount = cells_.data() + static_cast<std::size_t>(cw) * static_cast<std::size_t>(ch);
  float* cmean = ccount + static_cast<std::size_t>(cw) * static_cast<std::size_t>(ch);
  const int ncell = cw * ch;
  for (int i = 0; i < ncell; ++i) csum[i] = ccount[i] = 0.0f;
  float rmax = 0.0f;
  double pos_sum = 0.0;
  // With SIMD, runs of 4 whole 16-pixel cells take cells16_x4 (the same sums; the max in a vector
  // folded into rmax at the end: the max of a set of non-NaN values and the +0 start, where a -0 never
  // replaces +0 and equal values are the same bits, so the order does not matter).
  F4 mv = {0.0f, 0.0f, 0.0f, 0.0f};
  const int xend = det.x + det.width;
  for (int y = det.y; y < det.y + det.height; ++y) {
    const float* row = resp.row(y);
    float* crow_sum = csum + (y / cell) * cw;
    float* crow_cnt = ccount + (y / cell) * cw;
    for (int x0 = det.x; x0 < xend;) {
      const int cx = x0 / cell;
      if (!kHarrisIntegerTensor && simd_) {
        if (cell == 16 && x0 == cx * 16 && x0 + 64 <= xend) {
          float s4[4];
          cells16_x4(row + x0, mv, s4);
          for (int c = 0; c < 4; ++c) {
            crow_sum[cx + c] += s4[c];
            crow_cnt[cx + c] += 16.0f;
            pos_sum += static_cast<double>(s4[c]);
          }
          x0 += 64;
          continue;
        }
      }
      const int x1 = std::min(det.x + det.width, (cx + 1) * cell);
      float s = 0.0f;
      max_and_positive_sum(row + x0, x1 - x0, rmax, s, simd_, finite);
      crow_sum[cx] += s;
      crow_cnt[cx] += static_cast<float>(x1 - x0);
      pos_sum += static_cast<double>(s);
      x0 = x1;
    }
  }
  if (!kHarrisIntegerTensor)
    for (int k = 0; k < 4; ++k) rmax = mv[k] > rmax ? mv[k] : rmax;
  const double area = static_cast<double>(det.width) * static_cast<double>(det.height);
  const float global_mean = static_cast<float>(pos_sum / area);
  const float floor_v = config_.norm_floor * global_mean;
  if (config_.normalise) {
    const int n = config_.norm_cells;
    for (int cy = 0; cy < ch; ++cy)
      for (int cx = 0; cx < cw; ++cx) {
        float s = 0.0f, c = 0.0f;
        for (int j = std::max(0, cy - n); j <= std::min(ch - 1, cy + n); ++j)
          for (int i = std::max(0, cx - n); i <= std::min(cw - 1, cx + n); ++i) {
            s += csum[j * cw + i];
            c += ccount[j * cw + i];
          }
        cmean[cy * cw + cx] = (c > 0.0f ? s / c : 0.0f) + floor_v;
      }
  }
  return rmax;
}

std::size_t HarrisDetector::suppress_and_keep(ConstImageViewF32 resp, RectI det, float thresh, std::size_t cap,
                                              bool finite, bool& dropped) noexcept {
  const int nms = config_.nms_radius;
  const std::size_t wz = static_cast<std::size_t>(config_.max_width);
  const int cell = config_.norm_cell_px;
  const int cw = (resp.width() + cell - 1) / cell, ch = (resp.height() + cell - 1) / cell;
  const float* cmean = cells_.data() + 2 * static_cast<std::size_t>(cw) * static_cast<std::size_t>(ch);
  Corner* heap = heap_.data();
  std::size_t hn = 0;
  dropped = false;
  auto keep = [&](int x, int y, float v) {
    keep_best(make_corner(x, y, v, config_.normalise ? cmean + (y / cell) * cw + (x / cell) : nullptr), heap, hn, cap,
              dropped);
  };
  // Non-maximum suppression: a separable max filter (row max over 2n+1 columns kept in a ring of
  // 2n+1 rows, then the max over the ring) finds pixels equal to their window maximum with
  // vectorisable loops; only those (and above the threshold) get the exact check with the tie rule.
  const int nwin = 2 * nms + 1;
  const int dx0 = det.x, dx1 = det.x + det.width;
  for (int yy = det.y - nms; yy < det.y + nms; ++yy)
    nms_row_max(resp, nms, yy, dx0, dx1, nms_ring_.data() + static_cast<std::size_t>((yy - (det.y - nms)) % nwin) * wz);
  for (int y = det.y; y < det.y + det.height; ++y) {
    nms_row_max(resp, nms, y + nms, dx0, dx1,
                nms_ring_.data() + static_cast<std::size_t>((y + nms - (det.y - nms)) % nwin) * wz);
    // The window maximum is the max over the ring of the row maxima; it is only needed where the pixel
    // is the maximum of its own row window (about one pixel in three), so it is taken there alone:
    // a third of the compares of a full column pass, the same candidates.
    const float* __restrict own = nms_ring_.data() + static_cast<std::size_t>((y - (det.y - nms)) % nwin) * wz;
    const float* row = resp.row(y);
    // With SIMD the full window maximum (max over the ring) is a few vector instructions per pixel, and
    // then only local maxima take a branch: the per-pixel compares and their mispredicted branches were
    // most of the host's Harris time. The same candidates either way (v < max of the ring <=> v below
    // one of its rows; own is one of them). The candidates of 16 pixels are one bit mask (the window
    // maximum and the tests in 4-lane vectors, bitwise selections: the scalar expressions' values), so
    // only the candidates take a branch; the last < 16 pixels take the scalar test.
    int x = dx0;
    if (!kHarrisIntegerTensor && simd_) {
      const float* __restrict r0 = nms_ring_.data();
      const F4 t4 = F4{thresh, thresh, thresh, thresh};
      const I4 w0 = {1, 2, 4, 8}, w1 = w0 << 4, w2 = w0 << 8, w3 = w0 << 12;
      const auto cand4 = [&](int xs) {
        F4 w = load4(r0 + xs);
        for (int j = 1; j < nwin; ++j) {
          const F4 rj = load4(r0 + static_cast<std::size_t>(j) * wz + static_cast<std::size_t>(xs));
          w = max4(rj, w);
        }
        const F4 v = load4(row + xs);
        return ~(v < w) & (v > t4);  // the scalar loop's !(v < wmax) && v > thresh
      };
      for (; x + 16 <= dx1; x += 16) {
        const I4 b = (cand4(x) & w0) | (cand4(x + 4) & w1) | (cand4(x + 8) & w2) | (cand4(x + 12) & w3);
        unsigned bits = static_cast<unsigned>(b[0] | b[1] | b[2] | b[3]);
        while (bits != 0) {
          const int xc = x + __builtin_ctz(bits);
          bits &= bits - 1;
          const float v = row[xc];
          // A finite response: v is at least every value of its window (the max over the ring), so
          // only a tie with an earlier pixel can fail the window check.
          if (finite ? no_earlier_tie(resp, nms, xc, y, v) : strict_window_max(resp, nms, xc, y, v)) keep(xc, y, v);
        }
      }
    }
    for (; x < dx1; ++x) {
      const float v = row[x];
      if (v < own[x] || !(v > thresh)) continue;
      bool below = false;
      for (int j = 0; j < nwin && !below; ++j) below = v < nms_ring_[static_cast<std::size_t>(j) * wz + static_cast<std::size_t>(x)];
      if (below) continue;
      if (!strict_window_max(resp, nms, x, y, v)) continue;
      keep(x, y, v);
    }
  }
  return hn;
}

std::size_t HarrisDetector::suppress_blocks(ConstImageViewF32 resp, RectI det, float thresh, std::size_t cap,
                                            bool& dropped) noexcept {
  const int nms = config_.nms_radius;
  const int side = nms + 1;
  const int cell = config_.norm_cell_px;
  const int cw = (resp.width() + cell - 1) / cell, ch = (resp.height() + cell - 1) / cell;
  const float* cmean = cells_.data() + 2 * static_cast<std::size_t>(cw) * static_cast<std::size_t>(ch);
  Corner* heap = heap_.data();
  std::size_t hn = 0;
  dropped = false;
  auto keep = [&](int x, int y, float v) {
    keep_best(make_corner(x, y, v, config_.normalise ? cmean + (y / cell) * cw + (x / cell) : nullptr), heap, hn, cap,
              dropped);
  };
  const int dx1 = det.x + det.width, dy1 = det.y + det.height;
  for (int by = det.y; by < dy1; by += side) {
    const int ye = std::min(by + side, dy1);
    for (int bx = det.x; bx < dx1; bx += side) {
      const int xe = std::min(bx + side, dx1);
      // The block's maximum, the earliest in raster order among equals: the only pixel of the block
      // that can be a maximum of its window (every other one is within nms of it and loses to it).
      // Compared as the integers of their bits (a finite response, see block_max_wins): where the
      // block's maximum is positive this is its position, earliest among equals; where it is not, the
      // value found is not above it either, and neither passes the threshold (>= 0).
      int wx = bx, wy = by;
      std::int32_t wb = float_bits(resp.row(by) + bx);
      for (int y = by; y < ye; ++y) {
        const float* __restrict row = resp.row(y);
        for (int x = bx; x < xe; ++x) {
          const std::int32_t b = float_bits(row + x);
          if (b > wb) {
            wb = b;
            wx = x;
            wy = y;
          }
        }
      }
      const float wv = resp.row(wy)[wx];
      if (!(wv > thresh) || !block_max_wins(resp, nms, wx, wy, wb, bx, xe, by, ye)) continue;
      keep(wx, wy, wv);
    }
  }
  return hn;
}

template <typename Pixel>
Status HarrisDetector::detect_impl(ImageView<const Pixel> image, RectI roi, BoundedVector<Corner>& out) noexcept {
  out.clear();
  last_response_ = ConstImageViewF32();
  const Status in = check_input(image.empty() ? 0 : image.width(), image.empty() ? 0 : image.height(), out.capacity());
  if (!in) return in;
  const int W = image.width(), H = image.height();
  const int r = config_.block_radius;
  const int nms = config_.nms_radius;
  const int b = config_.border_px;

  // Detection area: ROI clipped to the image minus the border.
  const RectI det = roi.intersect(RectI{b, b, W - 2 * b, H - 2 * b});
  if (roi.empty() || det.empty()) {
    if (roi.empty() || roi.intersect(RectI{0, 0, W, H}).empty()) {
      counters_.increment(VisionCounter::kBadRoi);
      return Status(StatusCode::kOutOfRange, "harris: region of interest empty or outside the image");
    }
    return Status::ok();  // ROI only covers the border: no corners, not an error
  }
  // Response area: detection area grown by the NMS radius (+1 for sub-pixel), clipped to where the
  // response is defined (gradient needs 1 px, the box r px).
  const int v0 = r + 1;
  const RectI valid{v0, v0, W - 2 * v0, H - 2 * v0};
  const RectI grown{det.x - nms - 1, det.y - nms - 1, det.width + 2 * nms + 2, det.height + 2 * nms + 2};
  const RectI g = grown.intersect(valid);
  const RectI gz = grown.intersect(RectI{0, 0, W, H});

  ImageViewF32 resp = ImageViewF32::unchecked(response_.data(), W, H, W);
  zero_undefined(resp, g, gz);
  bool integer_tensor = false;
  if constexpr (kHarrisIntegerTensor && std::is_same<Pixel, std::uint8_t>::value) {
    if (r == 1) integer_tensor = harris_response_u8_r1(image, g, config_.k, resp, ring_);  // g is 2 px inside (valid)
  }
  if (!integer_tensor) float_tensor_response(image, g, resp);
  last_response_ = ConstImageViewF32(resp);

  // Statistics over the detection area: max (threshold), positive sum (normalisation floor) and the
  // normalisation cell means; then NMS and the top-K heap.
  const float rmax = response_statistics(resp, det, std::is_same<Pixel, std::uint8_t>::value);
  const float thresh = std::max(config_.min_response, config_.quality_level * rmax);
  const std::size_t cap = std::min(static_cast<std::size_t>(config_.max_corners), out.capacity());
  bool dropped = false;
  // Without SIMD, on 8-bit images (a finite response), the block NMS; the same corners (see harris.hpp).
  const bool blocks = block_nms_ && std::is_same<Pixel, std::uint8_t>::value;
  const std::size_t hn =
      blocks ? suppress_blocks(resp, det, thresh, cap, dropped) : suppress_and_keep(resp, det, thresh, cap, std::is_same<Pixel, std::uint8_t>::value, dropped);
  if (dropped) counters_.increment(VisionCounter::kCornerCapReached);
  Corner* heap = heap_.data();
  std::sort(heap, heap + hn, better);
  if (config_.subpixel) refine_subpixel(resp, heap, hn);
  for (std::size_t i = 0; i < hn; ++i) QNAV_ASSERT(out.push_back(heap[i]).is_ok(), "harris: more corners kept than the output holds (hn <= capacity)");
  return Status::ok();
}

template Status HarrisDetector::detect_impl<std::uint8_t>(ImageView<const std::uint8_t>, RectI, BoundedVector<Corner>&) noexcept;
template Status HarrisDetector::detect_impl<float>(ImageView<const float>, RectI, BoundedVector<Corner>&) noexcept;

}  // namespace qnav::vision
