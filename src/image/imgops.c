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

/* For each index k of one axis, the indices j of the other that span(k, f_span, n_other)
 * gives and their overlaps: overlap(j, k, f) (out: k an output cell, j its inputs) or
 * overlap(k, j, f) (k an input, j the output cells over it). Made once per call, so the
 * loops over pixels read the weights instead of making them again for every row. */
typedef struct {
  int *lo, *len; /* k's first j and how many */
  size_t *at;    /* where k's weights start in wt */
  double *wt;
} span_table;

static void table_free(span_table *t) {
  free(t->lo), free(t->len), free(t->at), free(t->wt);
}

static wv_status table_make(int n, int n_other, double f_span, double f, int out, span_table *t, wv_error *err) {
  memset(t, 0, sizeof *t);
  t->lo = malloc(sizeof(int) * (size_t)n), t->len = malloc(sizeof(int) * (size_t)n);
  t->at = malloc(sizeof(size_t) * (size_t)n);
  size_t total = 0;
  for (int k = 0; t->lo && t->len && t->at && k < n; k++) {
    int j0, j1;
    span(k, f_span, n_other, &j0, &j1);
    t->lo[k] = j0, t->len[k] = j1 >= j0 ? j1 - j0 + 1 : 0, t->at[k] = total;
    total += (size_t)t->len[k];
  }
  if (t->lo && t->len && t->at) t->wt = malloc(sizeof(double) * (total ? total : 1));
  if (!t->wt) {
    table_free(t);
    return wv_fail(err, WV_ERR_NOMEM, "out of memory for the downsampling's weights");
  }
  for (int k = 0; k < n; k++)
    for (int i = 0; i < t->len[k]; i++) {
      int j = t->lo[k] + i;
      t->wt[t->at[k] + (size_t)i] = out ? overlap(j, k, f) : overlap(k, j, f);
    }
  return WV_OK;
}

wv_status wv_image_downsample(const wv_image *in, int w, int h, wv_image *out, wv_error *err) {
  wv_status st = check_size(w, h, err);
  if (st) return st;
  if (!in || !in->data) return wv_fail(err, WV_ERR_INVALID, "downsample: no input image");
  double fx = (double)in->w / w, fy = (double)in->h / h, norm = 1.0 / (fx * fy);
  span_table tx, ty;
  if ((st = table_make(w, in->w, fx, fx, 1, &tx, err))) return st;
  if ((st = table_make(h, in->h, fy, fy, 1, &ty, err))) {
    table_free(&tx);
    return st;
  }
  if ((st = wv_image_alloc(out, w, h, in->c, err))) {
    table_free(&tx), table_free(&ty);
    return st;
  }
  /* each output row is its own: the same values on any number of threads */
#pragma omp parallel for schedule(static)
  for (int Y = 0; Y < h; Y++) {
    const double *wy = ty.wt + ty.at[Y];
    for (int X = 0; X < w; X++) {
      const double *wx = tx.wt + tx.at[X];
      double acc[4] = {0, 0, 0, 0};
      for (int a = 0; a < ty.len[Y]; a++) {
        int y = ty.lo[Y] + a;
        for (int b = 0; b < tx.len[X]; b++) {
          double wxy = wy[a] * wx[b];
          const float *p = wv_image_px(in, tx.lo[X] + b, y);
          for (int c = 0; c < in->c; c++) acc[c] += wxy * p[c];
        }
      }
      float *o = wv_image_px(out, X, Y);
      for (int c = 0; c < in->c; c++) o[c] = (float)(acc[c] * norm);
    }
  }
  table_free(&tx), table_free(&ty);
  return WV_OK;
}

wv_status wv_image_downsample_backward(int in_w, int in_h, const wv_image *dout, wv_image *din, wv_error *err) {
  wv_status st = check_size(in_w, in_h, err);
  if (st) return st;
  if (!dout || !dout->data) return wv_fail(err, WV_ERR_INVALID, "downsample backward: no adjoint image");
  int w = dout->w, h = dout->h;
  double fx = (double)in_w / w, fy = (double)in_h / h, norm = 1.0 / (fx * fy);
  span_table tx, ty;
  if ((st = table_make(in_w, w, 1.0 / fx, fx, 0, &tx, err))) return st;
  if ((st = table_make(in_h, h, 1.0 / fy, fy, 0, &ty, err))) {
    table_free(&tx);
    return st;
  }
  if ((st = wv_image_alloc(din, in_w, in_h, dout->c, err))) {
    table_free(&tx), table_free(&ty);
    return st;
  }
  /* Gather form: each input pixel sums the output cells that cover it, so
   * every din value is written once (no accumulation order to worry about), and rows
   * can go to threads. */
#pragma omp parallel for schedule(static)
  for (int y = 0; y < in_h; y++) {
    const double *wy = ty.wt + ty.at[y];
    for (int x = 0; x < in_w; x++) {
      const double *wx = tx.wt + tx.at[x];
      double acc[4] = {0, 0, 0, 0};
      for (int a = 0; a < ty.len[y]; a++) {
        if (wy[a] <= 0) continue;
        int Y = ty.lo[y] + a;
        for (int b = 0; b < tx.len[x]; b++) {
          double wxy = wy[a] * wx[b];
          if (wxy <= 0) continue;
          const float *g = wv_image_px(dout, tx.lo[x] + b, Y);
          for (int c = 0; c < dout->c; c++) acc[c] += wxy * g[c];
        }
      }
      float *o = wv_image_px(din, x, y);
      for (int c = 0; c < dout->c; c++) o[c] = (float)(acc[c] * norm);
    }
  }
  table_free(&tx), table_free(&ty);
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
