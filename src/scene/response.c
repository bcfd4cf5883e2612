/* Sensor response: what the camera does to radiance before we compare to a photo. */
#include <math.h>

#include "woven/scene.h"

float wv_encode(const wv_scene *s, float x) {
  if (x <= 0.0f) return 0.0f;
  switch (s->encoding) {
    case WV_ENC_SRGB: return x <= 0.0031308f ? 12.92f * x : 1.055f * powf(x, 1.0f / 2.4f) - 0.055f;
    case WV_ENC_GAMMA: return powf(x, (float)(1.0 / s->gamma));
    default: return x;
  }
}

float wv_decode(const wv_scene *s, float y) {
  if (y <= 0.0f) return 0.0f;
  switch (s->encoding) {
    case WV_ENC_SRGB: return y <= 0.04045f ? y / 12.92f : powf((y + 0.055f) / 1.055f, 2.4f);
    case WV_ENC_GAMMA: return powf(y, (float)s->gamma);
    default: return y;
  }
}

/* d encode / dx; 0 where the encoding is flat or undefined (x <= 0). */
static float encode_deriv(const wv_scene *s, float x) {
  if (x <= 0.0f) return 0.0f;
  switch (s->encoding) {
    case WV_ENC_SRGB:
      return x <= 0.0031308f ? 12.92f : 1.055f / 2.4f * powf(x, 1.0f / 2.4f - 1.0f);
    case WV_ENC_GAMMA: {
      float g = (float)(1.0 / s->gamma);
      return g * powf(x, g - 1.0f);
    }
    default: return 1.0f;
  }
}

static float mask_at(const wv_scene *s, int x, int y) {
  if (!s->falloff) return 1.0f;
  double dx = x + 0.5 - 0.5 * s->width, dy = y + 0.5 - 0.5 * s->height;
  return (float)exp(-(dx * dx + dy * dy) / (s->falloff_sigma * s->falloff_sigma));
}

void wv_scene_response(const wv_scene *s, const wv_image *rad, wv_image *cap) {
  float ex = (float)s->exposure, clip = (float)s->clip;
  for (int y = 0; y < rad->h; y++)
    for (int x = 0; x < rad->w; x++) {
      float m = mask_at(s, x, y);
      const float *in = wv_image_px(rad, x, y);
      float *out = wv_image_px(cap, x, y);
      for (int c = 0; c < rad->c; c++) {
        float v = in[c] * ex;
        if (clip > 0.0f && v > clip) v = clip;
        out[c] = m * wv_encode(s, v);
      }
    }
}

void wv_scene_response_backward(const wv_scene *s, const wv_image *rad, const wv_image *dcap, wv_image *drad) {
  float ex = (float)s->exposure, clip = (float)s->clip;
  for (int y = 0; y < rad->h; y++)
    for (int x = 0; x < rad->w; x++) {
      float m = mask_at(s, x, y);
      const float *in = wv_image_px(rad, x, y), *g = wv_image_px(dcap, x, y);
      float *out = wv_image_px(drad, x, y);
      for (int c = 0; c < rad->c; c++) {
        float v = in[c] * ex;
        int clipped = clip > 0.0f && v > clip;
        out[c] = clipped ? 0.0f : g[c] * m * encode_deriv(s, v) * ex;
      }
    }
}
