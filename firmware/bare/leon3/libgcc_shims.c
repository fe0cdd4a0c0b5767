/* libgcc_shims.c: the few compiler-support routines the link needs (64-bit integer division,
 * 64-bit <-> floating conversions, clz). Debian's 32-bit sparc libgcc.a is V8+ code (it uses V9
 * instructions), so it cannot be linked into a LEON3 image. Written with 32-bit operations only and
 * compiled with -fno-builtin, so gcc cannot turn them back into calls to themselves. Conversions are
 * correctly rounded (the same result as a hardware conversion on the host), see the comments. */
#include <stdint.h>

int __clzsi2(uint32_t x) {
  int n = 0;
  if (x == 0) return 32;
  if ((x & 0xffff0000u) == 0) { n += 16; x <<= 16; }
  if ((x & 0xff000000u) == 0) { n += 8; x <<= 8; }
  if ((x & 0xf0000000u) == 0) { n += 4; x <<= 4; }
  if ((x & 0xc0000000u) == 0) { n += 2; x <<= 2; }
  if ((x & 0x80000000u) == 0) { n += 1; }
  return n;
}

int __clzdi2(uint64_t x) {
  const uint32_t hi = (uint32_t)(x >> 32);
  return hi != 0 ? __clzsi2(hi) : 32 + __clzsi2((uint32_t)x);
}

/* Shift-subtract long division; the 32-bit case uses the hardware udiv. */
uint64_t __udivmoddi4(uint64_t n, uint64_t d, uint64_t* rem) {
  if ((n >> 32) == 0 && (d >> 32) == 0) {
    const uint32_t n32 = (uint32_t)n, d32 = (uint32_t)d;
    if (rem) *rem = n32 % d32;
    return n32 / d32;
  }
  uint64_t q = 0, r = 0;
  for (int i = 63; i >= 0; --i) {
    r = (r << 1) | ((n >> i) & 1u);
    if (r >= d) {
      r -= d;
      q |= (uint64_t)1 << i;
    }
  }
  if (rem) *rem = r;
  return q;
}
uint64_t __udivdi3(uint64_t n, uint64_t d) { return __udivmoddi4(n, d, 0); }
uint64_t __umoddi3(uint64_t n, uint64_t d) {
  uint64_t r;
  (void)__udivmoddi4(n, d, &r);
  return r;
}
int64_t __divdi3(int64_t a, int64_t b) {
  const int neg = (a < 0) != (b < 0);
  const uint64_t q = __udivmoddi4(a < 0 ? 0 - (uint64_t)a : (uint64_t)a, b < 0 ? 0 - (uint64_t)b : (uint64_t)b, 0);
  return neg ? (int64_t)(0 - q) : (int64_t)q;
}
int64_t __moddi3(int64_t a, int64_t b) {
  uint64_t r;
  (void)__udivmoddi4(a < 0 ? 0 - (uint64_t)a : (uint64_t)a, b < 0 ? 0 - (uint64_t)b : (uint64_t)b, &r);
  return a < 0 ? (int64_t)(0 - r) : (int64_t)r;
}

/* uint32 -> double, exact (fitod takes a signed 32-bit integer). */
static double u32_to_double(uint32_t u) { return (double)(int32_t)(u >> 1) * 2.0 + (double)(int32_t)(u & 1u); }

/* int64 -> double: hi * 2^32 is exact, lo is exact, so the one rounding of the sum is the correctly
 * rounded conversion. */
double __floatdidf(int64_t x) {
  return (double)(int32_t)(x >> 32) * 4294967296.0 + u32_to_double((uint32_t)x);
}
double __floatundidf(uint64_t x) {
  return u32_to_double((uint32_t)(x >> 32)) * 4294967296.0 + u32_to_double((uint32_t)x);
}

/* int64 -> float: keep 53 bits with a sticky bit (exact in a double), then one rounding to float. */
static float u64_to_float(uint64_t u) {
  if ((u >> 53) == 0) return (float)__floatundidf(u);
  const uint64_t kept = (u >> 11) | ((u & 0x7ffu) != 0);
  return (float)(__floatundidf(kept) * 2048.0);
}
float __floatdisf(int64_t x) { return x < 0 ? -u64_to_float(0 - (uint64_t)x) : u64_to_float((uint64_t)x); }
float __floatundisf(uint64_t x) { return u64_to_float(x); }

/* double -> int64 / uint64, truncating (values outside the range saturate; C leaves them undefined). */
static uint64_t trunc_to_u64(double t) { /* 0 <= t < 2^64 */
  if (t >= 18446744073709551616.0) return ~(uint64_t)0;
  const double hi_d = t * (1.0 / 4294967296.0);
  uint32_t hi;
  if (hi_d >= 2147483648.0) hi = (uint32_t)(int32_t)(hi_d - 2147483648.0) + 0x80000000u;
  else hi = (uint32_t)(int32_t)hi_d;
  double lo_d = t - u32_to_double(hi) * 4294967296.0; /* exact, in [0, 2^32) */
  uint32_t lo;
  if (lo_d >= 2147483648.0) lo = (uint32_t)(int32_t)(lo_d - 2147483648.0) + 0x80000000u;
  else lo = (uint32_t)(int32_t)lo_d;
  return ((uint64_t)hi << 32) | lo;
}
int64_t __fixdfdi(double d) {
  if (d != d) return 0;
  if (d >= 9223372036854775808.0) return INT64_MAX;
  if (d <= -9223372036854775808.0) return INT64_MIN;
  return d < 0 ? (int64_t)(0 - trunc_to_u64(-d)) : (int64_t)trunc_to_u64(d);
}
uint64_t __fixunsdfdi(double d) {
  if (!(d > 0)) return 0;
  return trunc_to_u64(d);
}
int64_t __fixsfdi(float f) { return __fixdfdi((double)f); }
uint64_t __fixunssfdi(float f) { return __fixunsdfdi((double)f); }
