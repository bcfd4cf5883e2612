/* The sensor response of one value, for a real type (a lane template in its
 * scalar flavours, see kernel/lanes.h; instantiated by sensor/sensor.h as
 * wv_encode_f / wv_respond_f in float and _d in double). */

/* The scene's colour encoding (linear values <= 0 give 0). */
WV_INLINE WV_R WV_FN(wv_encode)(const wv_scene *s, WV_R x) {
  if (x <= 0) return 0;
  switch (s->encoding) {
    case WV_ENC_SRGB: return WV_FN(wv_srgb_encode)(x);
    case WV_ENC_GAMMA: return wv_pow(x, (WV_R)(1.0 / s->gamma));
    default: return x;
  }
}

/* capture = mask * encode(min(exposure * radiance, clip)) (clip <= 0: none);
 * with slope, also its adjoint d capture / d radiance in double: 0 where
 * clipped (at exactly the clip value, the left derivative). mask: the falloff
 * at the pixel (wv_response_mask). */
WV_INLINE WV_R WV_FN(wv_respond)(const wv_scene *s, double mask, WV_R radiance, double *slope) {
  WV_R v = radiance * (WV_R)s->exposure, clip = (WV_R)s->clip;
  int clipped = clip > 0 && v > clip;
  if (clipped) v = clip;
  if (slope) *slope = clipped ? 0.0 : mask * wv_encode_slope(s, (double)v) * s->exposure;
  return (WV_R)mask * WV_FN(wv_encode)(s, v);
}
