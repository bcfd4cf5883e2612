/* woven: the structure loss L_s (include/woven/loss.h): the distance between the log
 * power spectra of the photo's and the render's luminance detail in the yarn band, and
 * its adjoint. The gradient of |FFT|^2 with respect to the image is another FFT:
 * dP_k/du = 2 Re(conj(F_k) e^{-2 pi i k.n / N}), so sum_k g_k dP_k/du = 2 c2r(g F). */
#include <fftw3.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "util/colour.h"
#include "woven/loss.h"

/* The luminance weights in float (the gradient of wv_luminance_f). */
static const float LUMA[3] = {(float)WV_LUMA_R, (float)WV_LUMA_G, (float)WV_LUMA_B};

struct wv_spectrum_loss {
  int w, h;          /* image size */
  int n, x0, y0, nc; /* crop side and corner; half-spectrum width n/2 + 1 */
  float *win;        /* n*n Hann window */
  float *u;          /* n*n windowed luminance, then the gradient */
  fftwf_complex *f, *g; /* n*nc: the render's spectrum, the gradient's half spectrum */
  double *p, *q, *t; /* n*n full power spectrum, smoothed, scratch */
  unsigned char *band; /* n*n: 1 inside the yarn band */
  double *s_photo;   /* n*n: the photo's log spectrum */
  int nband;
  fftwf_plan fwd, inv;
};

void wv_spectrum_loss_free(wv_spectrum_loss *s) {
  if (!s) return;
  if (s->fwd) fftwf_destroy_plan(s->fwd);
  if (s->inv) fftwf_destroy_plan(s->inv);
  fftwf_free(s->u), fftwf_free(s->f), fftwf_free(s->g);
  free(s->win), free(s->p), free(s->q), free(s->t), free(s->band), free(s->s_photo);
  free(s);
}

/* u = win * (Y - mean Y) over the centre crop. */
static void windowed_luma(wv_spectrum_loss *s, const wv_image *img) {
  int n = s->n;
  double m = 0;
  for (int y = 0; y < n; y++)
    for (int x = 0; x < n; x++) {
      const float *c = wv_image_px(img, s->x0 + x, s->y0 + y);
      float v = wv_luminance_f(c[0], c[1], c[2]);
      s->u[(size_t)y * n + x] = v;
      m += v;
    }
  m /= (double)n * n;
  for (size_t i = 0; i < (size_t)n * n; i++) s->u[i] = (float)((s->u[i] - m) * s->win[i]);
}

/* Circular 3 x 3 box average over the full spectrum (its own adjoint). The wrapped
 * neighbours are looked up once per row and column; the nine terms are summed in one fixed
 * order, so rows can go to threads. */
static void box3(const wv_spectrum_loss *s, const double *in, double *out) {
  int n = s->n;
#pragma omp parallel for schedule(static)
  for (int y = 0; y < n; y++) {
    const double *rows[3] = {in + (size_t)((y + n - 1) % n) * n, in + (size_t)y * n, in + (size_t)((y + 1) % n) * n};
    for (int x = 0; x < n; x++) {
      int xs[3] = {x ? x - 1 : n - 1, x, x + 1 < n ? x + 1 : 0};
      double v = 0;
      for (int dy = 0; dy < 3; dy++)
        for (int dx = 0; dx < 3; dx++) v += rows[dy][xs[dx]];
      out[(size_t)y * n + x] = v / 9.0;
    }
  }
}

/* The log spectrum of s->u into out (n*n); leaves F in s->f, the smoothed power in s->q,
 * and returns E, the band mean of the smoothed power. */
static double log_spectrum(wv_spectrum_loss *s, double *out) {
  int n = s->n, nc = s->nc;
  fftwf_execute_dft_r2c(s->fwd, s->u, s->f);
  for (int y = 0; y < n; y++)
    for (int x = 0; x < n; x++) {
      /* the other half of the spectrum is the conjugate of (-ky, -kx) */
      int yy = x < nc ? y : (n - y) % n, xx = x < nc ? x : n - x;
      const float *c = s->f[(size_t)yy * nc + xx];
      s->p[(size_t)y * n + x] = (double)c[0] * c[0] + (double)c[1] * c[1];
    }
  box3(s, s->p, s->q);
  double e = 0;
  for (size_t i = 0; i < (size_t)n * n; i++)
    if (s->band[i]) e += s->q[i];
  e = e / s->nband + 1e-30; /* a flat image has no band power: every q is 0, the log spectrum flat */
#pragma omp parallel for schedule(static)
  for (int i = 0; i < n * n; i++) out[i] = log(WV_SPECTRUM_EPS + s->q[i] / e);
  return e;
}

