/* The sensor response (what the camera does to radiance before we compare to a
 * photo): the camera blur (a Gaussian point-spread function on the radiance) and its
 * adjoint, the adjoint's encoding slope, the falloff mask, the image response and the
 * public per-value encoding and its inverse. The per-value response itself is
 * sensor/response_impl.h. */
#include <math.h>
#include <omp.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "sensor/sensor.h"
#include "util/vmath.h"
#include "woven/scene.h"

float wv_encode(const wv_scene *s, float x) { return wv_encode_f(s, x); }

float wv_decode(const wv_scene *s, float y) {
  if (y <= 0.0f) return 0.0f;
  switch (s->encoding) {
    case WV_ENC_SRGB: return wv_srgb_decode_f(y);
    case WV_ENC_GAMMA: return powf(y, (float)s->gamma);
    default: return y;
  }
}

float wv_power_f(float x, float e) {
  float y;
  wv_powf_n(&x, e, &y, 1);
  return y;
}

double wv_power_d(double x, double e) {
  double y;
  wv_pow_n(&x, e, &y, 1);
  return y;
}

double wv_slope_exponent(const wv_scene *s) {
  switch (s->encoding) {
    case WV_ENC_SRGB: return 1.0 / 2.4 - 1.0;
    case WV_ENC_GAMMA: return 1.0 / s->gamma - 1.0;
    default: return 0.0;
  }
}

double wv_encode_slope(const wv_scene *s, double x) {
  double p = x > 0.0 && s->encoding != WV_ENC_LINEAR ? wv_power_d(x, wv_slope_exponent(s)) : 0.0;
  return wv_encode_slope_pow(s->encoding, s->gamma, x, p);
}

/* Blocks of RESP_B values: the powers of a block are taken at once, from the stack. */
#define RESP_B 256

void wv_respond_n(const wv_scene *s, const double *mask, int n, int c, const float *rad, float *cap, double *slope) {
  float v[RESP_B], pe[RESP_B];
  double vd[RESP_B], ps[RESP_B], mv[RESP_B];
  int clipped[RESP_B], per = c > 0 ? RESP_B / c : 0, powered = s->encoding != WV_ENC_LINEAR;
  if (per < 1) return; /* images have 1 to 4 channels */
  for (int p0 = 0; p0 < n; p0 += per) {
    int np = n - p0 < per ? n - p0 : per, m = np * c;
    const float *in = rad + (size_t)p0 * c;
    for (int j = 0; j < m; j++) {
      v[j] = wv_expose_f(s, in[j], &clipped[j]);
      vd[j] = v[j], pe[j] = 0.0f, ps[j] = 0.0;
    }
    for (int k = 0; k < np; k++)
      for (int ch = 0; ch < c; ch++) mv[k * c + ch] = mask ? mask[p0 + k] : 1.0;
    if (powered) {
      wv_powf_n(v, wv_encode_exponent_f(s), pe, m);
      if (slope) wv_pow_n(vd, wv_slope_exponent(s), ps, m);
    }
    float *out = cap + (size_t)p0 * c;
    double *sl = slope ? slope + (size_t)p0 * c : NULL;
    /* one vector loop for each encoding, with and without slopes: the encoding a constant
     * in each */
#define RESPOND_BLOCK(enc)                                                                         \
  if (sl) {                                                                                        \
    _Pragma("omp simd") for (int j = 0; j < m; j++) out[j] =                                       \
        wv_respond_pow_f(s, enc, mv[j], v[j], clipped[j], pe[j], ps[j], sl + j);                   \
  } else {                                                                                         \
    _Pragma("omp simd") for (int j = 0; j < m; j++) out[j] =                                       \
        wv_respond_pow_f(s, enc, mv[j], v[j], clipped[j], pe[j], ps[j], NULL);                     \
  }
    switch (s->encoding) {
      case WV_ENC_SRGB: RESPOND_BLOCK(WV_ENC_SRGB) break;
      case WV_ENC_GAMMA: RESPOND_BLOCK(WV_ENC_GAMMA) break;
      default: RESPOND_BLOCK(WV_ENC_LINEAR)
    }
#undef RESPOND_BLOCK
  }
}

double wv_pixel_gaussian(int w, int h, int x, int y, double sigma) {
  double dx = x + 0.5 - 0.5 * w, dy = y + 0.5 - 0.5 * h;
  return exp(-(dx * dx + dy * dy) / (sigma * sigma));
}

double wv_response_mask(const wv_scene *s, int x, int y) {
  if (!s->falloff) return 1.0;
  return wv_pixel_gaussian(s->width, s->height, x, y, s->falloff_sigma);
}

void wv_response_mask_row(const wv_scene *s, int x0, int y, int n, double *mask) {
  for (int i = 0; i < n; i++) mask[i] = wv_response_mask(s, x0 + i, y);
}

