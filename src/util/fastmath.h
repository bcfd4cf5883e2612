/* Polynomial sine/cosine for |x| <= pi/2 (yarn angles never leave that range):
 * Taylor series to degree 11/12, error below 1e-7, several times faster than
 * libm and branch-free, which matters in the renderer's inner loop. */
#ifndef WOVEN_FASTMATH_H
#define WOVEN_FASTMATH_H

#include <stdint.h>

static inline float wv_sin_hp(float x) {
  float x2 = x * x;
  return x * (1.0f + x2 * (-1.0f / 6 + x2 * (1.0f / 120 + x2 * (-1.0f / 5040 +
             x2 * (1.0f / 362880 + x2 * (-1.0f / 39916800))))));
}
static inline float wv_cos_hp(float x) {
  float x2 = x * x;
  return 1.0f + x2 * (-0.5f + x2 * (1.0f / 24 + x2 * (-1.0f / 720 + x2 * (1.0f / 40320 +
         x2 * (-1.0f / 3628800 + x2 * (1.0f / 479001600))))));
}

/* exp(x) to about 1 ulp for x in [-87, 88] (clamped outside): x = k ln2 + r with
 * |r| <= ln2/2, e^r by its Taylor series to r^7, 2^k from the exponent bits.
 * Written with only +, -, *, compare and an int conversion so that the 8-wide
 * copy in render/render_simd.c, which repeats it operation for operation,
 * rounds identically: the forward renderer's vector and scalar paths and the
 * gradient kernel must give bit-identical radiance. */
static inline float wv_expf(float x) {
  x = x > -87.0f ? x : -87.0f;
  x = x < 88.0f ? x : 88.0f;
  float kf = (x * 1.44269502f + 12582912.0f) - 12582912.0f; /* round to nearest: 1.5 * 2^23 */
  float r = (x - kf * 0.693145751953125f) - kf * 1.42860677e-6f; /* ln 2 in two parts, kf ln2_hi exact */
  float p = 1.0f + r * (1.0f + r * (0.5f + r * (1.0f / 6 + r * (1.0f / 24 + r * (1.0f / 120 +
            r * (1.0f / 720 + r * (1.0f / 5040)))))));
  union { int32_t i; float f; } s = {((int32_t)kf + 127) << 23}; /* 2^k, k in [-126, 127] */
  return p * s.f;
}

/* floor as an integer: without SSE4.1 floorf is a library call or a long
 * sequence; a truncating conversion and one correction give the same integer
 * for every |x| < 2^62. */
static inline long long wv_floor_ll(float x) {
  long long i = (long long)x;
  return i - (x < (float)i);
}

/* atan2 to about 1e-7 rad: octant reduction, then a shift by pi/6 brings the
 * argument under tan(15 deg), where an odd Taylor series to x^13 suffices. */
static inline float wv_atan2(float y, float x) {
  float ax = x < 0 ? -x : x, ay = y < 0 ? -y : y;
  float mx = ax > ay ? ax : ay, mn = ax > ay ? ay : ax;
  if (mx == 0.0f) return 0.0f;
  float a = mn / mx, off = 0.0f;
  if (a > 0.26794919f) {
    a = (a * 1.7320508f - 1.0f) / (a + 1.7320508f);
    off = 0.52359878f;
  }
  float a2 = a * a;
  float r = off + a * (1.0f + a2 * (-1.0f / 3 + a2 * (1.0f / 5 + a2 * (-1.0f / 7 + a2 * (1.0f / 9 +
                  a2 * (-1.0f / 11 + a2 * (1.0f / 13)))))));
  if (ay > ax) r = 1.57079633f - r;
  if (x < 0) r = 3.14159265f - r;
  return y < 0 ? -r : r;
}

#endif
