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

wv_status wv_image_blur(const wv_image *in, double sigma, wv_image *out, wv_error *err) {
  out->data = NULL;
  if (!(sigma >= 0.0 && sigma <= 1000.0))
    return wv_fail(err, WV_ERR_INVALID, "blur sigma %g is outside 0..1000 pixels", sigma);
  wv_status st = wv_image_alloc(out, in->w, in->h, in->c, err);
  if (st) return st;
  size_t n = (size_t)in->w * in->h * in->c;
  int rad = (int)ceil(3.0 * sigma);
  float *tmp = malloc(n * sizeof(float));
  double *g = malloc(sizeof(double) * (size_t)(2 * rad + 1));
  if (!tmp || !g) {
    free(tmp), free(g);
    wv_image_free(out);
    return wv_fail(err, WV_ERR_NOMEM, "out of memory for a blur of %d x %d", in->w, in->h);
  }
  double gs = 0;
  for (int k = -rad; k <= rad; k++) gs += g[k + rad] = sigma > 0 ? exp(-0.5 * k * k / (sigma * sigma)) : 1.0;
  for (int k = 0; k <= 2 * rad; k++) g[k] /= gs;
  /* Separable: along x into tmp, then along y into out; edges clamped. */
  for (int pass = 0; pass < 2; pass++) {
    const float *src = pass ? tmp : in->data;
    float *dst = pass ? out->data : tmp;
    for (int y = 0; y < in->h; y++)
      for (int x = 0; x < in->w; x++)
        for (int c = 0; c < in->c; c++) {
          double s = 0;
          for (int k = -rad; k <= rad; k++) {
            int xx = pass ? x : x + k, yy = pass ? y + k : y;
            xx = xx < 0 ? 0 : xx >= in->w ? in->w - 1 : xx;
            yy = yy < 0 ? 0 : yy >= in->h ? in->h - 1 : yy;
            s += g[k + rad] * src[((size_t)yy * in->w + xx) * in->c + c];
          }
          dst[((size_t)y * in->w + x) * in->c + c] = (float)s;
        }
  }
  free(tmp), free(g);
  return WV_OK;
}
