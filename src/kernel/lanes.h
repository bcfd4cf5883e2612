/* Lane types: what the generic code (shading kernel, shapes, sampler, fast
 * math) computes on. Internal to the library.
 *
 * A generic file is a template written once with the names WV_L (the shading
 * real), WV_P (positions), WV_M (masks), WV_I (integers), WV_U (64-bit hashes),
 * WV_R (the scalar real of constants and parameters) and WV_FN(name) (the
 * instance's function name), and included once per lane flavour between
 * kernel/lane_begin.h and kernel/lane_end.h:
 *   WV_LANE_F  one float        (reference paths, tests, single points)   name_f
 *   WV_LANE_8  eight floats     (rendering; GCC vector extensions)        name_8
 *   WV_LANE_D  one double, positions in float (gradient checks)           name_d
 * Arithmetic is written with the ordinary operators, which GCC's vector
 * extensions define lane by lane (a scalar operand is broadcast). What the
 * operators cannot express (a select, a square root, a floor, a table lookup)
 * is one primitive below, with one implementation per type and a _Generic
 * front end, so the template calls wv_sel(m, a, b) whatever the lane type.
 *
 * Integer front ends send every scalar type to the scalar form ("default":
 * uint64_t and the unsigned long long of a ULL constant are different types).
 * Masks are int 0/1 in scalar flavours and int32 lanes of 0/-1 in vector ones;
 * combine them only with &, | and wv_not. IEEE +, -, *, / and sqrt round the
 * same in a vector lane as in a scalar register, and the build keeps
 * -ffp-contract=off (ISO C mode), so every flavour of a template gives
 * bit-identical float results. */
#ifndef WOVEN_LANES_H
#define WOVEN_LANES_H

#include <math.h>
#include <stdint.h>
#include <string.h>

#include "util/hash.h"

/* Helpers take and return vectors by value; they are always inlined, so the
 * note that such an ABI differs between targets does not apply. */
#pragma GCC diagnostic ignored "-Wpsabi"

#define WV_LANES 8
typedef float wv_f8 __attribute__((vector_size(4 * WV_LANES)));
typedef int32_t wv_i8 __attribute__((vector_size(4 * WV_LANES)));
typedef int64_t wv_l8 __attribute__((vector_size(8 * WV_LANES)));
typedef uint64_t wv_q8 __attribute__((vector_size(8 * WV_LANES)));
typedef uint32_t wv_w8 __attribute__((vector_size(4 * WV_LANES)));

#define WV_INLINE static inline __attribute__((always_inline))

/* Functions that run the 8-wide code are compiled in several versions
 * (target_clones): AVX-512 (64-bit multiplies for the hashes in one
 * instruction), AVX2, and plain x86-64, chosen when the program loads.
 * Elsewhere the same code is built for the default target. Defining
 * WV_SIMD_CLONES (e.g. empty: the baseline only) builds other versions. */
#ifndef WV_SIMD_CLONES
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && __GNUC__ >= 11
#define WV_SIMD_CLONES __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define WV_SIMD_CLONES
#endif
#endif

/* The lane index 0..7. */
#define WV_IOTA8 ((wv_i8){0, 1, 2, 3, 4, 5, 6, 7})

WV_INLINE wv_f8 wv_splat8(float x) { return (wv_f8){x, x, x, x, x, x, x, x}; }
WV_INLINE wv_i8 wv_splati8(int32_t x) { return (wv_i8){x, x, x, x, x, x, x, x}; }

/* ---- select: m ? a : b per lane ---- */
WV_INLINE float wv_sel_f(int m, float a, float b) { return m ? a : b; }
WV_INLINE double wv_sel_d(int m, double a, double b) { return m ? a : b; }
WV_INLINE wv_f8 wv_sel_8(wv_i8 m, wv_f8 a, wv_f8 b) { return (wv_f8)((m & (wv_i8)a) | (~m & (wv_i8)b)); }
#define wv_sel(m, a, b) _Generic((a), float: wv_sel_f, double: wv_sel_d, wv_f8: wv_sel_8)(m, a, b)

WV_INLINE int64_t wv_seli_f(int m, int64_t a, int64_t b) { return m ? a : b; }
WV_INLINE wv_i8 wv_seli_8(wv_i8 m, wv_i8 a, wv_i8 b) { return (m & a) | (~m & b); }
#define wv_seli(m, a, b) _Generic((a), wv_i8: wv_seli_8, default: wv_seli_f)(m, a, b)

