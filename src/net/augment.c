/* woven: the camera augmentation of FabricNet's training images. A render is noiseless,
 * focused, exposed as the scene says and stored losslessly; a photo is none of these.
 * wv_camera_augment draws, from one seed, what a camera adds and applies it to a render's
 * linear radiance before the scene's response (docs/fabricnet.md, "Camera augmentation"). */
#include <math.h>
#include <stdlib.h>

#include "util/colour.h"
#include "woven/dataset.h"
#include "woven/imgops.h"
#include "woven/io.h"
#include "woven/nn.h"

/* The distribution, one line each (uniform draws). */
#define AUG_GLINT_FRAC 0.004  /* up to this fraction of pixels (by brightness) sparkle */
#define AUG_GLINT_GAIN 3.0    /* a glint multiplies radiance by 1.5 .. 1.5 + this */
#define AUG_EXPOSURE_STOPS 0.5 /* exposure gain 2^(+-this) */
#define AUG_WB 0.1            /* white balance: red and blue gains exp(+-this) */
#define AUG_SHOT 0.003        /* noise variance a x + b on the exposed value: a up to this */
#define AUG_READ 2e-5         /* ... b up to this */
#define AUG_JPEG_P 0.75       /* probability of a JPEG round trip */
#define AUG_JPEG_QLO 70       /* its quality, 70 .. 95 */
#define AUG_JPEG_QHI 95

static double uni(wv_rng *r, double lo, double hi) { return lo + (hi - lo) * wv_rng_uniform(r); }

wv_status wv_camera_augment(const wv_scene *s, const wv_image *radiance, uint64_t seed, wv_image *capture,
                            wv_error *err) {
  return wv_camera_augment_blur(s, radiance, seed, WV_AUGMENT_BLUR, capture, err);
}

wv_status wv_camera_augment_blur(const wv_scene *s, const wv_image *radiance, uint64_t seed, double blur_max,
                                 wv_image *capture, wv_error *err) {
  wv_rng r;
  wv_rng_seed(&r, seed);
  /* every draw first, so each one's value does not depend on the image */
  double glint = uni(&r, 0, AUG_GLINT_FRAC), sigma = uni(&r, 0, blur_max);
  double expo = pow(2.0, uni(&r, -AUG_EXPOSURE_STOPS, AUG_EXPOSURE_STOPS));
  double gain[3] = {expo * exp(uni(&r, -AUG_WB, AUG_WB)), expo, expo * exp(uni(&r, -AUG_WB, AUG_WB))};
  double a = uni(&r, 0, AUG_SHOT), b = uni(&r, 0, AUG_READ);
  int jpeg = uni(&r, 0, 1) < AUG_JPEG_P;
  int quality = AUG_JPEG_QLO + (int)floor(uni(&r, 0, AUG_JPEG_QHI - AUG_JPEG_QLO + 1));

  wv_image rad = {0};
  wv_status st = wv_image_alloc(&rad, radiance->w, radiance->h, 3, err);
  if (st) return st;
  size_t np = (size_t)rad.w * rad.h;
  double mean = 0;
  for (size_t i = 0; i < np; i++) {
    const float *p = radiance->data + i * radiance->c;
    for (int c = 0; c < 3; c++) rad.data[3 * i + c] = p[radiance->c >= 3 ? c : 0];
    mean += wv_luminance_d(rad.data[3 * i], rad.data[3 * i + 1], rad.data[3 * i + 2]);
  }
  mean = mean / (double)np + 1e-12;
  /* Glints: fibres that mirror the light into a pixel; brighter pixels sparkle more. */
  for (size_t i = 0; i < np; i++) {
    float *p = rad.data + 3 * i;
    double lum = wv_luminance_d(p[0], p[1], p[2]);
    double u = uni(&r, 0, 1), g = uni(&r, 1.5, 1.5 + AUG_GLINT_GAIN);
    if (u < glint * lum / mean)
      for (int c = 0; c < 3; c++) p[c] = (float)(p[c] * g);
  }
  /* Defocus, then the exposure and white-balance gains. */
  wv_image blurred = {0};
  st = wv_image_blur(&rad, sigma, &blurred, err);
  wv_image_free(&rad);
  if (st) return st;
  /* Sensor noise on the exposed signal x: variance a x + b (shot and read noise). */
  double ex = s->exposure > 0 ? s->exposure : 1;
  for (size_t i = 0; i < np; i++)
    for (int c = 0; c < 3; c++) {
      float *v = blurred.data + 3 * i + c;
      double x = ex * gain[c] * *v;
      x += sqrt(a * (x > 0 ? x : 0) + b) * wv_rng_normal(&r);
      *v = (float)((x > 0 ? x : 0) / ex);
    }
  wv_image cap = {0};
  if ((st = wv_image_alloc(&cap, blurred.w, blurred.h, 3, err))) {
    wv_image_free(&blurred);
    return st;
  }
  wv_scene_response(s, &blurred, &cap);
  wv_image_free(&blurred);
  wv_image_quantise8(&cap);
  if (!jpeg) {
    *capture = cap;
    return WV_OK;
  }
  st = wv_image_jpeg_roundtrip(&cap, quality, capture, err);
  wv_image_free(&cap);
  return st;
}
