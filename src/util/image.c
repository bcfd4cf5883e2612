#include "woven/image.h"

#include <math.h>
#include <stdlib.h>

wv_status wv_image_alloc(wv_image *img, int w, int h, int c, wv_error *err) {
  img->data = NULL;
  img->w = img->h = img->c = 0;
  if (w <= 0 || h <= 0 || c <= 0 || c > 4)
    return wv_fail(err, WV_ERR_INVALID, "invalid image size %d x %d x %d", w, h, c);
  if ((long)w * (long)h > WV_IMAGE_MAX_PIXELS)
    return wv_fail(err, WV_ERR_NOMEM, "image of %d x %d pixels is too large (limit %ld pixels)",
                   w, h, (long)WV_IMAGE_MAX_PIXELS);
  img->data = calloc((size_t)w * h * c, sizeof(float));
  if (!img->data) return wv_fail(err, WV_ERR_NOMEM, "out of memory for a %d x %d image", w, h);
  img->w = w;
  img->h = h;
  img->c = c;
  return WV_OK;
}

void wv_image_free(wv_image *img) {
  if (!img) return;
  free(img->data);
  img->data = NULL;
  img->w = img->h = img->c = 0;
}

double wv_image_mad(const wv_image *a, const wv_image *b) {
  if (a->w != b->w || a->h != b->h || a->c != b->c) return -1.0;
  size_t n = (size_t)a->w * a->h * a->c;
  double s = 0;
  for (size_t i = 0; i < n; i++) s += fabs((double)a->data[i] - b->data[i]);
  return n ? s / n : 0.0;
}

double wv_image_mean(const wv_image *a) {
  size_t n = (size_t)a->w * a->h * a->c;
  double s = 0;
  for (size_t i = 0; i < n; i++) s += a->data[i];
  return n ? s / n : 0.0;
}
