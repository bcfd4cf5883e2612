/* The sensor response of one value, for a real type (a lane template in its
 * scalar flavours, see kernel/lanes.h; instantiated by sensor/sensor.h as
 * wv_encode_f / wv_respond_f in float and _d in double). Each step comes in two
 * forms: one that takes its powers itself and one that is handed them, for callers
 * that take the powers of many values at once (wv_respond_n). */

/* The power the scene's colour encoding raises a linear value to (1: none). */
WV_INLINE WV_R WV_FN(wv_encode_exponent)(const wv_scene *s) {
  switch (s->encoding) {
    case WV_ENC_SRGB: return (WV_R)1.0 / (WV_R)2.4;
    case WV_ENC_GAMMA: return (WV_R)(1.0 / s->gamma);
    default: return 1;
  }
}

/* The colour encoding enc (with the scene's gamma) of x, given p = x^wv_encode_exponent
 * (not read where the encoding is linear); linear values <= 0 give 0. */
WV_INLINE WV_R WV_FN(wv_encode_pow)(wv_encoding enc, WV_R x, WV_R p) {
  if (x <= 0) return 0;
  switch (enc) {
    case WV_ENC_SRGB: return WV_FN(wv_srgb_encode_pow)(x, p);
    case WV_ENC_GAMMA: return p;
    default: return x;
  }
}

/* The scene's colour encoding (linear values <= 0 give 0). */
WV_INLINE WV_R WV_FN(wv_encode)(const wv_scene *s, WV_R x) {
  WV_R p = x > 0 && s->encoding != WV_ENC_LINEAR ? WV_FN(wv_power)(x, WV_FN(wv_encode_exponent)(s)) : 0;
  return WV_FN(wv_encode_pow)(s->encoding, x, p);
}

/* exposure * radiance, clipped at the scene's clip (clip <= 0: none); *clipped tells. */
WV_INLINE WV_R WV_FN(wv_expose)(const wv_scene *s, WV_R radiance, int *clipped) {
  WV_R v = radiance * (WV_R)s->exposure, clip = (WV_R)s->clip;
  *clipped = clip > 0 && v > clip;
  return *clipped ? clip : v;
}

/* The response of an exposed value v (wv_expose) given its powers pe = v^wv_encode_exponent
 * and ps = v^wv_slope_exponent (read only with slope); enc: the scene's encoding, a
 * separate argument so that a loop over values can be made for each encoding. */
WV_INLINE WV_R WV_FN(wv_respond_pow)(const wv_scene *s, wv_encoding enc, double mask, WV_R v, int clipped, WV_R pe,
                                      double ps, double *slope) {
  if (slope) *slope = clipped ? 0.0 : mask * wv_encode_slope_pow(enc, s->gamma, (double)v, ps) * s->exposure;
  return (WV_R)mask * WV_FN(wv_encode_pow)(enc, v, pe);
}

/* capture = mask * encode(min(exposure * radiance, clip)) (clip <= 0: none);
 * with slope, also its adjoint d capture / d radiance in double: 0 where
 * clipped (at exactly the clip value, the left derivative). mask: the falloff
 * at the pixel (wv_response_mask). */
WV_INLINE WV_R WV_FN(wv_respond)(const wv_scene *s, double mask, WV_R radiance, double *slope) {
  int clipped;
  WV_R v = WV_FN(wv_expose)(s, radiance, &clipped);
  int powered = v > 0 && s->encoding != WV_ENC_LINEAR;
  WV_R pe = powered ? WV_FN(wv_power)(v, WV_FN(wv_encode_exponent)(s)) : 0;
  double ps = slope && powered ? wv_power_d((double)v, wv_slope_exponent(s)) : 0;
  return WV_FN(wv_respond_pow)(s, s->encoding, mask, v, clipped, pe, ps, slope);
}
