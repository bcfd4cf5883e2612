/* woven: float images in memory (woven/image.h): allocation with size limits, pixel access,
 * mean and difference, and the one Gaussian blur (of an image or of one plane). */
#include "woven/image.h"

#include <math.h>
#include <omp.h>
#include <stddef.h>
#include <stdlib.h>

#include "woven/nn.h"

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
  return n ? wv_nn_l1(a->data, b->data, n, 0, NULL, 0.0f) / n : 0.0;
}

double wv_image_mean(const wv_image *a) {
  size_t n = (size_t)a->w * a->h * a->c;
  double s = 0;
  for (size_t i = 0; i < n; i++) s += a->data[i];
  return n ? s / n : 0.0;
}

/* One pass of the separable blur along x (vertical 0) or y (1) of a plane whose pixels are
 * `stride` floats apart; taps g[0..2r]; edges clamped; sums in double. Every value sums its
 * taps k ascending whatever the path, but a row of values is summed at once in acc (w
 * doubles), a tap at a time: the sums are independent (no chain of dependent adds) and the
 * rows are read whole. Along x the values farther than r from both edges go that way and
 * skip the clamp; the others keep the plain loop. Rows go to threads, each with its own acc
 * in accs (w doubles a thread). */
static void blur_pass(const float *in, float *out, int w, int h, int stride, int vertical, const double *g, int r,
                      double *accs) {
  if (!vertical) {
    int lo = r < w ? r : w, hi = w - r > lo ? w - r : lo; /* [lo, hi): no clamped tap */
#pragma omp parallel for schedule(static)
    for (int y = 0; y < h; y++) {
      double *acc = accs + (size_t)omp_get_thread_num() * w;
      const float *row = in + (size_t)y * w * stride;
      float *orow = out + (size_t)y * w * stride;
      for (int x = lo; x < hi; x++) acc[x] = 0;
      for (int k = 0; k <= 2 * r; k++) {
        const float *src = row + (ptrdiff_t)(k - r) * stride;
        double gk = g[k];
        for (int x = lo; x < hi; x++) acc[x] += gk * src[(size_t)x * stride];
      }
      for (int x = 0; x < w; x++) {
        if (x >= lo && x < hi) {
          orow[(size_t)x * stride] = (float)acc[x];
          continue;
        }
        double s = 0;
        for (int k = -r; k <= r; k++) {
          int xx = x + k < 0 ? 0 : x + k >= w ? w - 1 : x + k;
          s += g[k + r] * row[(size_t)xx * stride];
        }
        orow[(size_t)x * stride] = (float)s;
      }
    }
    return;
  }
#pragma omp parallel for schedule(static)
  for (int y = 0; y < h; y++) {
    double *acc = accs + (size_t)omp_get_thread_num() * w;
    for (int x = 0; x < w; x++) acc[x] = 0;
    for (int k = -r; k <= r; k++) {
      int yy = y + k < 0 ? 0 : y + k >= h ? h - 1 : y + k;
      const float *src = in + (size_t)yy * w * stride;
      double gk = g[k + r];
      for (int x = 0; x < w; x++) acc[x] += gk * src[(size_t)x * stride];
    }
    float *orow = out + (size_t)y * w * stride;
    for (int x = 0; x < w; x++) orow[(size_t)x * stride] = (float)acc[x];
  }
}

int wv_gaussian_radius(double sigma) { return (int)ceil(3.0 * sigma); }

void wv_gaussian_taps(double sigma, double *g) {
  int r = wv_gaussian_radius(sigma);
  double gs = 0;
  for (int k = -r; k <= r; k++) gs += g[k + r] = sigma > 0 ? exp(-0.5 * k * k / (sigma * sigma)) : 1.0;
  for (int k = 0; k <= 2 * r; k++) g[k] /= gs;
}

wv_status wv_blur_plane(const float *in, float *out, int w, int h, int stride, double sigma, wv_error *err) {
  if (!(sigma >= 0.0 && sigma <= 1000.0))
    return wv_fail(err, WV_ERR_INVALID, "blur sigma %g is outside 0..1000 pixels", sigma);
  int r = wv_gaussian_radius(sigma), nt = omp_get_max_threads();
  float *tmp = malloc(sizeof(float) * (size_t)w * h * stride);
  double *g = malloc(sizeof(double) * ((size_t)(2 * r + 1) + (size_t)w * nt)); /* taps, a row per thread */
  if (!tmp || !g) {
    free(tmp), free(g);
    return wv_fail(err, WV_ERR_NOMEM, "out of memory for a blur of %d x %d", w, h);
  }
  wv_gaussian_taps(sigma, g);
  blur_pass(in, tmp, w, h, stride, 0, g, r, g + 2 * r + 1);
  blur_pass(tmp, out, w, h, stride, 1, g, r, g + 2 * r + 1);
  free(tmp), free(g);
  return WV_OK;
}

wv_status wv_image_blur(const wv_image *in, double sigma, wv_image *out, wv_error *err) {
  out->data = NULL;
  if (!(sigma >= 0.0 && sigma <= 1000.0))
    return wv_fail(err, WV_ERR_INVALID, "blur sigma %g is outside 0..1000 pixels", sigma);
  wv_status st = wv_image_alloc(out, in->w, in->h, in->c, err);
  for (int c = 0; c < in->c && !st; c++) st = wv_blur_plane(in->data + c, out->data + c, in->w, in->h, in->c, sigma, err);
  if (st) wv_image_free(out);
  return st;
}