void wv_scene_response(const wv_scene *s, const wv_image *rad, wv_image *cap) {
  int c = rad->c, per = c > 0 ? RESP_B / c : 0;
  if (per < 1) return;
#pragma omp parallel for schedule(static)
  for (int y = 0; y < rad->h; y++) {
    double mask[RESP_B];
    for (int x0 = 0; x0 < rad->w; x0 += per) { /* blocks of the row, from the stack */
      int n = rad->w - x0 < per ? rad->w - x0 : per;
      wv_response_mask_row(s, x0, y, n, mask);
      wv_respond_n(s, mask, n, c, wv_image_px(rad, x0, y), wv_image_px(cap, x0, y), NULL);
    }
  }
}

/* The camera blur, K = Ky Kx: a 1-D Gaussian along x on each row, then along y.
 * Every value of K v sums its terms with k ascending (v at the clamped i + k); every
 * value q of K^T v sums them in the order of the plain transpose loop "for each source
 * i ascending, for each k ascending, add to clamp(i + k)". Values whose terms reach no
 * clamped edge take the same sum either way (the kernel is symmetric), so a row's inner
 * values are summed a whole row at a time, one tap at a time (vectorised), and only the
 * r values at each end take the loops with clamping. Everything below follows these
 * orders, so a value does not depend on the threads, the bands or the path. */

#define PSF_R_MAX (3 * (int)WV_PSF_MAX_SIGMA + 1) /* the largest radius, ceil(3 sigma) */
#define PSF_TERMS_MAX (2 * (2 * PSF_R_MAX + 1) * (2 * PSF_R_MAX + 1)) /* of a value of K^T or dK */

/* out[e] = sum over the terms t in order of wt[t] * src[t][e], e < m, each value summed
 * term after term from 0; a block of values at a time, so the sums stay in cache. */
WV_SIMD_CLONES
static void psf_terms(int nt, const double *wt, const double *const *src, size_t m, double *restrict out) {
  enum { B = 64 };
  for (size_t e0 = 0; e0 < m; e0 += B) {
    size_t nb = m - e0 < B ? m - e0 : B;
    double acc[B] = {0};
    for (int t = 0; t < nt; t++) {
      const double *restrict s = src[t] + e0;
      double w = wt[t];
#pragma omp simd
      for (size_t j = 0; j < nb; j++) acc[j] += w * s[j];
    }
    memcpy(out + e0, acc, nb * sizeof *out);
  }
}

/* One line of n values (c interleaved channels) along x: out = K in, or K^T in. */
static void psf_line(const double *wk, int r, int n, int c, const double *in, double *out, int adjoint) {
  int lo = r < n ? r : n, hi = n - r > lo ? n - r : lo; /* [lo, hi): the inner values */
  double wt[2 * PSF_R_MAX + 1];
  const double *src[2 * PSF_R_MAX + 1];
  if (hi > lo) {
    for (int k = -r; k <= r; k++) /* K: in[q + k], k ascending; K^T: in[q - k], its sources ascending */
      wt[k + r] = wk[k < 0 ? -k : k], src[k + r] = in + (ptrdiff_t)(lo + k) * c;
    psf_terms(2 * r + 1, wt, src, (size_t)(hi - lo) * c, out + (size_t)lo * c);
  }
  for (int q = 0; q < n; q++) {
    if (q == lo && hi > lo) q = hi; /* the inner values are done */
    if (q >= n) break;
    double *o = out + (size_t)q * c;
    for (int ch = 0; ch < c; ch++) o[ch] = 0;
    if (!adjoint) {
      for (int k = -r; k <= r; k++) {
        int i = q + k < 0 ? 0 : q + k >= n ? n - 1 : q + k; /* clamped edge */
        for (int ch = 0; ch < c; ch++) o[ch] += wk[k < 0 ? -k : k] * in[(size_t)i * c + ch];
      }
      continue;
    }
    for (int i = q - r < 0 ? 0 : q - r; i <= q + r && i < n; i++)
      for (int k = -r; k <= r; k++) {
        int t = i + k < 0 ? 0 : i + k >= n ? n - 1 : i + k;
        if (t != q) continue;
        for (int ch = 0; ch < c; ch++) o[ch] += wk[k < 0 ? -k : k] * in[(size_t)i * c + ch];
      }
  }
}

/* The terms of row q of the blur along y of h rows, appended to wt / src: K takes rows
 * clamp(q + k), K^T the rows i with clamp(i + k) = q, in the orders above. Source row i
 * is ring[i % slots]. Returns the new count. */