WV_INLINE uint64_t wv_selu_f(int m, uint64_t a, uint64_t b) { return m ? a : b; }
WV_INLINE wv_q8 wv_selu_8(wv_i8 m, wv_q8 a, wv_q8 b) {
  wv_q8 w = (wv_q8)__builtin_convertvector(m, wv_l8); /* 0 / -1 widened */
  return (w & a) | (~w & b);
}
#define wv_selu(m, a, b) _Generic((a), wv_q8: wv_selu_8, default: wv_selu_f)(m, a, b)

WV_INLINE uint32_t wv_selw_f(int m, uint32_t a, uint32_t b) { return m ? a : b; }
WV_INLINE wv_w8 wv_selw_8(wv_i8 m, wv_w8 a, wv_w8 b) { return ((wv_w8)m & a) | (~(wv_w8)m & b); }
#define wv_selw(m, a, b) _Generic((a), wv_w8: wv_selw_8, default: wv_selw_f)(m, a, b)

/* ---- masks ---- */
WV_INLINE int wv_not_f(int m) { return !m; }
WV_INLINE wv_i8 wv_not_8(wv_i8 m) { return ~m; }
#define wv_not(m) _Generic((m), wv_i8: wv_not_8, default: wv_not_f)(m)

WV_INLINE int wv_any_f(int m) { return m != 0; }
WV_INLINE int wv_any_8(wv_i8 m) {
  int32_t r = 0;
  for (int i = 0; i < WV_LANES; i++) r |= m[i];
  return r != 0;
}
#define wv_any(m) _Generic((m), wv_i8: wv_any_8, default: wv_any_f)(m)
WV_INLINE int wv_all_f(int m) { return m != 0; }
WV_INLINE int wv_all_8(wv_i8 m) {
  int32_t r = -1;
  for (int i = 0; i < WV_LANES; i++) r &= m[i];
  return r != 0;
}
#define wv_all(m) _Generic((m), wv_i8: wv_all_8, default: wv_all_f)(m)
/* Lane i's mask as bit i. */
WV_INLINE unsigned wv_bits_8(wv_i8 m) {
  unsigned b = 0;
  for (int i = 0; i < WV_LANES; i++) b |= (unsigned)(m[i] & 1) << i;
  return b;
}

/* ---- reals ---- */
WV_INLINE wv_f8 wv_sqrt_8(wv_f8 x) { /* compiles to one sqrtps per vector register */
  wv_f8 r;
  for (int i = 0; i < WV_LANES; i++) r[i] = sqrtf(x[i]);
  return r;
}
#define wv_sqrt(x) _Generic((x), float: sqrtf, double: sqrt, wv_f8: wv_sqrt_8)(x)

WV_INLINE wv_f8 wv_abs_8(wv_f8 x) { return (wv_f8)((wv_i8)x & 0x7fffffff); }
#define wv_abs(x) _Generic((x), float: fabsf, double: fabs, wv_f8: wv_abs_8)(x)

/* floor as an integer: without SSE4.1 floorf is a library call or a long
 * sequence; a truncating conversion and one correction give the same integer.
 * Scalar: 64 bits, |x| < 2^62 (clamped to +-4e18 beyond, NaN to -4e18). Vector: 32 bits, |x| < 2^31 (callers check). */
WV_INLINE int64_t wv_floori_f(float x) {
  /* clamped first: converting a float beyond the integer's range (or NaN) is
   * undefined; values within it are untouched */
  if (!(x > -4.0e18f)) x = -4.0e18f;
  if (x > 4.0e18f) x = 4.0e18f;
  long long i = (long long)x;
  return i - (x < (float)i);
}
WV_INLINE wv_i8 wv_floori_8(wv_f8 x) {
  wv_i8 i = __builtin_convertvector(x, wv_i8);
  return i + (x < __builtin_convertvector(i, wv_f8)); /* a true compare is -1 */
}
#define wv_floori(x) _Generic((x), float: wv_floori_f, wv_f8: wv_floori_8)(x)

/* Whether the lane type's integers can hold floor(x) for the cell arithmetic:
 * always in scalar (64 bits); |x| < 2^22 in the 8-wide form (32-bit lanes, and
 * wv_divn's float quotient stays within one), false for NaN. */
WV_INLINE int wv_indexable_f(float x) {
  (void)x;
  return 1;
}
WV_INLINE wv_i8 wv_indexable_8(wv_f8 x) { return wv_abs_8(x) < 4194304.0f; }
#define wv_indexable(x) _Generic((x), float: wv_indexable_f, wv_f8: wv_indexable_8)(x)

WV_INLINE float wv_itof_f(int64_t i) { return (float)i; }
WV_INLINE wv_f8 wv_itof_8(wv_i8 i) { return __builtin_convertvector(i, wv_f8); }
#define wv_itof(i) _Generic((i), wv_i8: wv_itof_8, default: wv_itof_f)(i)

