/* Image operations with adjoints, for losses on processed renders. */
#include "woven/imgops.h"

#include <math.h>
#include <stdlib.h>

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
   * every din value is written once (no accumulation order to worry about). */
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

/* ---- sensor response pieces ---- */

double wv_encode_d(const wv_scene *s, double x) {
  if (x <= 0.0) return 0.0;
  switch (s->encoding) {
    case WV_ENC_SRGB: return x <= 0.0031308 ? 12.92 * x : 1.055 * pow(x, 1.0 / 2.4) - 0.055;
    case WV_ENC_GAMMA: return pow(x, 1.0 / s->gamma);
    default: return x;
  }
}

double wv_encode_slope(const wv_scene *s, double x) {
  if (x <= 0.0) return 0.0;
  switch (s->encoding) {
    case WV_ENC_SRGB: return x <= 0.0031308 ? 12.92 : 1.055 / 2.4 * pow(x, 1.0 / 2.4 - 1.0);
    case WV_ENC_GAMMA: return pow(x, 1.0 / s->gamma - 1.0) / s->gamma;
    default: return 1.0;
  }
}

/* The same expression as response.c, so the float mask is bitwise the same. */
double wv_falloff_mask(const wv_scene *s, int x, int y) {
  if (!s->falloff) return 1.0;
  double dx = x + 0.5 - 0.5 * s->width, dy = y + 0.5 - 0.5 * s->height;
  return exp(-(dx * dx + dy * dy) / (s->falloff_sigma * s->falloff_sigma));
}

static size_t count(const wv_image *im) { return (size_t)im->w * im->h * im->c; }

void wv_image_encode(const wv_scene *s, const wv_image *in, wv_image *out) {
  for (size_t i = 0, n = count(in); i < n; i++) out->data[i] = wv_encode(s, in->data[i]);
}

void wv_image_encode_backward(const wv_scene *s, const wv_image *in, const wv_image *dout, wv_image *din) {
  for (size_t i = 0, n = count(in); i < n; i++)
    din->data[i] = (float)(dout->data[i] * wv_encode_slope(s, in->data[i]));
}

void wv_image_clip(const wv_image *in, float clip, wv_image *out) {
  for (size_t i = 0, n = count(in); i < n; i++) {
    float v = in->data[i];
    out->data[i] = clip > 0.0f && v > clip ? clip : v;
  }
}

void wv_image_clip_backward(const wv_image *in, float clip, const wv_image *dout, wv_image *din) {
  for (size_t i = 0, n = count(in); i < n; i++)
    din->data[i] = clip > 0.0f && in->data[i] > clip ? 0.0f : dout->data[i];
}

void wv_image_mask(const wv_scene *s, const wv_image *in, wv_image *out) {
  for (int y = 0; y < in->h; y++)
    for (int x = 0; x < in->w; x++) {
      float m = (float)wv_falloff_mask(s, x, y);
      const float *p = wv_image_px(in, x, y);
      float *o = wv_image_px(out, x, y);
      for (int c = 0; c < in->c; c++) o[c] = m * p[c];
    }
}

void wv_image_mask_backward(const wv_scene *s, const wv_image *dout, wv_image *din) {
  wv_image_mask(s, dout, din); /* the mask is a diagonal linear map: its own adjoint */
}

void wv_image_scale(const wv_image *in, float k, wv_image *out) {
  for (size_t i = 0, n = count(in); i < n; i++) out->data[i] = k * in->data[i];
}

double wv_image_l1(const wv_image *a, const wv_image *b, wv_image *da) {
  if (a->w != b->w || a->h != b->h || a->c != b->c) return -1.0;
  size_t n = count(a);
  double sum = 0.0, inv = 1.0 / (double)n;
  for (size_t i = 0; i < n; i++) {
    double d = (double)a->data[i] - (double)b->data[i];
    sum += fabs(d);
    if (da) da->data[i] = d > 0 ? (float)inv : d < 0 ? (float)-inv : 0.0f;
  }
  return sum * inv;
}

/* ---- Gaussian blur and 8-bit quantisation ---- */

wv_status wv_image_blur(const wv_image *in, double sigma, wv_image *out, wv_error *err) {
  wv_status st = wv_image_alloc(out, in->w, in->h, in->c, err);
  if (st) return st;
  size_t n = (size_t)in->w * in->h * in->c;
  int r = sigma > 0 ? (int)ceil(3 * sigma) : 0;
  if (r == 0) {
    for (size_t i = 0; i < n; i++) out->data[i] = in->data[i];
    return WV_OK;
  }
  double *g = malloc(sizeof(double) * (size_t)(2 * r + 1)), gs = 0;
  float *tmp = malloc(sizeof(float) * n);
  if (!g || !tmp) {
    free(g), free(tmp), wv_image_free(out);
    return wv_fail(err, WV_ERR_NOMEM, "out of memory for a blur");
  }
  for (int k = -r; k <= r; k++) gs += g[k + r] = exp(-0.5 * k * k / (sigma * sigma));
  for (int k = 0; k <= 2 * r; k++) g[k] /= gs;
  int w = in->w, h = in->h, c = in->c;
  for (int y = 0; y < h; y++) /* along x into tmp */
    for (int x = 0; x < w; x++)
      for (int ch = 0; ch < c; ch++) {
        double s = 0;
        for (int k = -r; k <= r; k++) {
          int xx = x + k < 0 ? 0 : x + k >= w ? w - 1 : x + k;
          s += g[k + r] * in->data[((size_t)y * w + xx) * c + ch];
        }
        tmp[((size_t)y * w + x) * c + ch] = (float)s;
      }
  for (int y = 0; y < h; y++) /* along y into out */
    for (int x = 0; x < w; x++)
      for (int ch = 0; ch < c; ch++) {
        double s = 0;
        for (int k = -r; k <= r; k++) {
          int yy = y + k < 0 ? 0 : y + k >= h ? h - 1 : y + k;
          s += g[k + r] * tmp[((size_t)yy * w + x) * c + ch];
        }
        out->data[((size_t)y * w + x) * c + ch] = (float)s;
      }
  free(g), free(tmp);
  return WV_OK;
}

void wv_image_quantise8(wv_image *img) {
  size_t n = (size_t)img->w * img->h * img->c;
  for (size_t i = 0; i < n; i++) {
    float v = img->data[i] < 0 ? 0 : img->data[i] > 1 ? 1 : img->data[i];
    img->data[i] = floorf(v * 255.0f + 0.5f) / 255.0f;
  }
}