static int psf_column(const double *wk, int r, int h, int q, int adjoint, double *const *ring, int slots, int nt,
                      double *wt, const double **src) {
  for (int i = adjoint ? (q - r < 0 ? 0 : q - r) : 0; i <= (adjoint ? q + r : 0) && i < h; i++)
    for (int k = -r; k <= r; k++) {
      int t = (adjoint ? i : q) + k;
      t = t < 0 ? 0 : t >= h ? h - 1 : t;
      if (adjoint && t != q) continue;
      wt[nt] = wk[k < 0 ? -k : k], src[nt++] = ring[(adjoint ? i : t) % slots];
    }
  return nt;
}

/* The 1-D kernel of the camera blur: wk[0..r] (symmetric, summing to 1 over -r..r) and,
 * when dwk is given, its derivative by sigma. With e_k = exp(-k^2 / 2 sigma^2) and
 * w_k = e_k / S, S = sum_j e_j: dw_k/dsigma = w_k (k^2 - sum_j w_j j^2) / sigma^3. */
static int psf_kernel(double sigma, double *wk, double *dwk) {
  int r = (int)ceil(3 * sigma);
  double sum = 0, m2 = 0;
  for (int k = 0; k <= r; k++) sum += (k ? 2 : 1) * (wk[k] = exp(-0.5 * k * k / (sigma * sigma)));
  for (int k = 0; k <= r; k++) wk[k] /= sum, m2 += (k ? 2 : 1) * wk[k] * k * k;
  if (dwk)
    for (int k = 0; k <= r; k++) dwk[k] = wk[k] * (k * k - m2) / (sigma * sigma * sigma);
  return r;
}

static wv_status psf_check(double sigma, wv_error *err) {
  if (!(sigma <= WV_PSF_MAX_SIGMA))
    return wv_fail(err, WV_ERR_INVALID, "camera blur sigma %g px is outside 0..%g", sigma, WV_PSF_MAX_SIGMA);
  return WV_OK;
}

/* Rows y0 .. y1-1 of the result, with a ring of 2r + 1 prepared source rows: K's are
 * Kx of the input rows, K^T's the input rows, dK's both Kx and dKx of them. */
static void psf_band(const wv_psf_stream *ps, const double *wk, const double *dwk, int r, int y0, int y1,
                     double *buf) {
  size_t m = (size_t)ps->w * ps->c;
  int slots = 2 * r + 1, h = ps->h;
  double *ring[2 * PSF_R_MAX + 1], *dring[2 * PSF_R_MAX + 1];
  for (int j = 0; j < slots; j++) ring[j] = buf + j * m, dring[j] = buf + (slots + j) * m;
  double *in = buf + 2 * slots * m, *out = in + m, *row = out + m;
  int next = y0 - r < 0 ? 0 : y0 - r; /* the next source row to prepare */
  for (int q = y0; q < y1; q++) {
    for (; next <= q + r && next < h; next++) {
      double *slot = ring[next % slots];
      if (ps->op == WV_PSF_KT) {
        ps->load(ps->ctx, next, slot);
        continue;
      }
      ps->load(ps->ctx, next, in);
      psf_line(wk, r, ps->w, ps->c, in, slot, 0);
      if (ps->op == WV_PSF_DK) psf_line(dwk, r, ps->w, ps->c, in, dring[next % slots], 0);
    }
    double wt[PSF_TERMS_MAX];
    const double *src[PSF_TERMS_MAX];
    switch (ps->op) {
      case WV_PSF_K: psf_terms(psf_column(wk, r, h, q, 0, ring, slots, 0, wt, src), wt, src, m, out); break;
      case WV_PSF_KT: /* K^T = Kx^T Ky^T */
        psf_terms(psf_column(wk, r, h, q, 1, ring, slots, 0, wt, src), wt, src, m, row);
        psf_line(wk, r, ps->w, ps->c, row, out, 1);
        break;
      case WV_PSF_DK: { /* dK = dKy Kx + Ky dKx */
        int nt = psf_column(dwk, r, h, q, 0, ring, slots, 0, wt, src);
        psf_terms(psf_column(wk, r, h, q, 0, dring, slots, nt, wt, src), wt, src, m, out);
        break;
      }
    }
    ps->store(ps->ctx, q, out);
  }
}

wv_status wv_psf_run(const wv_psf_stream *ps, wv_error *err) {
  wv_status st = psf_check(ps->sigma, err);
  if (st) return st;
  size_t m = (size_t)ps->w * ps->c;
  double wk[3 * (int)WV_PSF_MAX_SIGMA + 2], dwk[3 * (int)WV_PSF_MAX_SIGMA + 2];
  int r = ps->sigma > 0 ? psf_kernel(ps->sigma, wk, dwk) : 0;
  if (!(ps->sigma > 0)) wk[0] = 1, dwk[0] = 0; /* K is the identity, dK vanishes */
  /* bands of rows in any order: each recomputes the 2r source rows it shares with its
   * neighbours, few against its own */
  int band = 4 * r > 32 ? 4 * r : 32, nb = (ps->h + band - 1) / band, fail = 0;
  int threads = ps->threads > 0 ? ps->threads : omp_get_max_threads();
  if (threads > nb) threads = nb;
#pragma omp parallel num_threads(threads)
  {
    double *buf = malloc((2 * (size_t)(2 * r + 1) + 3) * m * sizeof *buf);
    if (!buf) {
#pragma omp atomic write
      fail = 1;
    }
#pragma omp for schedule(dynamic, 1)
    for (int b = 0; b < nb; b++)
      if (buf) psf_band(ps, wk, dwk, r, b * band, (b + 1) * band < ps->h ? (b + 1) * band : ps->h, buf);
    free(buf);
  }
  if (fail) return wv_fail(err, WV_ERR_NOMEM, "out of memory for the camera blur");
  return WV_OK;
}

