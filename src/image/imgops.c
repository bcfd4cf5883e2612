/* Image operations with adjoints, for losses on processed renders: area
 * downsampling and its transpose, the L1 difference. */
#include "woven/imgops.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "woven/nn.h"

/* ---- area downsampling ---- */

/* Covered length of input cell [i, i+1) by output cell [o f, (o+1) f). */
static double overlap(int i, int o, double f) {
  double a = o * f, b = (o + 1) * f;
  double lo = i > a ? i : a, hi = i + 1 < b ? i + 1 : b;
  return hi > lo ? hi - lo : 0.0;
}

/* Input indices an output cell may touch (one extra on each side against
 * rounding; overlap() gives the extras weight 0). */
static void span(int o, double f, int n_in, int *i0, int *i1) {
  *i0 = (int)floor(o * f) - 1;
  *i1 = (int)ceil((o + 1) * f);
  if (*i0 < 0) *i0 = 0;
  if (*i1 > n_in - 1) *i1 = n_in - 1;
}

static wv_status check_size(int w, int h, wv_error *err) {
  if (w < 1 || h < 1) return wv_fail(err, WV_ERR_INVALID, "image size %d x %d must be positive", w, h);
  return WV_OK;
}

wv_status wv_image_downsample(const wv_image *in, int w, int h, wv_image *out, wv_error *err) {
  wv_status st = check_size(w, h, err);
  if (st) return st;
  if (!in || !in->data) return wv_fail(err, WV_ERR_INVALID, "downsample: no input image");
  if ((st = wv_image_alloc(out, w, h, in->c, err))) return st;
  double fx = (double)in->w / w, fy = (double)in->h / h, norm = 1.0 / (fx * fy);
  /* each output row is its own: the same values on any number of threads */
#pragma omp parallel for schedule(static)
  for (int Y = 0; Y < h; Y++) {
    int y0, y1;
    span(Y, fy, in->h, &y0, &y1);
    for (int X = 0; X < w; X++) {
      int x0, x1;
      span(X, fx, in->w, &x0, &x1);
      double acc[4] = {0, 0, 0, 0};
      for (int y = y0; y <= y1; y++) {
        double wy = overlap(y, Y, fy);
        for (int x = x0; x <= x1; x++) {
          double wxy = wy * overlap(x, X, fx);
          const float *p = wv_image_px(in, x, y);
          for (int c = 0; c < in->c; c++) acc[c] += wxy * p[c];
        }
      }
      float *o = wv_image_px(out, X, Y);
      for (int c = 0; c < in->c; c++) o[c] = (float)(acc[c] * norm);
    }
  }
  return WV_OK;
}

wv_status wv_image_downsample_backward(int in_w, int in_h, const wv_image *dout, wv_image *din, wv_error *err) {
  wv_status st = check_size(in_w, in_h, err);
  if (st) return st;
  if (!dout || !dout->data) return wv_fail(err, WV_ERR_INVALID, "downsample backward: no adjoint image");
  if ((st = wv_image_alloc(din, in_w, in_h, dout->c, err))) return st;
  int w = dout->w, h = dout->h;
  double fx = (double)in_w / w, fy = (double)in_h / h, norm = 1.0 / (fx * fy);
  /* Gather form: each input pixel sums the output cells that cover it, so
   * every din value is written once (no accumulation order to worry about), and rows
   * can go to threads. */
#pragma omp parallel for schedule(static)
  for (int y = 0; y < in_h; y++) {
    int Y0, Y1;
    span(y, 1.0 / fy, h, &Y0, &Y1);
    for (int x = 0; x < in_w; x++) {
      int X0, X1;
      span(x, 1.0 / fx, w, &X0, &X1);
      double acc[4] = {0, 0, 0, 0};
      for (int Y = Y0; Y <= Y1; Y++) {
        double wy = overlap(y, Y, fy);
        if (wy <= 0) continue;
        for (int X = X0; X <= X1; X++) {
          double wxy = wy * overlap(x, X, fx);
          if (wxy <= 0) continue;
          const float *g = wv_image_px(dout, X, Y);
          for (int c = 0; c < dout->c; c++) acc[c] += wxy * g[c];
        }
      }
      float *o = wv_image_px(din, x, y);
      for (int c = 0; c < dout->c; c++) o[c] = (float)(acc[c] * norm);
    }
  }
  return WV_OK;
}

static size_t count(const wv_image *im) { return (size_t)im->w * im->h * im->c; }

double wv_image_l1(const wv_image *a, const wv_image *b, wv_image *da) {
  if (a->w != b->w || a->h != b->h || a->c != b->c) return -1.0;
  size_t n = count(a);
  double inv = 1.0 / (double)n;
  if (da) memset(da->data, 0, n * sizeof *da->data);
  return wv_nn_l1(a->data, b->data, n, 0, da ? da->data : NULL, (float)inv) * inv;
}

/* ---- 8-bit quantisation ---- */

void wv_image_quantise8(wv_image *img) {
  size_t n = (size_t)img->w * img->h * img->c;
  for (size_t i = 0; i < n; i++) {
    float v = img->data[i] < 0 ? 0 : img->data[i] > 1 ? 1 : img->data[i];
    img->data[i] = floorf(v * 255.0f + 0.5f) / 255.0f;
  }
}
