/* The sensor response (what the camera does to radiance before we compare to a
 * photo): the camera blur (a Gaussian point-spread function on the radiance) and its
 * adjoint, the adjoint's encoding slope, the falloff mask, the image response and the
 * public per-value encoding and its inverse. The per-value response itself is
 * sensor/response_impl.h. */
#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "sensor/sensor.h"
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

double wv_encode_slope(const wv_scene *s, double x) {
  if (x <= 0.0) return 0.0;
  switch (s->encoding) {
    case WV_ENC_SRGB: return wv_srgb_encode_slope(x);
    case WV_ENC_GAMMA: return pow(x, 1.0 / s->gamma - 1.0) / s->gamma;
    default: return 1.0;
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

void wv_scene_response(const wv_scene *s, const wv_image *rad, wv_image *cap) {
  for (int y = 0; y < rad->h; y++)
    for (int x = 0; x < rad->w; x++) {
      double m = wv_response_mask(s, x, y);
      const float *in = wv_image_px(rad, x, y);
      float *out = wv_image_px(cap, x, y);
      for (int c = 0; c < rad->c; c++) out[c] = wv_respond_f(s, m, in[c], NULL);
    }
}

/* One 1-D pass along x or y: out += K in, or K^T in when adjoint. Rows along x, and
 * column bands along y (whole rows of memory at a time), go to separate threads: each
 * writes only its own, and every value sums its terms in the same order as one thread
 * would (k ascending for each source pixel), so the result does not depend on the
 * number of threads. */
static void psf_pass(const double *wk, int r, int w, int h, int c, int along_y, const double *in, double *out,
                     int adjoint) {
  if (!along_y) {
    /* Every value sums its terms in the order of the plain loop "for each i, for each k":
     * a value of K in takes k ascending, a value of K^T in (sources i ascending) k
     * descending. Values farther than r from both ends take no clamped term, so they are
     * summed a whole row at a time, one tap at a time (vectorised); the 2r at the ends
     * keep the plain loop. */
    int lo = r < w ? r : w, hi = w - r > lo ? w - r : lo; /* [lo, hi): the inner values */
#pragma omp parallel for schedule(static)
    for (int j = 0; j < h; j++) {
      const double *ir = in + (size_t)j * w * c;
      double *orow = out + (size_t)j * w * c;
      for (int kk = 0; kk <= 2 * r; kk++) {
        int k = adjoint ? r - kk : kk - r;
        double wt = wk[k < 0 ? -k : k];
        /* inner value q: K takes in[q + k], K^T in[q - k] */
        const double *src = ir + (ptrdiff_t)(adjoint ? -k : k) * c;
        for (size_t e = (size_t)lo * c; e < (size_t)hi * c; e++) orow[e] += wt * src[e];
      }
      for (int i = 0; i < w; i++) {
        if (!adjoint && i >= lo && i < hi) continue;
        if (adjoint && i >= lo + r && i < hi - r) continue; /* its terms all land on inner values */
        for (int k = -r; k <= r; k++) {
          int q = i + k < 0 ? 0 : i + k >= w ? w - 1 : i + k; /* clamped edge */
          if (adjoint && q >= lo && q < hi) continue;         /* summed above */
          double wt = wk[k < 0 ? -k : k];
          for (int ch = 0; ch < c; ch++) {
            if (adjoint) orow[(size_t)q * c + ch] += wt * ir[(size_t)i * c + ch];
            else orow[(size_t)i * c + ch] += wt * ir[(size_t)q * c + ch];
          }
        }
      }
    }
    return;
  }
  int row = w * c, band = 256, nb = (row + band - 1) / band;
#pragma omp parallel for schedule(static)
  for (int b = 0; b < nb; b++) {
    int x0 = b * band, x1 = x0 + band < row ? x0 + band : row;
    for (int i = 0; i < h; i++)
      for (int k = -r; k <= r; k++) {
        int q = i + k < 0 ? 0 : i + k >= h ? h - 1 : i + k;
        double wt = wk[k < 0 ? -k : k];
        const double *src = in + (size_t)(adjoint ? i : q) * row;
        double *dst = out + (size_t)(adjoint ? q : i) * row;
        for (int x = x0; x < x1; x++) dst[x] += wt * src[x];
      }
  }
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

wv_status wv_psf_apply(double sigma, int w, int h, int c, const double *in, double *out, int adjoint,
                       wv_error *err) {
  size_t n = (size_t)w * h * c;
  if (!(sigma > 0)) {
    memcpy(out, in, n * sizeof *out);
    return WV_OK;
  }
  wv_status st = psf_check(sigma, err);
  if (st) return st;
  double wk[3 * (int)WV_PSF_MAX_SIGMA + 2];
  int r = psf_kernel(sigma, wk, NULL);
  double *tmp = calloc(n, sizeof *tmp);
  if (!tmp) return wv_fail(err, WV_ERR_NOMEM, "out of memory for the camera blur");
  memset(out, 0, n * sizeof *out);
  /* K = Ky Kx, so K^T = Kx^T Ky^T: the passes in the other order */
  psf_pass(wk, r, w, h, c, adjoint, in, tmp, adjoint);
  psf_pass(wk, r, w, h, c, !adjoint, tmp, out, adjoint);
  free(tmp);
  return WV_OK;
}

wv_status wv_psf_apply_dsigma(double sigma, int w, int h, int c, const double *in, double *out, wv_error *err) {
  size_t n = (size_t)w * h * c;
  memset(out, 0, n * sizeof *out);
  if (!(sigma > 0)) return WV_OK; /* every derivative of exp(-k^2 / 2 sigma^2) vanishes at 0 */
  wv_status st = psf_check(sigma, err);
  if (st) return st;
  double wk[3 * (int)WV_PSF_MAX_SIGMA + 2], dwk[3 * (int)WV_PSF_MAX_SIGMA + 2];
  int r = psf_kernel(sigma, wk, dwk);
  double *tmp = malloc(n * sizeof *tmp);
  if (!tmp) return wv_fail(err, WV_ERR_NOMEM, "out of memory for the camera blur's derivative");
  /* K = Ky Kx: dK = dKy Kx + Ky dKx */
  memset(tmp, 0, n * sizeof *tmp);
  psf_pass(wk, r, w, h, c, 0, in, tmp, 0);
  psf_pass(dwk, r, w, h, c, 1, tmp, out, 0);
  memset(tmp, 0, n * sizeof *tmp);
  psf_pass(dwk, r, w, h, c, 0, in, tmp, 0);
  psf_pass(wk, r, w, h, c, 1, tmp, out, 0);
  free(tmp);
  return WV_OK;
}

wv_status wv_scene_capture(const wv_scene *s, const wv_image *rad, wv_image *cap, wv_error *err) {
  if (!(s->psf_sigma > 0)) {
    wv_scene_response(s, rad, cap);
    return WV_OK;
  }
  size_t n = (size_t)rad->w * rad->h * rad->c;
  double *a = malloc(2 * n * sizeof *a);
  if (!a) return wv_fail(err, WV_ERR_NOMEM, "out of memory for the camera blur");
  for (size_t i = 0; i < n; i++) a[i] = rad->data[i];
  wv_status st = wv_psf_apply(s->psf_sigma, rad->w, rad->h, rad->c, a, a + n, 0, err);
  if (!st) {
    wv_image b = *rad;
    b.data = cap->data; /* the blurred radiance, then the response in place */
    for (size_t i = 0; i < n; i++) cap->data[i] = (float)a[n + i];
    wv_scene_response(s, &b, cap);
  }
  free(a);
  return st;
}
