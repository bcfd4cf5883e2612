/* Polynomial sine/cosine for |x| <= pi/2 (yarn angles never leave that range):
 * Taylor series to degree 11/12, error below 1e-7, several times faster than
 * libm and branch-free, which matters in the renderer's inner loop. */
#ifndef WOVEN_FASTMATH_H
#define WOVEN_FASTMATH_H

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

#endif
