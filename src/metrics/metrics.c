/* Image comparison metrics: SSIM, mean absolute difference, and the weave's spectrum
 * (the luminance detail, its log power spectrum and the weave-spectrum correlation). */
#include "woven/metrics.h"

#include <fftw3.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "util/colour.h"
#include "util/select.h"

#define WIN 11
#define RAD 5

/* Separable Gaussian filter of one plane over the valid region: out is
 * (w - 10) x (h - 10). tmp holds w x (h - 10). Each value sums its taps k ascending from
 * 0; a row of values is summed at once, a tap at a time (independent sums, rows read
 * whole). Rows go to threads: the values do not depend on their number. */
static void blur_valid(const double *in, int w, int h, const double *g, double *tmp, double *out) {
  int oh = h - 2 * RAD, ow = w - 2 * RAD;
#pragma omp parallel for schedule(static)
  for (int y = 0; y < oh; y++) {
    double *t = tmp + (size_t)y * w;
    for (int x = 0; x < w; x++) t[x] = 0;
    for (int k = 0; k < WIN; k++) {
      const double *src = in + (size_t)(y + k) * w;
      for (int x = 0; x < w; x++) t[x] += g[k] * src[x];
    }
  }
#pragma omp parallel for schedule(static)
  for (int y = 0; y < oh; y++) {
    const double *t = tmp + (size_t)y * w;
    double *o = out + (size_t)y * ow;
    for (int x = 0; x < ow; x++) o[x] = 0;
    for (int k = 0; k < WIN; k++)
      for (int x = 0; x < ow; x++) o[x] += g[k] * t[x + k];
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
        pa[i] = wv_luminance_d(x[0], x[1], x[2]);
        pb[i] = wv_luminance_d(y[0], y[1], y[2]);
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

/* ---- the weave's spectrum ---- */

static const double PI = 3.14159265358979323846;

wv_status wv_image_detail(const wv_image *img, int x0, int y0, int w, int h, float *out, wv_error *err) {
  return wv_image_detail_window(img, x0, y0, w, h, 1, out, err);
}

wv_status wv_image_detail_window(const wv_image *img, int x0, int y0, int w, int h, int hann, float *out,
                                 wv_error *err) {
  if (w < 1 || h < 1 || x0 < 0 || y0 < 0 || x0 + w > img->w || y0 + h > img->h)
    return wv_fail(err, WV_ERR_INVALID, "detail window %d x %d at (%d, %d) is not inside the %d x %d image", w, h, x0,
                   y0, img->w, img->h);
  size_t n = (size_t)w * h;
  float *blur = malloc(sizeof(float) * n);
  double *hx = malloc(sizeof(double) * (size_t)(w + h)), *hy = hx + w;
  if (!blur || !hx) {
    free(blur), free(hx);
    return wv_fail(err, WV_ERR_NOMEM, "out of memory for a %d x %d detail image", w, h);
  }
  for (int y = 0; y < h; y++)
    for (int x = 0; x < w; x++) {
      const float *c = wv_image_px(img, x0 + x, y0 + y);
      out[(size_t)y * w + x] = img->c >= 3 ? wv_luminance_f(c[0], c[1], c[2]) : c[0];
    }
  wv_status st = wv_blur_plane(out, blur, w, h, 1, WV_DETAIL_SIGMA, err);
  if (st) {
    free(blur), free(hx);
    return st;
  }
  double m = 0, v = 0;
  for (size_t i = 0; i < n; i++) m += out[i] -= blur[i];
  m /= (double)n;
  for (size_t i = 0; i < n; i++) v += (out[i] - m) * (out[i] - m);
  double is = v > 1e-20 ? 1.0 / sqrt(v / (double)n) : 0.0; /* a flat window has no detail */
  for (int x = 0; x < w; x++) hx[x] = hann ? 0.5 - 0.5 * cos(2 * PI * (x + 0.5) / w) : 1;
  for (int y = 0; y < h; y++) hy[y] = hann ? 0.5 - 0.5 * cos(2 * PI * (y + 0.5) / h) : 1;
  for (int y = 0; y < h; y++)
    for (int x = 0; x < w; x++) {
      size_t i = (size_t)y * w + x;
      out[i] = (float)((out[i] - m) * is) * (float)(hx[x] * hy[y]);
    }
  free(blur), free(hx);
  return WV_OK;
}

wv_status wv_weave_spectrum(const wv_image *img, int x0, int y0, int n, float *out, wv_error *err) {
  if (n < 2 || n % 2)
    return wv_fail(err, WV_ERR_INVALID, "weave spectrum: the window side must be even and at least 2, not %d", n);
  int nc = n / 2 + 1;
  float *a = fftwf_alloc_real((size_t)n * n);
  fftwf_complex *f = fftwf_alloc_complex((size_t)n * nc);
  if (!a || !f) {
    fftwf_free(a), fftwf_free(f);
    return wv_fail(err, WV_ERR_NOMEM, "out of memory for a %d x %d spectrum", n, n);
  }
  wv_status st = wv_image_detail(img, x0, y0, n, n, a, err);
  fftwf_plan plan = NULL;
  if (!st) {
    /* FFTW's planner is not thread-safe; FFTW_ESTIMATE keeps results reproducible. */
#pragma omp critical(wv_fftw_planner)
    plan = fftwf_plan_dft_r2c_2d(n, n, a, f, FFTW_ESTIMATE);
    if (!plan) st = wv_fail(err, WV_ERR_NOMEM, "cannot plan a %d x %d FFT", n, n);
  }
  if (!st) {
    fftwf_execute(plan);
    /* Bin (u, v) of the half spectrum is row v mod n, column u; the other half is
     * its conjugate mirror: |F(-u, -v)| = |F(u, v)|. */
    for (int v = -n / 2; v < n / 2; v++)
      for (int u = -n / 2; u < n / 2; u++) {
        int uu = u, vv = v;
        if (uu < 0) uu = -uu, vv = -vv;
        const float *c = f[(size_t)((vv % n + n) % n) * nc + uu];
        double p = (double)c[0] * c[0] + (double)c[1] * c[1];
        out[(size_t)(v + n / 2) * n + (u + n / 2)] = (float)log1p(p);
      }
  }
  if (plan) {
#pragma omp critical(wv_fftw_planner)
    fftwf_destroy_plan(plan);
  }
  fftwf_free(a), fftwf_free(f);
  return st;
}

/* The logarithm of a noise spectrum's power has the same spread at every level, so z means
 * the same where a blur left little power; log(1 + P) would not (it is P itself where P is
 * small, and its fluctuations would look like peaks). */
wv_status wv_spectrum_whiten(const float *spec, int n, double floor_z, double cap_z, float *z, wv_error *err) {
  int nr = (int)(n * 0.7072) + 2;
  int *count = calloc((size_t)nr + 1, sizeof(int));
  float *vals = malloc(sizeof(float) * (size_t)n * n), *lg = malloc(sizeof(float) * (size_t)n * n);
  float *med = malloc(sizeof(float) * (size_t)nr * 2), *mad = med ? med + nr : NULL;
  int *start = malloc(sizeof(int) * ((size_t)nr + 1));
  if (!count || !vals || !lg || !med || !start) {
    free(count), free(vals), free(lg), free(med), free(start);
    return wv_fail(err, WV_ERR_NOMEM, "out of memory for a %d x %d prominence map", n, n);
  }
  size_t nn = (size_t)n * n;
  for (size_t i = 0; i < nn; i++) vals[i] = spec[i];
  double dead = 1e-6 * expm1((double)wv_select_float(vals, nn, nn / 2));
  for (size_t i = 0; i < nn; i++) lg[i] = (float)log(expm1((double)spec[i]) + 1e-30);
  spec = lg;
#define RING(u, v) ((int)(sqrt((double)(u) * (u) + (double)(v) * (v)) + 0.5))
  for (int v = -n / 2; v < n / 2; v++)
    for (int u = -n / 2; u < n / 2; u++) count[RING(u, v)]++;
  start[0] = 0;
  for (int r = 0; r < nr; r++) start[r + 1] = start[r] + count[r];
  memset(count, 0, sizeof(int) * (size_t)nr);
  for (int v = -n / 2; v < n / 2; v++)
    for (int u = -n / 2; u < n / 2; u++) {
      int r = RING(u, v);
      vals[start[r] + count[r]++] = spec[(size_t)(v + n / 2) * n + (u + n / 2)];
    }
  for (int r = 0; r < nr; r++) {
    float *a = vals + start[r];
    int c = count[r];
    med[r] = mad[r] = 0;
    if (c < 1) continue;
    med[r] = wv_select_float(a, (size_t)c, (size_t)c / 2);
    if (!(exp((double)med[r]) > dead)) continue; /* no power here: no peaks either (mad stays 0) */
    for (int i = 0; i < c; i++) a[i] = fabsf(a[i] - med[r]);
    mad[r] = 1.4826f * wv_select_float(a, (size_t)c, (size_t)c / 2);
  }
  for (int v = -n / 2; v < n / 2; v++)
    for (int u = -n / 2; u < n / 2; u++) {
      int r = RING(u, v);
      size_t i = (size_t)(v + n / 2) * n + (u + n / 2);
      double q = 0;
      /* a flat spectrum (a flat image) has no prominence anywhere */
      if ((double)u * u + (double)v * v > WV_WSC_DC_RADIUS * WV_WSC_DC_RADIUS && mad[r] > 1e-6f)
        q = (spec[i] - med[r]) / mad[r];
      q -= floor_z;
      z[i] = (float)(q < 0 ? 0 : q > cap_z - floor_z ? cap_z - floor_z : q);
    }
#undef RING
  free(count), free(vals), free(lg), free(med), free(start);
  return WV_OK;
}


/* A bin of the detail's power spectrum is a peak when it holds at least this many times the
 * mean of the (2 r + 1)^2 bins about it. */
#define PERIODIC_RATIO 8.0
#define PERIODIC_HALF 4

wv_status wv_detail_periodic(const wv_image *img, double sigma, double *share, wv_image *periodic, wv_error *err) {
  if (img->w < 2 * PERIODIC_HALF + 1 || img->h < 2 * PERIODIC_HALF + 1 || img->c < 3)
    return wv_fail(err, WV_ERR_INVALID, "the periodic share needs an RGB image of at least %d x %d, not %d x %d x %d",
                   2 * PERIODIC_HALF + 1, 2 * PERIODIC_HALF + 1, img->w, img->h, img->c);
  int w = img->w, h = img->h, wc = w / 2 + 1;
  size_t np = (size_t)w * h, nf = (size_t)h * wc;
  wv_image low = {0};
  wv_status st = wv_image_blur(img, sigma, &low, err);
  if (st) return st;
  if (periodic && (st = wv_image_alloc(periodic, w, h, 3, err))) {
    wv_image_free(&low);
    return st;
  }
  float *x = fftwf_alloc_real(np);
  fftwf_complex *f = fftwf_alloc_complex(nf);
  double *pw = malloc(sizeof(double) * nf);
  unsigned char *mask = calloc(nf, 1);
  fftwf_plan fwd = NULL, inv = NULL;
  if (!x || !f || !pw || !mask) st = wv_fail(err, WV_ERR_NOMEM, "out of memory for a %d x %d spectrum", w, h);
  if (!st) {
#pragma omp critical(wv_fftw_planner)
    {
      fwd = fftwf_plan_dft_r2c_2d(h, w, x, f, FFTW_ESTIMATE);
      inv = periodic ? fftwf_plan_dft_c2r_2d(h, w, f, x, FFTW_ESTIMATE) : NULL;
    }
    if (!fwd || (periodic && !inv)) st = wv_fail(err, WV_ERR_NOMEM, "cannot plan a %d x %d FFT", w, h);
  }
  if (!st) {
    for (size_t i = 0; i < np; i++) {
      const float *p = img->data + i * img->c, *l = low.data + i * low.c;
      x[i] = (float)wv_luminance_d(p[0] - l[0], p[1] - l[1], p[2] - l[2]);
    }
    fftwf_execute(fwd);
    for (size_t i = 0; i < nf; i++) pw[i] = (double)f[i][0] * f[i][0] + (double)f[i][1] * f[i][1];
    double total = 0, peaks = 0;
    for (int v = 0; v < h; v++)
      for (int u = 0; u < wc; u++) {
        double m = 0;
        for (int dv = -PERIODIC_HALF; dv <= PERIODIC_HALF; dv++)
          for (int du = -PERIODIC_HALF; du <= PERIODIC_HALF; du++) {
            int uu = u + du, vv = ((v + dv) % h + h) % h;
            if (uu < 0 || uu >= wc) uu = uu < 0 ? -uu : w - uu, vv = (h - vv) % h; /* the conjugate half */
            m += pw[(size_t)vv * wc + uu];
          }
        m /= (2 * PERIODIC_HALF + 1) * (2 * PERIODIC_HALF + 1);
        size_t i = (size_t)v * wc + u;
        int twice = !(u == 0 || (w % 2 == 0 && u == wc - 1)); /* the bin stands for its mirror too */
        total += (1 + twice) * pw[i];
        if ((u || v) && pw[i] >= PERIODIC_RATIO * m && pw[i] > 0) mask[i] = 1, peaks += (1 + twice) * pw[i];
      }
    *share = total > 0 ? peaks / total : 0;
    for (int c = 0; periodic && c < 3; c++) {
      for (size_t i = 0; i < np; i++) x[i] = img->data[i * img->c + c] - low.data[i * low.c + c];
      fftwf_execute(fwd);
      for (size_t i = 0; i < nf; i++)
        if (!mask[i]) f[i][0] = f[i][1] = 0;
      fftwf_execute(inv);
      for (size_t i = 0; i < np; i++) periodic->data[i * 3 + c] = x[i] / (float)np;
    }
  }
#pragma omp critical(wv_fftw_planner)
  {
    if (fwd) fftwf_destroy_plan(fwd);
    if (inv) fftwf_destroy_plan(inv);
  }
  fftwf_free(x), fftwf_free(f), free(pw), free(mask);
  wv_image_free(&low);
  if (st && periodic) wv_image_free(periodic);
  return st;
}

double wv_wsc_spectra(const float *sa, const float *sb, int n) {
  double ma = 0, mb = 0;
  long cnt = 0;
  const double r2 = WV_WSC_DC_RADIUS * WV_WSC_DC_RADIUS;
  for (int pass = 0; pass < 2; pass++) {
    double saa = 0, sbb = 0, sab = 0;
    for (int v = -n / 2; v < n / 2; v++)
      for (int u = -n / 2; u < n / 2; u++) {
        if ((double)u * u + (double)v * v <= r2) continue;
        size_t i = (size_t)(v + n / 2) * n + (u + n / 2);
        if (pass == 0) {
          ma += sa[i], mb += sb[i], cnt++;
        } else {
          double da = sa[i] - ma, db = sb[i] - mb;
          saa += da * da, sbb += db * db, sab += da * db;
        }
      }
    if (pass == 0) {
      if (!cnt) return 0;
      ma /= (double)cnt, mb /= (double)cnt;
    } else {
      return saa > 0 && sbb > 0 ? sab / sqrt(saa * sbb) : 0.0; /* a flat spectrum correlates with nothing */
    }
  }
  return 0;
}

/* The side of the centred window WSC compares: WV_WSC_SIZE, or the largest even square both hold. */
static wv_status wsc_side(const wv_image *a, const wv_image *b, int *out, wv_error *err) {
  int n = WV_WSC_SIZE;
  int side = a->w < a->h ? a->w : a->h;
  if (b->w < side) side = b->w;
  if (b->h < side) side = b->h;
  if (side < n) n = side - side % 2;
  if (n < 32)
    return wv_fail(err, WV_ERR_INVALID, "images of %d x %d and %d x %d are too small for WSC (at least 32 x 32)", a->w,
                   a->h, b->w, b->h);
  *out = n;
  return WV_OK;
}

wv_status wv_wsc(const wv_image *a, const wv_image *b, double *out, wv_error *err) {
  int n;
  if (wsc_side(a, b, &n, err)) return WV_ERR_INVALID;
  float *sa = malloc(sizeof(float) * (size_t)n * n * 2), *sb = sa ? sa + (size_t)n * n : NULL;
  if (!sa) return wv_fail(err, WV_ERR_NOMEM, "out of memory for WSC");
  wv_status st = wv_weave_spectrum(a, (a->w - n) / 2, (a->h - n) / 2, n, sa, err);
  if (!st) st = wv_weave_spectrum(b, (b->w - n) / 2, (b->h - n) / 2, n, sb, err);
  if (!st) *out = wv_wsc_spectra(sa, sb, n);
  free(sa);
  return st;
}

wv_status wv_wsc_whitened(const wv_image *a, const wv_image *b, double *out, wv_error *err) {
  int n;
  if (wsc_side(a, b, &n, err)) return WV_ERR_INVALID;
  size_t nn = (size_t)n * n;
  float *sa = malloc(sizeof(float) * nn * 4), *sb = sa ? sa + nn : NULL, *za = sa ? sa + 2 * nn : NULL,
        *zb = sa ? sa + 3 * nn : NULL;
  if (!sa) return wv_fail(err, WV_ERR_NOMEM, "out of memory for WSC");
  wv_status st = wv_weave_spectrum(a, (a->w - n) / 2, (a->h - n) / 2, n, sa, err);
  if (!st) st = wv_weave_spectrum(b, (b->w - n) / 2, (b->h - n) / 2, n, sb, err);
  if (!st) st = wv_spectrum_whiten(sa, n, WV_WSC_Z_FLOOR, WV_WSC_Z_CAP, za, err);
  if (!st) st = wv_spectrum_whiten(sb, n, WV_WSC_Z_FLOOR, WV_WSC_Z_CAP, zb, err);
  if (!st) *out = wv_wsc_spectra(za, zb, n);
  free(sa);
  return st;
}