wv_status wv_spectrum_loss_create(const wv_image *photo, wv_spectrum_loss **out, wv_error *err) {
  *out = NULL;
  int n = photo->w < photo->h ? photo->w : photo->h;
  if (n > WV_SPECTRUM_SIDE) n = WV_SPECTRUM_SIDE;
  n &= ~1;
  if (n < 16 || photo->c < 3)
    return wv_fail(err, WV_ERR_INVALID, "the structure loss needs an RGB image of at least 16 x 16 (got %d x %d)",
                   photo->w, photo->h);
  wv_spectrum_loss *s = calloc(1, sizeof *s);
  if (!s) return wv_fail(err, WV_ERR_NOMEM, "out of memory for the structure loss");
  s->w = photo->w, s->h = photo->h, s->n = n, s->nc = n / 2 + 1;
  s->x0 = (photo->w - n) / 2, s->y0 = (photo->h - n) / 2;
  size_t nn = (size_t)n * n, nh = (size_t)n * s->nc;
  s->win = malloc(sizeof(float) * nn);
  s->u = fftwf_alloc_real(nn);
  s->f = fftwf_alloc_complex(nh), s->g = fftwf_alloc_complex(nh);
  s->p = malloc(sizeof(double) * nn), s->q = malloc(sizeof(double) * nn), s->t = malloc(sizeof(double) * nn);
  s->band = malloc(nn), s->s_photo = malloc(sizeof(double) * nn);
  if (!s->win || !s->u || !s->f || !s->g || !s->p || !s->q || !s->t || !s->band || !s->s_photo) {
    wv_spectrum_loss_free(s);
    return wv_fail(err, WV_ERR_NOMEM, "out of memory for the structure loss");
  }
  s->fwd = fftwf_plan_dft_r2c_2d(n, n, s->u, s->f, FFTW_ESTIMATE);
  s->inv = fftwf_plan_dft_c2r_2d(n, n, s->g, s->u, FFTW_ESTIMATE);
  if (!s->fwd || !s->inv) {
    wv_spectrum_loss_free(s);
    return wv_fail(err, WV_ERR_INTERNAL, "FFTW could not plan a %d x %d transform", n, n);
  }
  const double PI = 3.14159265358979323846;
  for (int y = 0; y < n; y++)
    for (int x = 0; x < n; x++) {
      double hy = 0.5 - 0.5 * cos(2 * PI * (y + 0.5) / n), hx = 0.5 - 0.5 * cos(2 * PI * (x + 0.5) / n);
      s->win[(size_t)y * n + x] = (float)(hy * hx);
      /* the band in units of a 256-pixel crop, so it means the same period at any n */
      double fy = y <= n / 2 ? y : y - n, fx = x <= n / 2 ? x : x - n;
      int in = sqrt(fx * fx + fy * fy) * WV_SPECTRUM_SIDE / n > WV_SPECTRUM_RMIN;
      s->band[(size_t)y * n + x] = (unsigned char)in;
      s->nband += in;
    }
  windowed_luma(s, photo);
  log_spectrum(s, s->s_photo);
  *out = s;
  return WV_OK;
}

double wv_spectrum_loss_eval(wv_spectrum_loss *s, const wv_image *render, wv_image *d, float weight) {
  int n = s->n, nc = s->nc;
  size_t nn = (size_t)n * n;
  windowed_luma(s, render);
  double *sr = s->t;
  double e = log_spectrum(s, sr);
  double loss = 0;
  for (size_t i = 0; i < nn; i++)
    if (s->band[i]) loss += (sr[i] - s->s_photo[i]) * (sr[i] - s->s_photo[i]);
  loss /= s->nband;
  if (!d) return loss;
  /* dL/dS -> dL/dq through the log -> dL/dQ (E depends on every band bin) */
  double aq = 0;
  for (size_t i = 0; i < nn; i++) {
    double a = s->band[i] ? 2.0 * (sr[i] - s->s_photo[i]) / s->nband / (WV_SPECTRUM_EPS + s->q[i] / e) : 0.0;
    sr[i] = a; /* sr now holds a_k = dL/dS_k * dS_k/dq_k */
    aq += a * s->q[i] / e;
  }
  for (size_t i = 0; i < nn; i++) s->q[i] = s->band[i] ? (sr[i] - aq / s->nband) / e : 0.0;
  box3(s, s->q, s->p); /* dL/dP: the box is its own adjoint */
  /* dL/du = 2 c2r(dL/dP * F) on the half spectrum (dL/dP is symmetric like P) */
  for (int y = 0; y < n; y++)
    for (int x = 0; x < nc; x++) {
      size_t k = (size_t)y * nc + x;
      double g = s->p[(size_t)y * n + x];
      s->g[k][0] = (float)(g * s->f[k][0]), s->g[k][1] = (float)(g * s->f[k][1]);
    }
  fftwf_execute_dft_c2r(s->inv, s->g, s->u);
  /* through u = win (Y - mean Y) and the luminance weights */
  double m = 0;
  for (size_t i = 0; i < nn; i++) m += (double)s->win[i] * 2.0 * s->u[i];
  m /= (double)nn;
  for (int y = 0; y < n; y++)
    for (int x = 0; x < n; x++) {
      size_t i = (size_t)y * n + x;
      double gy = (s->win[i] * 2.0 * s->u[i] - m) * weight;
      float *c = wv_image_px(d, s->x0 + x, s->y0 + y);
      for (int ch = 0; ch < 3; ch++) c[ch] += (float)(gy * LUMA[ch]);
    }
  return loss;
}