/* Truncation to int32 and the float whose bits are an int32 (fast exp). */
WV_INLINE int32_t wv_trunc32_f(float x) { return (int32_t)x; }
WV_INLINE wv_i8 wv_trunc32_8(wv_f8 x) { return __builtin_convertvector(x, wv_i8); }
#define wv_trunc32(x) _Generic((x), float: wv_trunc32_f, wv_f8: wv_trunc32_8)(x)
WV_INLINE float wv_asfloat_f(int32_t i) {
  float f;
  memcpy(&f, &i, sizeof f);
  return f;
}
WV_INLINE wv_f8 wv_asfloat_8(wv_i8 i) { return (wv_f8)i; }
#define wv_asfloat(i) _Generic((i), wv_i8: wv_asfloat_8, default: wv_asfloat_f)(i)

/* ---- integers ---- */
/* floor(x / n) and the mathematical x mod n (0 <= result < n), n >= 1. Vector:
 * for |x| < 2^22 and n <= 2^12, where the float quotient is off by at most one
 * and one correction fixes it. */
WV_INLINE int64_t wv_divn_f(int64_t x, int n) {
  int64_t q = x / n;
  return q - (q * n > x);
}
WV_INLINE wv_i8 wv_divn_8(wv_i8 x, int n) {
  wv_i8 q = wv_floori_8(wv_itof_8(x) * (1.0f / (float)n));
  wv_i8 r = x - q * n;
  return q + (r < 0) - (r >= n); /* a true compare is -1 */
}
#define wv_divn(x, n) _Generic((x), wv_i8: wv_divn_8, default: wv_divn_f)(x, n)
#define wv_modn(x, n) ((x) - wv_divn(x, n) * (n))

/* Integers widened to 64-bit hash input, as the scalar (uint64_t)(int64_t) cast. */
WV_INLINE uint64_t wv_tou64_f(int64_t x) { return (uint64_t)x; }
WV_INLINE wv_q8 wv_tou64_8(wv_i8 x) { return (wv_q8)__builtin_convertvector(x, wv_l8); }
#define wv_tou64(x) _Generic((x), wv_i8: wv_tou64_8, default: wv_tou64_f)(x)

/* Uniform float in [0, 1) from the top 24 bits (wv_u01 in util/hash.h). */
WV_INLINE wv_f8 wv_u01_8(wv_q8 h) {
  return __builtin_convertvector(__builtin_convertvector(h >> 40, wv_i8), wv_f8) * (1.0f / 16777216.0f);
}
#define wv_u01g(h) _Generic((h), wv_q8: wv_u01_8, default: wv_u01)(h)

/* The hashes of util/hash.h on 64-bit lanes (the same bodies). */
WV_INLINE wv_q8 wv_mix64_8(wv_q8 z) { return WV_MIX64_BODY(z); }
WV_INLINE wv_q8 wv_hash2_8(wv_q8 a, wv_q8 b, uint64_t seed) { return WV_HASH2_BODY(wv_mix64_8, a, b, seed); }
#define wv_mix64g(z) _Generic((z), wv_q8: wv_mix64_8, default: wv_mix64)(z)
#define wv_hash2g(a, b, seed) _Generic((a), wv_q8: wv_hash2_8, default: wv_hash2)(a, b, seed)

/* ---- table lookups ---- */
/* tab[i] per lane; built as one vector (writing lanes one by one through memory
 * stalls the read of the whole vector that follows). */
WV_INLINE int32_t wv_gather32_f(const int32_t *tab, int64_t i) { return tab[i]; }
WV_INLINE wv_i8 wv_gather32_8(const int32_t *tab, wv_i8 i) {
  return (wv_i8){tab[i[0]], tab[i[1]], tab[i[2]], tab[i[3]], tab[i[4]], tab[i[5]], tab[i[6]], tab[i[7]]};
}
#define wv_gather32(tab, i) _Generic((i), wv_i8: wv_gather32_8, default: wv_gather32_f)(tab, i)
WV_INLINE float wv_gatherf_f(const float *tab, uint64_t i) { return tab[i]; }
WV_INLINE wv_f8 wv_gatherf_8(const float *tab, wv_q8 i) {
  return (wv_f8){tab[i[0]], tab[i[1]], tab[i[2]], tab[i[3]], tab[i[4]], tab[i[5]], tab[i[6]], tab[i[7]]};
}
#define wv_gatherf(tab, i) _Generic((i), wv_q8: wv_gatherf_8, default: wv_gatherf_f)(tab, i)

#endif
