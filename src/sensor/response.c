/* The sensor response (what the camera does to radiance before we compare to a
 * photo): the adjoint's encoding slope, the falloff mask, the image response
 * and the public per-value encoding and its inverse. The per-value response
 * itself is sensor/response_impl.h. */
#include <math.h>

#include "sensor/sensor.h"
#include "woven/scene.h"

float wv_encode(const wv_scene *s, float x) { return wv_encode_f(s, x); }

float wv_decode(const wv_scene *s, float y) {
  if (y <= 0.0f) return 0.0f;
  switch (s->encoding) {
    case WV_ENC_SRGB: return y <= 0.04045f ? y / 12.92f : powf((y + 0.055f) / 1.055f, 2.4f);
    case WV_ENC_GAMMA: return powf(y, (float)s->gamma);
    default: return y;
  }
}

double wv_encode_slope(const wv_scene *s, double x) {
  if (x <= 0.0) return 0.0;
  switch (s->encoding) {
    case WV_ENC_SRGB: return x <= 0.0031308 ? 12.92 : 1.055 / 2.4 * pow(x, 1.0 / 2.4 - 1.0); /* d(wv_encode) */
    case WV_ENC_GAMMA: return pow(x, 1.0 / s->gamma - 1.0) / s->gamma;
    default: return 1.0;
  }
}

double wv_response_mask(const wv_scene *s, int x, int y) {
  if (!s->falloff) return 1.0;
  double dx = x + 0.5 - 0.5 * s->width, dy = y + 0.5 - 0.5 * s->height;
  return exp(-(dx * dx + dy * dy) / (s->falloff_sigma * s->falloff_sigma));
}

void wv_scene_response(const wv_scene *s, const wv_image *rad, wv_image *cap) {
  for (int y = 0; y < rad->h; y++)
    for (int x = 0; x < rad->w; x++) {
      double m = wv_response_mask(s, x, y);
      const float *in = wv_image_px(rad, x, y);
      float *out = wv_image_px(cap, x, y);
      for (int c = 0; c < rad->c; c++) out[c] = wv_respond_f(s, m, in[c], NULL);
    }
}
