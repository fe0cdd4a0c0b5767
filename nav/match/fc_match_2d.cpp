#include "nav/match/fc_match_2d.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

namespace qnav::match {

float zncc_i8(const std::int8_t* a, const std::int8_t* b, std::size_t n) noexcept {
  std::int32_t sa = 0, sb = 0;
  for (std::size_t i = 0; i < n; ++i) {
    sa += a[i];
    sb += b[i];
  }
  std::int64_t saa = 0, sbb = 0, sab = 0;
  for (std::size_t i = 0; i < n; ++i) {
    saa += static_cast<std::int32_t>(a[i]) * a[i];
    sbb += static_cast<std::int32_t>(b[i]) * b[i];
    sab += static_cast<std::int32_t>(a[i]) * b[i];
  }
  const double nn = static_cast<double>(n);
  const double va = static_cast<double>(saa) - static_cast<double>(sa) * sa / nn;
  const double vb = static_cast<double>(sbb) - static_cast<double>(sb) * sb / nn;
  if (va <= 1e-9 || vb <= 1e-9) return 0.0f;
  const double cov = static_cast<double>(sab) - static_cast<double>(sa) * sb / nn;
  return static_cast<float>(cov / std::sqrt(va * vb));
}

namespace {
// The float just below x (std::nextafter(x, -inf)) from its bits: the freestanding LEON3 build's libm
// has no nextafterf. NaN and -inf are returned as they are.
inline float next_below(float x) noexcept {
  if (!(x == x) || x == -std::numeric_limits<float>::infinity()) return x;
  if (x == 0.0f) return -std::numeric_limits<float>::denorm_min();
  std::uint32_t bits;
  std::memcpy(&bits, &x, sizeof bits);
  bits = x > 0.0f ? bits - 1u : bits + 1u;
  std::memcpy(&x, &bits, sizeof x);
  return x;
}

#if defined(__SSE2__) || defined(__ARM_NEON)
constexpr bool kSimd = true;
#else
constexpr bool kSimd = false;
#endif

// The appearance pruning (the no-SIMD path for descriptors of kPrunedBytes): the first kHeadBytes terms
// of every dot product, the other kPrunedBytes - kHeadBytes only for pairs whose bound can pass.
constexpr std::size_t kPrunedBytes = 64;
constexpr std::size_t kHeadBytes = 52;

// Integer dot product of two widened descriptors: int16 x int16 summed in int32 (exact: |product| <=
// 2^14, at most a few hundred terms). The fixed-length form lets the compiler unroll and vectorise it
// (pmaddwd on x86, smlal on ARM). Without SIMD the kernels below are used instead.
template <std::size_t D>
inline std::int32_t dot_i16(const std::int16_t* a, const std::int16_t* b) noexcept {
  std::int32_t s = 0;
  for (std::size_t q = 0; q < D; ++q) s += static_cast<std::int32_t>(a[q]) * b[q];
  return s;
}

inline std::int32_t dot_i16(const std::int16_t* a, const std::int16_t* b, std::size_t d) noexcept {
  std::int32_t s = 0;
  for (std::size_t q = 0; q < d; ++q) s += static_cast<std::int32_t>(a[q]) * b[q];
  return s;
}

// Without SIMD (LEON3, armhf VFP): two rows of A against four consecutive rows of B in one pass over
// their first m terms, on the int8 descriptors themselves: per term 2 + 4 loads for 8 multiply-adds
// instead of 2 loads per multiply-add, the 8 sums held in registers (M, S > 0: the term count and B's
// row stride fixed, the row offsets immediates; 0: m and stride at run time). The same integer sums as
// dot_i16, term by term (exact). On LEON3 this shape counted fewest instructions of those tried
// (3 or 4 rows of A by 4 of B spill registers; unrolling the term loop adds spills around it).
template <std::size_t M, std::size_t S>
inline void dot_i8_2x4_terms(const std::int8_t* a0, const std::int8_t* a1, const std::int8_t* b, std::size_t m,
                             std::size_t stride, std::int32_t* r0, std::int32_t* r1) noexcept {
  const std::size_t n = M > 0 ? M : m;         // terms taken
  const std::size_t rs = S > 0 ? S : stride;   // B's row stride
  std::int32_t s00 = 0, s01 = 0, s02 = 0, s03 = 0, s10 = 0, s11 = 0, s12 = 0, s13 = 0;
  for (std::size_t q = 0; q < n; ++q) {
    const std::int32_t x0 = a0[q], x1 = a1[q];
    const std::int32_t y0 = b[q], y1 = b[rs + q], y2 = b[2 * rs + q], y3 = b[3 * rs + q];
    s00 += x0 * y0;
    s01 += x0 * y1;
    s02 += x0 * y2;
    s03 += x0 * y3;
    s10 += x1 * y0;
    s11 += x1 * y1;
    s12 += x1 * y2;
    s13 += x1 * y3;
  }
  r0[0] = s00;
  r0[1] = s01;
  r0[2] = s02;
  r0[3] = s03;
  r1[0] = s10;
  r1[1] = s11;
  r1[2] = s12;
  r1[3] = s13;
}

// All D terms (D > 0 fixed; D == 0: d at run time) of rows of length d.
template <std::size_t D>
inline void dot_i8_2x4(const std::int8_t* a0, const std::int8_t* a1, const std::int8_t* b, std::size_t d,
                       std::int32_t* r0, std::int32_t* r1) noexcept {
  dot_i8_2x4_terms<D, D>(a0, a1, b, d, d, r0, r1);
}

// Two rows of A against one row of B (the last nb % 4 rows).
template <std::size_t D>
inline void dot_i8_2x1(const std::int8_t* a0, const std::int8_t* a1, const std::int8_t* b, std::size_t d,
                       std::int32_t& r0, std::int32_t& r1) noexcept {
  const std::size_t n = D > 0 ? D : d;
  std::int32_t s0 = 0, s1 = 0;
  for (std::size_t q = 0; q < n; ++q) {
    const std::int32_t y = b[q];
    s0 += static_cast<std::int32_t>(a0[q]) * y;
    s1 += static_cast<std::int32_t>(a1[q]) * y;
  }
  r0 = s0;
  r1 = s1;
}

// The first M terms of the dot products of two rows of A with four consecutive rows of B (row stride
// S), for the pruned path below.
template <std::size_t M, std::size_t S>
inline void dot_i8_2x4_head(const std::int8_t* a0, const std::int8_t* a1, const std::int8_t* b, std::int32_t* r0,
                            std::int32_t* r1) noexcept {
  dot_i8_2x4_terms<M, S>(a0, a1, b, M, S, r0, r1);
}

// The dot product of n terms of two int8 rows (the pruned path's remaining terms of one pair).
template <std::size_t N>
inline std::int32_t dot_i8(const std::int8_t* x, const std::int8_t* y) noexcept {
  std::int32_t s = 0;
  for (std::size_t q = 0; q < N; ++q) s += static_cast<std::int32_t>(x[q]) * y[q];
  return s;
}

// The dot products of A's rows i0 and i1 (i1 may equal i0) with every row of B, into r0[0, nb) and r1[0, nb).
template <std::size_t D>
void dot_rows_2(const std::int8_t* a0, const std::int8_t* a1, const std::int8_t* b, std::size_t nb, std::size_t d,
                std::int32_t* r0, std::int32_t* r1) noexcept {
  const std::size_t n = D > 0 ? D : d;
  std::size_t j = 0;
  for (; j + 4 <= nb; j += 4) dot_i8_2x4<D>(a0, a1, b + j * n, d, r0 + j, r1 + j);
  for (; j < nb; ++j) dot_i8_2x1<D>(a0, a1, b + j * n, d, r0[j], r1[j]);
}

}  // namespace

std::size_t FcMatcher2d::arena_bytes(const FcMatch2dConfig& c) noexcept {
  const std::size_t nc = c.max_points * c.max_candidates_per_point;
  return nc * sizeof(Candidate) + (c.max_points + 1) * sizeof(std::uint32_t) + 3 * nc * sizeof(std::uint32_t) + nc * sizeof(Vec2d) + 4 * nc * sizeof(double) +
         2 * c.max_points + 4 * c.max_points * sizeof(float) + 2 * c.max_points * c.max_descriptor_bytes * sizeof(std::int16_t) +
         c.max_points * (2 * sizeof(std::int32_t) + 3 * sizeof(float)) + 12 * c.max_points * sizeof(float) +
         128;
}

Status FcMatcher2d::init(const FcMatch2dConfig& c, Arena& arena) noexcept {
  if (c.max_points == 0 || c.max_points > 65535 || c.max_candidates_per_point == 0 || c.max_candidates_per_point > 32 ||
      !(c.sigma_dist_m > 0.0) || !(c.sigma_dir_rad > 0.0) || !(c.appearance_weight >= 0.0f && c.appearance_weight <= 1.0f) ||
      !std::isfinite(c.min_appearance) || !std::isfinite(c.min_support) || c.max_descriptor_bytes == 0 ||
      c.max_descriptor_bytes > 4096)
    return Status(StatusCode::kInvalidArgument, "fc_match_2d: bad configuration");
  const std::size_t nc = c.max_points * c.max_candidates_per_point;
  cand_ = arena.allocate<Candidate>(nc);
  first_ = arena.allocate<std::uint32_t>(c.max_points + 1);
  order_ = arena.allocate<std::uint32_t>(nc);
  sorted_a_ = arena.allocate<std::uint32_t>(nc);
  near_ = arena.allocate<std::uint32_t>(nc);
  translation_ = arena.allocate<Vec2d>(nc);
  sorted_tx_ = arena.allocate<double>(nc);
  sorted_ty_ = arena.allocate<double>(nc);
  sorted_ax_ = arena.allocate<double>(nc);
  sorted_ay_ = arena.allocate<double>(nc);
  used_a_ = arena.allocate<std::uint8_t>(c.max_points);
  used_b_ = arena.allocate<std::uint8_t>(c.max_points);
  stats_a_ = arena.allocate<float>(2 * c.max_points);
  stats_b_ = arena.allocate<float>(2 * c.max_points);
  wide_a_ = arena.allocate<std::int16_t>(c.max_points * c.max_descriptor_bytes);
  wide_b_ = arena.allocate<std::int16_t>(c.max_points * c.max_descriptor_bytes);
  dot_row_ = arena.allocate<std::int32_t>(2 * c.max_points);
  z_row_ = arena.allocate<float>(c.max_points);
  sum_b_ = arena.allocate<float>(c.max_points);
  inv_b_ = arena.allocate<float>(c.max_points);
  bound_ = arena.allocate<float>(12 * c.max_points);
  if (cand_.empty() || first_.empty() || order_.empty() || sorted_a_.empty() || near_.empty() || translation_.empty() ||
      sorted_tx_.empty() || sorted_ty_.empty() || sorted_ax_.empty() || sorted_ay_.empty() || used_a_.empty() || used_b_.empty() || stats_a_.empty() || stats_b_.empty() ||
      wide_a_.empty() || wide_b_.empty() || dot_row_.empty() || z_row_.empty() || sum_b_.empty() || inv_b_.empty() || bound_.empty())
    return Status(StatusCode::kCapacityExceeded, "fc_match_2d: arena too small");
  config_ = c;
  ready_ = true;
  return Status::ok();
}

// Stage 1 of match(): the appearance candidates of each a in cand_, grouped by a, best first
// (insertion into a k-long list), first_[i] their start (first_[na] the end). Each descriptor's sum
// and 1/sqrt(n var) are computed once, so a pair costs one integer dot product. Returns their count.
std::size_t FcMatcher2d::appearance_candidates(const KeypointSet2d& a, const KeypointSet2d& b, std::size_t na,
                                               std::size_t nb) noexcept {
  const std::size_t k = config_.max_candidates_per_point;
  const std::size_t d = a.desc_bytes;
  // Without SIMD (or forced, for the tests): the int8 kernels, pruned for kPrunedBytes descriptors.
  const bool scalar = !kSimd || config_.force_scalar_kernels;
  if (scalar && d == kPrunedBytes) return appearance_pruned(a, b, na, nb);
  auto stats = [d](const std::int8_t* p, float* st) {
    std::int32_t s1 = 0, s2 = 0;
    for (std::size_t q = 0; q < d; ++q) {
      s1 += p[q];
      s2 += static_cast<std::int32_t>(p[q]) * p[q];
    }
    const double var = static_cast<double>(s2) - static_cast<double>(s1) * s1 / static_cast<double>(d);
    st[0] = static_cast<float>(s1);
    st[1] = var > 1e-9 ? static_cast<float>(1.0 / std::sqrt(var)) : 0.0f;
  };
  for (std::size_t i = 0; i < na; ++i) stats(a.descriptors.data() + i * d, stats_a_.data() + 2 * i);
  for (std::size_t j = 0; j < nb; ++j) stats(b.descriptors.data() + j * d, stats_b_.data() + 2 * j);
  if (!scalar) {
    for (std::size_t j = 0; j < nb; ++j) {  // for the row loop below, which vectorises
      sum_b_[j] = stats_b_[2 * j];
      inv_b_[j] = stats_b_[2 * j + 1];
    }
    for (std::size_t q = 0; q < na * d; ++q) wide_a_[q] = a.descriptors[q];
    for (std::size_t q = 0; q < nb * d; ++q) wide_b_[q] = b.descriptors[q];
  }
  const float inv_d = 1.0f / static_cast<float>(d);
  std::size_t nc = 0;
  std::size_t paired_row = na;  // scalar: the row of A whose dot products are in dot_row_'s second half (na: none)
  for (std::size_t i = 0; i < na; ++i) {
    first_[i] = static_cast<std::uint32_t>(nc);
    const float sa = stats_a_[2 * i], ia = stats_a_[2 * i + 1];
    if (ia == 0.0f) continue;  // a flat descriptor has no candidates
    std::size_t have = 0;
    Candidate* list = cand_.data() + nc;
    // b with appearance z joins a's k-long list, best first, when it clears min_appearance.
    const auto keep_best = [&](std::size_t j, float z) {
      if (!(z >= config_.min_appearance)) return;
      if (have == k && z <= list[k - 1].appearance) return;
      std::size_t pos = have < k ? have++ : k - 1;
      while (pos > 0 && list[pos - 1].appearance < z) {
        list[pos] = list[pos - 1];
        --pos;
      }
      list[pos] = Candidate{static_cast<std::uint16_t>(i), static_cast<std::uint16_t>(j), z, 0.0f};
    };
    if (!scalar) {
      // With SIMD: the row's dot products, then its ZNCCs, each in a loop without branches
      // (independent iterations the compiler pipelines or vectorises), then the selection: the same
      // float expression per pair as the loop below, so the same z.
      const std::int16_t* da = wide_a_.data() + i * d;
      std::int32_t* dots = dot_row_.data();
      if (d == 64) {
        for (std::size_t j = 0; j < nb; ++j) dots[j] = dot_i16<64>(da, wide_b_.data() + j * 64);
      } else {
        for (std::size_t j = 0; j < nb; ++j) dots[j] = dot_i16(da, wide_b_.data() + j * d, d);
      }
      float* zs = z_row_.data();
      const float* sum_b = sum_b_.data();
      const float* inv_b = inv_b_.data();
      for (std::size_t j = 0; j < nb; ++j) {
        const float z = (static_cast<float>(dots[j]) - sa * sum_b[j] * inv_d) * ia * inv_b[j];
        zs[j] = inv_b[j] == 0.0f ? -std::numeric_limits<float>::infinity() : z;  // a flat b is no candidate
      }
      for (std::size_t j = 0; j < nb; ++j) keep_best(j, zs[j]);
    } else {
      // Without SIMD: the dot products of rows i and i + 1 are taken together (dot_rows_2, on the int8
      // descriptors) when row i's are not already in dot_row_'s second half; then the selection in b
      // order with the same float expression per pair as before, so the same z.
      const std::int32_t* rows = dot_row_.data() + config_.max_points;  // row i + 1's, taken with row i's
      if (paired_row != i) {
        std::int32_t* r0 = dot_row_.data();
        const std::int8_t* a0 = a.descriptors.data() + i * d;
        const bool pair = i + 1 < na;
        const std::int8_t* a1 = pair ? a0 + d : a0;
        dot_rows_2<0>(a0, a1, b.descriptors.data(), nb, d, r0, r0 + config_.max_points);  // d != 64 (64: appearance_pruned)
        paired_row = pair ? i + 1 : na;
        rows = r0;
      }
      for (std::size_t j = 0; j < nb; ++j) {
        const float ib = stats_b_[2 * j + 1];
        if (ib == 0.0f) continue;
        keep_best(j, (static_cast<float>(rows[j]) - sa * stats_b_[2 * j] * inv_d) * ia * ib);
      }
    }
    nc += have;
  }
  first_[na] = static_cast<std::uint32_t>(nc);
  return nc;
}

// appearance_candidates() without SIMD for kPrunedBytes descriptors: the same stats_a_ / stats_b_ and
// the same candidate lists, bit for bit. A pair (a, b) joins a's list only if its z (the float
// expression below, monotonic in the integer dot product) clears min_appearance and, once the list is
// full, its last entry. Rows i and i + 1 of A are taken against four rows of B at a time over the
// first kHeadBytes terms (p, exact). On the other r = kPrunedBytes - kHeadBytes terms (sums s_r,
// centred norms c_r = |x_r - mean(x_r)|), Cauchy-Schwarz bounds the rest of the dot product by
// c_ra c_rb + s_ra s_rb / r, so with i = 1 / sqrt(n var) and s the whole sums,
//   z <= U = p ia ib - (sa ia / 8) (sb ib / 8) + (s_ra ia / 4) (s_rb ib / 4) + (c_ra ia) (c_rb ib) + margin,
// margin = 2^-12 (1 + max_A g_a g_b), g = i |x| >= 1: every term of U and z is at most g_a g_b in
// size, so their float rounding stays below 2^-18 (1 + g_a g_b). A pair whose U cannot join is
// dropped; else its remaining terms are added and z is computed as in the unpruned path. Each row's
// list sees the pairs in b order as before (row i + 1's is kept aside until row i's is complete).
std::size_t FcMatcher2d::appearance_pruned(const KeypointSet2d& a, const KeypointSet2d& b, std::size_t na,
                                           std::size_t nb) noexcept {
  constexpr std::size_t d = kPrunedBytes, h = kHeadBytes;
  const std::size_t k = config_.max_candidates_per_point;
  const float inv_d = 1.0f / static_cast<float>(d);
  const float min_app = config_.min_appearance;
  const float inf = std::numeric_limits<float>::infinity();
  // One pass per descriptor: stats as appearance_candidates() computes them (the same integer sums),
  // and the bound's factors: f[0] = i, f[1] = s i / 8, f[2] = s_r i / 4, f[3] = c_r i; returns g.
  const auto factors = [](const std::int8_t* p, float* st, float* f) {
    std::int32_t s1 = 0, s2 = 0, r1 = 0, r2 = 0;
    for (std::size_t q = 0; q < h; ++q) {
      s1 += p[q];
      s2 += static_cast<std::int32_t>(p[q]) * p[q];
    }
    for (std::size_t q = h; q < d; ++q) {
      r1 += p[q];
      r2 += static_cast<std::int32_t>(p[q]) * p[q];
    }
    s1 += r1;
    s2 += r2;
    const double var = static_cast<double>(s2) - static_cast<double>(s1) * s1 / static_cast<double>(d);
    st[0] = static_cast<float>(s1);
    st[1] = var > 1e-9 ? static_cast<float>(1.0 / std::sqrt(var)) : 0.0f;
    const double i = static_cast<double>(st[1]);
    const double cr2 = static_cast<double>(r2) - static_cast<double>(r1) * r1 / static_cast<double>(d - h);
    f[0] = st[1];
    f[1] = static_cast<float>(s1 * i * 0.125);
    f[2] = static_cast<float>(r1 * i / std::sqrt(static_cast<double>(d - h)));
    f[3] = static_cast<float>(std::sqrt(cr2 > 0.0 ? cr2 : 0.0) * i);
    return std::sqrt(static_cast<double>(s2)) * i;
  };
  static_assert(d == 64, "the bound's factor 1/8 is 1/sqrt(d)");
  float* fa = bound_.data();                     // per a: 4 factors
  float* fb = bound_.data() + 4 * config_.max_points;  // per b: 4 factors, then its constant term
  double max_ga = 0.0;
  for (std::size_t i = 0; i < na; ++i) max_ga = std::max(max_ga, factors(a.descriptors.data() + i * d, stats_a_.data() + 2 * i, fa + 4 * i));
  for (std::size_t j = 0; j < nb; ++j) {
    const double g = factors(b.descriptors.data() + j * d, stats_b_.data() + 2 * j, fb + 8 * j);
    fb[8 * j + 4] = fb[8 * j] == 0.0f ? -inf : static_cast<float>(0x1p-12 * (1.0 + max_ga * g));  // a flat b: U = -inf
  }
  // Row state; cut: a pair can join only if its z > cut (before the list is full: the float just
  // below min_appearance, so z > cut is z >= min_appearance; then the list's last z). A flat row's
  // cut is +inf.
  const float open_cut = next_below(min_app);
  struct Row {
    const std::int8_t* x;
    Candidate* list;
    std::size_t have;
    std::uint16_t index;
    float sa, ia;
  };
  // The pair passed its bound: its remaining terms, its z as in the unpruned path, the list
  // insertion; returns the row's new cut. Kept out of line (most pairs do not get here).
  const auto finish = [&](Row& r, std::size_t j, std::int32_t p) __attribute__((noinline)) -> float {
    const std::int32_t dot = p + dot_i8<d - h>(r.x + h, b.descriptors.data() + j * d + h);
    const float ib = stats_b_[2 * j + 1];
    const float z = (static_cast<float>(dot) - r.sa * stats_b_[2 * j] * inv_d) * r.ia * ib;
    if (z >= min_app && !(r.have == k && z <= r.list[k - 1].appearance)) {
      std::size_t pos = r.have < k ? r.have++ : k - 1;
      while (pos > 0 && r.list[pos - 1].appearance < z) {
        r.list[pos] = r.list[pos - 1];
        --pos;
      }
      r.list[pos] = Candidate{r.index, static_cast<std::uint16_t>(j), z, 0.0f};
    }
    return r.have == k ? r.list[k - 1].appearance : open_cut;
  };
  const auto bound = [](std::int32_t p, const float* x, const float* y) {
    return (((static_cast<float>(p) * x[0] * y[0] - x[1] * y[1]) + x[2] * y[2]) + x[3] * y[3]) + y[4];
  };
  Candidate spare[32];  // row i + 1's list while row i's is built (k <= 32, init())
  std::int32_t head0[4], head1[4];
  std::size_t nc = 0;
  for (std::size_t i = 0; i < na; i += 2) {
    const bool pair = i + 1 < na;
    const std::int8_t* a0 = a.descriptors.data() + i * d;
    const std::int8_t* a1 = pair ? a0 + d : a0;
    Row r0{a0, cand_.data() + nc, 0, static_cast<std::uint16_t>(i), stats_a_[2 * i], stats_a_[2 * i + 1]};
    Row r1{a1, spare, 0, static_cast<std::uint16_t>(i + 1), pair ? stats_a_[2 * i + 2] : 0.0f, pair ? stats_a_[2 * i + 3] : 0.0f};
    const float* x0 = fa + 4 * i;
    const float* x1 = pair ? x0 + 4 : x0;
    float cut0 = r0.ia != 0.0f ? open_cut : inf, cut1 = r1.ia != 0.0f ? open_cut : inf;  // flat rows: no candidates
    if (cut0 != inf || cut1 != inf) {
      std::size_t j = 0;
      for (; j + 4 <= nb; j += 4) {
        dot_i8_2x4_head<h, d>(a0, a1, b.descriptors.data() + j * d, head0, head1);
        for (std::size_t t = 0; t < 4; ++t) {
          const float* y = fb + 8 * (j + t);
          if (bound(head0[t], x0, y) > cut0) cut0 = finish(r0, j + t, head0[t]);
          if (bound(head1[t], x1, y) > cut1) cut1 = finish(r1, j + t, head1[t]);
        }
      }
      for (; j < nb; ++j) {
        const std::int8_t* yb = b.descriptors.data() + j * d;
        const std::int32_t p0 = dot_i8<h>(a0, yb), p1 = dot_i8<h>(a1, yb);
        const float* y = fb + 8 * j;
        if (bound(p0, x0, y) > cut0) cut0 = finish(r0, j, p0);
        if (bound(p1, x1, y) > cut1) cut1 = finish(r1, j, p1);
      }
    }
    first_[i] = static_cast<std::uint32_t>(nc);
    nc += r0.have;
    if (pair) {
      first_[i + 1] = static_cast<std::uint32_t>(nc);
      for (std::size_t q = 0; q < r1.have; ++q) cand_[nc + q] = spare[q];
      nc += r1.have;
    }
  }
  first_[na] = static_cast<std::uint32_t>(nc);
  return nc;
}

// The radius in implied translation t within which two candidates can pass the gate (at the longest
// baseline in A, with a margin over rounding), and the largest coordinate of any finite position.
void FcMatcher2d::translation_gate(const KeypointSet2d& a, const KeypointSet2d& b, std::size_t na, std::size_t nb,
                                   double& gate_radius_m, double& abs_max_m) const noexcept {
  double xmin = 1e300, xmax = -1e300, ymin = 1e300, ymax = -1e300;
  for (std::size_t i = 0; i < na; ++i) {
    const Vec2d p = a.position_m[i];
    if (!std::isfinite(p.x()) || !std::isfinite(p.y())) continue;  // its pairs score 0 (NaN arithmetic)
    xmin = std::min(xmin, p.x());
    xmax = std::max(xmax, p.x());
    ymin = std::min(ymin, p.y());
    ymax = std::max(ymax, p.y());
    abs_max_m = std::max(abs_max_m, std::max(std::abs(p.x()), std::abs(p.y())));
  }
  for (std::size_t j = 0; j < nb; ++j) {
    const Vec2d p = b.position_m[j];
    if (std::isfinite(p.x()) && std::isfinite(p.y())) abs_max_m = std::max(abs_max_m, std::max(std::abs(p.x()), std::abs(p.y())));
  }
  const double la_max = xmax >= xmin ? std::sqrt((xmax - xmin) * (xmax - xmin) + (ymax - ymin) * (ymax - ymin)) : 0.0;
  // gate2 = 27.6 (sd^2 + la^2 sphi^2) and la sphi = sigma_dir la + sd grows with la.
  const double ls = config_.sigma_dir_rad * la_max + config_.sigma_dist_m;
  const double gate2_max = 2.0 * 13.8 * (config_.sigma_dist_m * config_.sigma_dist_m + ls * ls);
  gate_radius_m = std::sqrt(gate2_max) * (1.0 + 1e-9) + 1e-9 * (1.0 + 4.0 * abs_max_m);
}

Status FcMatcher2d::match(const KeypointSet2d& a, const KeypointSet2d& b, double dtheta_rad,
                          BoundedVector<Match2d>& out) noexcept {
  out.clear();
  if (!ready_) return Status(StatusCode::kNotReady, "fc_match_2d: not initialised");
  if (!std::isfinite(dtheta_rad) || a.desc_bytes == 0 || a.desc_bytes != b.desc_bytes || a.desc_bytes > config_.max_descriptor_bytes ||
      a.descriptors.size() < a.position_m.size() * a.desc_bytes || b.descriptors.size() < b.position_m.size() * b.desc_bytes) {
    counters_.increment(FcMatchCounter::kBadInput);
    return Status(StatusCode::kInvalidArgument, "fc_match_2d: inconsistent keypoint sets");
  }
  std::size_t na = a.position_m.size(), nb = b.position_m.size();
  if (na > config_.max_points) {
    counters_.increment(FcMatchCounter::kPointsIgnored, static_cast<std::uint32_t>(na - config_.max_points));
    na = config_.max_points;
  }
  if (nb > config_.max_points) {
    counters_.increment(FcMatchCounter::kPointsIgnored, static_cast<std::uint32_t>(nb - config_.max_points));
    nb = config_.max_points;
  }
  if (na < 2 || nb < 2) return Status::ok();

  // 1. Appearance candidates, grouped by a, best first.
  const std::size_t nc = appearance_candidates(a, b, na, nb);
  if (nc == 0) return Status::ok();

  // 2. Continuous geometric score. A pair of candidates c = (a, b), c2 = (a', b') passes the gate below
  //    only when |(b' - b) - R(a' - a)| is small, i.e. when their implied translations t = b - R a
  //    are close: |t(c2) - t(c)| <= the gate's largest radius (at the longest baseline in A). So
  //    candidates are sorted by t.x, and each c visits only the c2 within that radius in t (a
  //    conservative prefilter with a margin over rounding: every pair the gate would pass is
  //    visited), grouped by a' in increasing order, with the original per-pair arithmetic. A pair the
  //    prefilter drops contributes 0 to the sum, so the scores are the same as visiting every a'.
  const Mat2d r = Pose2{0.0, 0.0, dtheta_rad}.rotation();
  const double inv2sd = 1.0 / (2.0 * config_.sigma_dist_m * config_.sigma_dist_m);
  const float w = config_.appearance_weight;
  double gate_radius_m = 0.0, abs_max_m = 0.0;
  translation_gate(a, b, na, nb, gate_radius_m, abs_max_m);
  for (std::size_t c = 0; c < nc; ++c) {
    translation_[c] = b.position_m[cand_[c].b] - r * a.position_m[cand_[c].a];
    order_[c] = static_cast<std::uint32_t>(c);
  }
  std::sort(order_.begin(), order_.begin() + nc, [this](std::uint32_t x, std::uint32_t y) {
    if (translation_[x].x() != translation_[y].x()) return translation_[x].x() < translation_[y].x();
    return x < y;
  });
  for (std::size_t o = 0; o < nc; ++o) {
    const std::uint32_t c = order_[o];
    const std::uint32_t ai = cand_[c].a;
    sorted_tx_[o] = translation_[c].x();
    sorted_ty_[o] = translation_[c].y();
    sorted_ax_[o] = a.position_m[ai].x();
    sorted_ay_[o] = a.position_m[ai].y();
    sorted_a_[o] = ai;
  }
  const double gr2 = gate_radius_m * gate_radius_m;
  // Per pair, with la^2 = |a' - a|^2 (no square root): gate2 <= 27.6 (3 sd^2 + 2 sigma_dir^2 la^2),
  // as (sigma_dir la + sd)^2 <= 2 sigma_dir^2 la^2 + 2 sd^2; with a relative and an absolute margin
  // over the rounding of t and of gate2 (positions are at most abs_max_m from the origin).
  const double sd2 = config_.sigma_dist_m * config_.sigma_dist_m;
  const double pair_c0 = 2.0 * 13.8 * 3.0 * sd2 * (1.0 + 1e-9);
  const double pair_c1 = 2.0 * 13.8 * 2.0 * config_.sigma_dir_rad * config_.sigma_dir_rad * (1.0 + 1e-9);
  const double pair_margin = 1e-9 * (1.0 + abs_max_m) * (1.0 + abs_max_m);
  // Candidates are scored in translation order (each score depends only on its own candidate), so
  // the window of candidates within gate_radius_m in t.x moves one way: [lo, hi) by two pointers (a
  // correctly rounded difference is monotonic in its operands, so the window is the same contiguous
  // run the per-candidate scan found). The window is streamed from the sorted arrays with a
  // branch-free compaction; the scoring below reads the neighbours in candidate order as before.
  std::size_t lo = 0, hi = 0;
  for (std::size_t rc = 0; rc < nc; ++rc) {
    const std::uint32_t c = order_[rc];
    Candidate& cc = cand_[c];
    const std::size_t i = cc.a;
    const double tcx = sorted_tx_[rc], tcy = sorted_ty_[rc];
    const double pix = sorted_ax_[rc], piy = sorted_ay_[rc];
    while (lo < rc && !(tcx - sorted_tx_[lo] <= gate_radius_m)) ++lo;
    if (hi < rc + 1) hi = rc + 1;
    while (hi < nc && sorted_tx_[hi] - tcx <= gate_radius_m) ++hi;
    std::size_t nn = 0;
    for (std::size_t o = lo; o < hi; ++o) {
      const double dx = sorted_tx_[o] - tcx, dy = sorted_ty_[o] - tcy;
      const double dt2 = dx * dx + dy * dy;
      const double ex = sorted_ax_[o] - pix, ey = sorted_ay_[o] - piy;
      const double la2 = ex * ex + ey * ey;
      const bool keep = (dt2 <= gr2) & (dt2 <= pair_c0 + pair_c1 * la2 + pair_margin) & (sorted_a_[o] != i);
      near_[nn] = order_[o];
      nn += keep ? 1u : 0u;
    }
    std::sort(near_.begin(), near_.begin() + nn);
    double acc = 0.0;
    const Vec2d pa = a.position_m[i];
    const Vec2d pb = b.position_m[cc.b];
    for (std::size_t g = 0; g < nn;) {
      const std::size_t i2 = cand_[near_[g]].a;
      std::size_t g1 = g + 1;
      while (g1 < nn && cand_[near_[g1]].a == i2) ++g1;
      const Vec2d va = r * (a.position_m[i2] - pa);
      const double la = va.norm();
      if (la < 1e-9) {
        g = g1;
        continue;
      }
      const double sphi = config_.sigma_dir_rad + config_.sigma_dist_m / la;
      const double inv2sp = 1.0 / (2.0 * sphi * sphi);
      // Gate: f >= 1e-3 needs dd^2 < 13.8 sd^2 and phi^2 < 13.8 sphi^2, so |vb - va|^2 (~ dd^2 +
      // (la phi)^2) stays below 13.8 (sd^2 + la^2 sphi^2); x2 margin for the small-angle form.
      const double gate2 = 2.0 * 13.8 * (config_.sigma_dist_m * config_.sigma_dist_m + la * la * sphi * sphi);
      double best = 0.0;
      for (; g < g1; ++g) {
        const std::uint32_t c2 = near_[g];
        if (cand_[c2].b == cc.b) continue;
        const Vec2d vb = b.position_m[cand_[c2].b] - pb;
        if ((vb - va).squaredNorm() > gate2) continue;
        const double lb = vb.norm();
        const double dd = la - lb;
        const double ed = dd * dd * inv2sd;
        if (ed > 4.5 || lb < 1e-9) continue;  // beyond 3 sigma
        const double cosphi = va.dot(vb) / (la * lb);
        if (cosphi <= 0.0) continue;  // directions disagree by more than 90 degrees
        const double phi2 = 2.0 * (1.0 - cosphi);  // ~ phi^2 for small phi
        const double e = ed + phi2 * inv2sp;
        if (e > 6.9) continue;  // f < 1e-3
        const double f = std::exp(-e);
        if (f > best) best = f;
      }
      acc += best;
    }
    cc.score = static_cast<float>(acc) * ((1.0f - w) + w * std::max(0.0f, cc.appearance));
  }

  // 3. Greedy one-to-one selection.
  for (std::size_t c = 0; c < nc; ++c) order_[c] = static_cast<std::uint32_t>(c);
  std::sort(order_.begin(), order_.begin() + nc, [this](std::uint32_t x, std::uint32_t y) {
    if (cand_[x].score != cand_[y].score) return cand_[x].score > cand_[y].score;
    return x < y;
  });
  for (std::size_t i = 0; i < na; ++i) used_a_[i] = 0;
  for (std::size_t j = 0; j < nb; ++j) used_b_[j] = 0;
  for (std::size_t o = 0; o < nc; ++o) {
    const Candidate& cc = cand_[order_[o]];
    if (cc.score < config_.min_support) break;
    if (used_a_[cc.a] || used_b_[cc.b]) continue;
    if (!out.push_back(Match2d{cc.a, cc.b, cc.score, cc.appearance})) break;
    used_a_[cc.a] = 1;
    used_b_[cc.b] = 1;
  }
  return Status::ok();
}

}  // namespace qnav::match
