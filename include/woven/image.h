/* woven: float images (interleaved, row-major, top row first). */
#ifndef WOVEN_IMAGE_H
#define WOVEN_IMAGE_H

#include <stddef.h>
#include "woven/error.h"

typedef struct {
  int w, h, c;  /* width, height, channels (1, 3 or 4) */
  float *data;  /* w*h*c floats, owned by the image */
} wv_image;

/* Largest image the program will allocate (pixels); guards against absurd sizes. */
#define WV_IMAGE_MAX_PIXELS (1L << 28)

wv_status wv_image_alloc(wv_image *img, int w, int h, int c, wv_error *err);
void wv_image_free(wv_image *img);
static inline float *wv_image_px(const wv_image *img, int x, int y) {
  return img->data + ((size_t)y * img->w + x) * img->c;
}
/* Mean absolute difference over all samples; -1 if shapes differ. */
double wv_image_mad(const wv_image *a, const wv_image *b);
double wv_image_mean(const wv_image *a);
/* Gaussian blur of standard deviation sigma pixels (kernel radius ceil(3 sigma),
 * edges clamped), every channel; out is allocated here. */
wv_status wv_image_blur(const wv_image *in, double sigma, wv_image *out, wv_error *err);
/* The same blur of one plane of w x h floats whose pixels are `stride` floats apart (a
 * channel of an interleaved image), in to out (distinct). */
wv_status wv_blur_plane(const float *in, float *out, int w, int h, int stride, double sigma, wv_error *err);
/* The blur's taps: g[0..2r], r = wv_gaussian_radius(sigma), summing to 1 (sigma 0: one tap). */
int wv_gaussian_radius(double sigma);
void wv_gaussian_taps(double sigma, double *g);

#endif
