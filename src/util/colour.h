/* Colour: the Rec. 709 luminance and the sRGB transfer curve (IEC 61966-2-1) of
 * linear RGB, the one place each is written. Float and double forms round
 * differently, so each caller keeps the precision it computes in. Inline: the
 * sensor response encodes every pixel. Internal to the library. */
#ifndef WOVEN_UTIL_COLOUR_H
#define WOVEN_UTIL_COLOUR_H

#include <math.h>

/* Rec. 709 luminance weights of linear R, G, B. */
#define WV_LUMA_R 0.2126
#define WV_LUMA_G 0.7152
#define WV_LUMA_B 0.0722

/* Luminance Y of linear R, G, B, in double and in float. */
static inline double wv_luminance_d(double r, double g, double b) {
  return WV_LUMA_R * r + WV_LUMA_G * g + WV_LUMA_B * b;
}
static inline float wv_luminance_f(float r, float g, float b) {
  return (float)WV_LUMA_R * r + (float)WV_LUMA_G * g + (float)WV_LUMA_B * b;
}

/* sRGB encoding of a linear value x > 0 whose power p = x^(1/2.4) is already taken
 * (p is not read on the linear segment), in float and double: for callers that take
 * many powers at once. */
static inline float wv_srgb_encode_pow_f(float x, float p) { return x <= 0.0031308f ? 12.92f * x : 1.055f * p - 0.055f; }
static inline double wv_srgb_encode_pow_d(double x, double p) { return x <= 0.0031308 ? 12.92 * x : 1.055 * p - 0.055; }
/* sRGB encoding of a linear value (0 for values <= 0), in float and double. */
static inline float wv_srgb_encode_f(float x) {
  if (x <= 0) return 0;
  return wv_srgb_encode_pow_f(x, x <= 0.0031308f ? 0.0f : powf(x, 1.0f / 2.4f));
}
static inline double wv_srgb_encode_d(double x) {
  if (x <= 0) return 0;
  return wv_srgb_encode_pow_d(x, x <= 0.0031308 ? 0.0 : pow(x, 1.0 / 2.4));
}
/* Its slope d encode / d linear for a linear value x > 0, given p = x^(1/2.4 - 1). */
static inline double wv_srgb_encode_slope_pow(double x, double p) { return x <= 0.0031308 ? 12.92 : 1.055 / 2.4 * p; }
/* The inverse: sRGB value to linear. */
static inline float wv_srgb_decode_f(float y) { return y <= 0.04045f ? y / 12.92f : powf((y + 0.055f) / 1.055f, 2.4f); }

#endif