/* wv_psf_apply's rows: a plain image in, a plain image out. */
typedef struct {
  const double *in;
  double *out;
  size_t m;
} plain_rows;
static void plain_load(void *ctx, int y, double *row) {
  const plain_rows *p = ctx;
  memcpy(row, p->in + (size_t)y * p->m, p->m * sizeof *row);
}
static void plain_store(void *ctx, int y, const double *row) {
  const plain_rows *p = ctx;
  memcpy(p->out + (size_t)y * p->m, row, p->m * sizeof *row);
}

static wv_status psf_plain(wv_psf_op op, double sigma, int w, int h, int c, const double *in, double *out,
                           wv_error *err) {
  plain_rows pr = {in, out, (size_t)w * c};
  wv_psf_stream ps = {.op = op, .sigma = sigma, .w = w, .h = h, .c = c, .load = plain_load, .store = plain_store,
                      .ctx = &pr};
  return wv_psf_run(&ps, err);
}

wv_status wv_psf_apply(double sigma, int w, int h, int c, const double *in, double *out, int adjoint,
                       wv_error *err) {
  if (!(sigma > 0)) {
    memcpy(out, in, (size_t)w * h * c * sizeof *out);
    return WV_OK;
  }
  return psf_plain(adjoint ? WV_PSF_KT : WV_PSF_K, sigma, w, h, c, in, out, err);
}

wv_status wv_psf_apply_dsigma(double sigma, int w, int h, int c, const double *in, double *out, wv_error *err) {
  if (!(sigma > 0)) { /* every derivative of exp(-k^2 / 2 sigma^2) vanishes at 0 */
    memset(out, 0, (size_t)w * h * c * sizeof *out);
    return WV_OK;
  }
  return psf_plain(WV_PSF_DK, sigma, w, h, c, in, out, err);
}

/* wv_scene_capture's rows: the radiance image in, the response of the blurred rows out. */
typedef struct {
  const wv_scene *s;
  const wv_image *rad;
  wv_image *cap;
} capture_rows;
static void capture_load(void *ctx, int y, double *row) {
  const capture_rows *p = ctx;
  const float *in = wv_image_px(p->rad, 0, y);
  for (int i = 0; i < p->rad->w * p->rad->c; i++) row[i] = in[i];
}
static void capture_store(void *ctx, int y, const double *row) {
  const capture_rows *p = ctx;
  float *out = wv_image_px(p->cap, 0, y);
  int c = p->cap->c, per = c > 0 ? RESP_B / c : 0;
  float v[RESP_B];
  double mask[RESP_B];
  for (int x0 = 0; per > 0 && x0 < p->cap->w; x0 += per) { /* blocks of the row, from the stack */
    int n = p->cap->w - x0 < per ? p->cap->w - x0 : per;
    for (int i = 0; i < n * c; i++) v[i] = (float)row[(size_t)x0 * c + i];
    wv_response_mask_row(p->s, x0, y, n, mask);
    wv_respond_n(p->s, mask, n, c, v, out + (size_t)x0 * c, NULL);
  }
}

wv_status wv_scene_capture(const wv_scene *s, const wv_image *rad, wv_image *cap, wv_error *err) {
  if (!(s->psf_sigma > 0)) {
    wv_scene_response(s, rad, cap);
    return WV_OK;
  }
  wv_image copy = {0}; /* in place: the blur reads rows the response has written */
  if (cap->data == rad->data) {
    wv_status st = wv_image_alloc(&copy, rad->w, rad->h, rad->c, err);
    if (st) return st;
    memcpy(copy.data, rad->data, sizeof(float) * rad->w * rad->h * rad->c);
  }
  capture_rows cr = {s, copy.data ? &copy : rad, cap};
  wv_psf_stream ps = {.op = WV_PSF_K, .sigma = s->psf_sigma, .w = rad->w, .h = rad->h, .c = rad->c,
                      .load = capture_load, .store = capture_store, .ctx = &cr};
  wv_status st = wv_psf_run(&ps, err);
  wv_image_free(&copy);
  return st;
}
