/* Fast math, generic over the float lane types (a template: see kernel/lanes.h;
 * instantiated by kernel/fastmath.h). Written with +, -, *, /, compares,
 * selects and int conversions only, so every lane type rounds identically. */

/* Polynomial sine/cosine for |x| <= pi/2 (yarn angles never leave that range):
 * Taylor series to degree 11/12, error below 1e-7, several times faster than
 * libm and branch-free, which matters in the renderer's inner loop. */
WV_INLINE WV_P WV_FN(wv_sin_hp)(WV_P x) {
  WV_P x2 = x * x;
  return x * (1.0f + x2 * (-1.0f / 6 + x2 * (1.0f / 120 + x2 * (-1.0f / 5040 +
             x2 * (1.0f / 362880 + x2 * (-1.0f / 39916800))))));
}
WV_INLINE WV_P WV_FN(wv_cos_hp)(WV_P x) {
  WV_P x2 = x * x;
  return 1.0f + x2 * (-0.5f + x2 * (1.0f / 24 + x2 * (-1.0f / 720 + x2 * (1.0f / 40320 +
         x2 * (-1.0f / 3628800 + x2 * (1.0f / 479001600))))));
}

/* exp(x) to about 1 ulp for x in [-87, 88] (clamped outside): x = k ln2 + r with
 * |r| <= ln2/2, e^r by its Taylor series to r^7, 2^k from the exponent bits. */
WV_INLINE WV_P WV_FN(wv_expf)(WV_P x) {
  x = wv_sel(x > -87.0f, x, WV_PB(-87.0f));
  x = wv_sel(x < 88.0f, x, WV_PB(88.0f));
  WV_P kf = (x * 1.44269502f + 12582912.0f) - 12582912.0f; /* round to nearest: 1.5 * 2^23 */
  WV_P r = (x - kf * 0.693145751953125f) - kf * 1.42860677e-6f; /* ln 2 in two parts, kf ln2_hi exact */
  WV_P p = 1.0f + r * (1.0f + r * (0.5f + r * (1.0f / 6 + r * (1.0f / 24 + r * (1.0f / 120 +
           r * (1.0f / 720 + r * (1.0f / 5040)))))));
  return p * wv_asfloat((wv_trunc32(kf) + 127) << 23); /* 2^k, k in [-126, 127] */
}

/* atan2 to about 1e-7 rad: octant reduction, then a shift by pi/6 brings the
 * argument under tan(15 deg), where an odd Taylor series to x^13 suffices.
 * Branches are selects; atan2(0, 0) = 0. */
WV_INLINE WV_P WV_FN(wv_atan2)(WV_P y, WV_P x) {
  WV_P ax = wv_abs(x), ay = wv_abs(y);
  WV_M xbig = ax > ay;
  WV_P mx = wv_sel(xbig, ax, ay), mn = wv_sel(xbig, ay, ax);
  WV_M zero = mx == 0.0f;
  WV_P a = mn / wv_sel(zero, WV_PB(1.0f), mx);
  WV_M shift = a > 0.26794919f;
  a = wv_sel(shift, (a * 1.7320508f - 1.0f) / (a + 1.7320508f), a);
  WV_P off = wv_sel(shift, WV_PB(0.52359878f), WV_PB(0.0f));
  WV_P a2 = a * a;
  WV_P r = off + a * (1.0f + a2 * (-1.0f / 3 + a2 * (1.0f / 5 + a2 * (-1.0f / 7 + a2 * (1.0f / 9 +
                 a2 * (-1.0f / 11 + a2 * (1.0f / 13)))))));
  r = wv_sel(ay > ax, 1.57079633f - r, r);
  r = wv_sel(x < 0.0f, 3.14159265f - r, r);
  r = wv_sel(y < 0.0f, -r, r);
  return wv_sel(zero, WV_PB(0.0f), r);
}
