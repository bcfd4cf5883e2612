#include "woven/metrics.h"

#include <math.h>
#include <stdlib.h>

#define WIN 11
#define RAD 5

/* Separable Gaussian filter of one plane over the valid region: out is
 * (w - 10) x (h - 10). tmp holds w x (h - 10). */
static void blur_valid(const double *in, int w, int h, const double *g, double *tmp, double *out) {
  int oh = h - 2 * RAD, ow = w - 2 * RAD;
  for (int y = 0; y < oh; y++)
    for (int x = 0; x < w; x++) {
      double s = 0;
      for (int k = 0; k < WIN; k++) s += g[k] * in[(size_t)(y + k) * w + x];
      tmp[(size_t)y * w + x] = s;
    }
  for (int y = 0; y < oh; y++)
    for (int x = 0; x < ow; x++) {
      double s = 0;
      for (int k = 0; k < WIN; k++) s += g[k] * tmp[(size_t)y * w + x + k];
      out[(size_t)y * ow + x] = s;
    }
}

static double ssim_plane(const double *a, const double *b, int w, int h, double *buf) {
  double g[WIN], gs = 0;
  for (int k = 0; k < WIN; k++) gs += g[k] = exp(-0.5 * (k - RAD) * (k - RAD) / (1.5 * 1.5));
  for (int k = 0; k < WIN; k++) g[k] /= gs;
  size_t n = (size_t)w * h, on = (size_t)(w - 2 * RAD) * (h - 2 * RAD);
  double *aa = buf, *bb = aa + n, *ab = bb + n, *tmp = ab + n;
  double *ma = tmp + n, *mb = ma + on, *saa = mb + on, *sbb = saa + on, *sab = sbb + on;
  for (size_t i = 0; i < n; i++) aa[i] = a[i] * a[i], bb[i] = b[i] * b[i], ab[i] = a[i] * b[i];
  blur_valid(a, w, h, g, tmp, ma);
  blur_valid(b, w, h, g, tmp, mb);
  blur_valid(aa, w, h, g, tmp, saa);
  blur_valid(bb, w, h, g, tmp, sbb);
  blur_valid(ab, w, h, g, tmp, sab);
  const double C1 = 0.01 * 0.01, C2 = 0.03 * 0.03;
  double sum = 0;
  for (size_t i = 0; i < on; i++) {
    double va = saa[i] - ma[i] * ma[i], vb = sbb[i] - mb[i] * mb[i], cov = sab[i] - ma[i] * mb[i];
    sum += ((2 * ma[i] * mb[i] + C1) * (2 * cov + C2)) /
           ((ma[i] * ma[i] + mb[i] * mb[i] + C1) * (va + vb + C2));
  }
  return sum / (double)on;
}

wv_status wv_ssim(const wv_image *a, const wv_image *b, wv_ssim_mode mode, double *out, wv_error *err) {
  if (a->w != b->w || a->h != b->h || a->c != b->c)
    return wv_fail(err, WV_ERR_INVALID, "images differ in size: %d x %d x %d and %d x %d x %d", a->w, a->h, a->c,
                   b->w, b->h, b->c);
  if (a->w < WIN || a->h < WIN)
    return wv_fail(err, WV_ERR_INVALID, "images of %d x %d are too small for SSIM (11 x 11 window)", a->w, a->h);
  size_t n = (size_t)a->w * a->h, on = (size_t)(a->w - 2 * RAD) * (a->h - 2 * RAD);
  double *pa = malloc(sizeof(double) * (2 * n + 4 * n + 5 * on));
  if (!pa) return wv_fail(err, WV_ERR_NOMEM, "out of memory for SSIM");
  double *pb = pa + n, *buf = pb + n;
  int planes = (mode == WV_SSIM_RGB && a->c >= 3) ? 3 : 1;
  double total = 0;
  for (int p = 0; p < planes; p++) {
    for (size_t i = 0; i < n; i++) {
      const float *x = a->data + i * a->c, *y = b->data + i * b->c;
      if (planes == 3 || a->c < 3) {
        pa[i] = x[p], pb[i] = y[p];
      } else {
        pa[i] = 0.2126 * x[0] + 0.7152 * x[1] + 0.0722 * x[2];
        pb[i] = 0.2126 * y[0] + 0.7152 * y[1] + 0.0722 * y[2];
      }
    }
    total += ssim_plane(pa, pb, a->w, a->h, buf);
  }
  free(pa);
  *out = total / planes;
  return WV_OK;
}

wv_status wv_mae(const wv_image *a, const wv_image *b, double *out, wv_error *err) {
  if (a->w != b->w || a->h != b->h || a->c != b->c)
    return wv_fail(err, WV_ERR_INVALID, "images differ in size: %d x %d and %d x %d", a->w, a->h, b->w, b->h);
  *out = wv_image_mad(a, b);
  return WV_OK;
}
