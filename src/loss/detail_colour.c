/* woven: the detail-colour loss L_k (include/woven/loss.h): how the colour of the
 * pixel-scale detail varies, compared between photo and render, and its adjoint. A
 * one-colour cloth shows its weave as light and shade (the R, G and B detail move
 * together); a two-colour one (denim) along the line between its two yarn colours. The
 * Gram and spectrum terms see neither, so a fit could put hues on warp and weft that the
 * photo does not have, or merge two that it has. */
#include <stdlib.h>
#include <string.h>

#include "woven/image.h"
#include "woven/loss.h"

#define TAPS_CAP 64

struct wv_colour_loss {
  int w, h;          /* image size */
  int n, x0, y0;     /* crop side and corner */
  int r;             /* blur radius: the interior starts r pixels inside the crop */
  double g[TAPS_CAP]; /* the blur's taps (WV_COLOUR_SIGMA) */
  float *tmp;        /* 3*n*n one pass of the blur, per channel */
  float *det;        /* 3*n*n the detail on the interior (0 outside), centred */
  float *gd;         /* 3*n*n the gradient with respect to the detail */
  double *acc;       /* 3*n one row of the blur's sums, per channel */
  double photo[9];   /* the photo's normalised covariance */
  int flat;          /* the photo has no detail: nothing to match, L_k = 0 */
};

void wv_colour_loss_free(wv_colour_loss *c) {
  if (!c) return;
  free(c->tmp), free(c->det), free(c->gd), free(c->acc);
  free(c);
}

/* The blur's sums are made a row at a time, tap after tap over the row's values (s[x] +=
 * g[k] v[x + k], k ascending for every x): each value adds its terms in the same order as
 * one sum per value would, and the row's loop is a vector loop. acc: n doubles. */

/* det = x - blur(x) on the interior [r, n-r)^2 of the crop: the blur's taps there stay
 * inside the crop, so no edge rule enters. One channel; tmp and det n*n. */
static void detail_forward(const wv_colour_loss *c, const wv_image *img, int ch, float *tmp, float *det,
                           double *acc) {
  int n = c->n, r = c->r;
  const double *g = c->g;
  for (int y = 0; y < n; y++) { /* along x, every row the second pass reads */
    const float *row = wv_image_px(img, c->x0, c->y0 + y) + ch;
    for (int x = r; x < n - r; x++) acc[x] = 0;
    for (int k = -r; k <= r; k++)
#pragma omp simd
      for (int x = r; x < n - r; x++) acc[x] += g[k + r] * row[3 * (x + k)];
    for (int x = r; x < n - r; x++) tmp[(size_t)y * n + x] = (float)acc[x];
  }
  memset(det, 0, sizeof(float) * (size_t)n * n);
  for (int y = r; y < n - r; y++) { /* along y, then det = x - blur(x) */
    const float *row = wv_image_px(img, c->x0, c->y0 + y) + ch;
    for (int x = r; x < n - r; x++) acc[x] = 0;
    for (int k = -r; k <= r; k++) {
      const float *t = tmp + (size_t)(y + k) * n;
#pragma omp simd
      for (int x = r; x < n - r; x++) acc[x] += g[k + r] * t[x];
    }
    for (int x = r; x < n - r; x++) det[(size_t)y * n + x] = row[3 * x] - (float)acc[x];
  }
}

/* Backward of det = x - blur(x): dL/dx = gd - blur^T(gd), gd zero outside the interior;
 * blur^T is the same separable sum with the taps that land inside the interior.
 * weight * dL/dx is added into channel ch of d's crop. */
static void detail_backward(const wv_colour_loss *c, const float *gd, float *tmp, wv_image *d, int ch, float weight,
                            double *acc) {
  int n = c->n, r = c->r, lo = r, hi = n - r; /* the interior [lo, hi) */
  const double *g = c->g;
  for (int y = 0; y < n; y++) { /* along y: rows y + k inside the interior */
    for (int x = lo; x < hi; x++) acc[x] = 0;
    int k0 = lo - y > -r ? lo - y : -r, k1 = hi - 1 - y < r ? hi - 1 - y : r;
    for (int k = k0; k <= k1; k++) {
      const float *t = gd + (size_t)(y + k) * n;
#pragma omp simd
      for (int x = lo; x < hi; x++) acc[x] += g[k + r] * t[x];
    }
    for (int x = lo; x < hi; x++) tmp[(size_t)y * n + x] = (float)acc[x];
  }
  for (int y = 0; y < n; y++) { /* along x: columns x + k inside the interior */
    float *row = wv_image_px(d, c->x0, c->y0 + y) + ch;
    const float *t = tmp + (size_t)y * n;
    for (int x = 0; x < n; x++) acc[x] = 0;
    /* tap k reaches the interior from columns x with lo <= x + k < hi */
    for (int k = -r; k <= r; k++) {
      int x0 = lo - k > 0 ? lo - k : 0, x1 = hi - k < n ? hi - k : n;
#pragma omp simd
      for (int x = x0; x < x1; x++) acc[x] += g[k + r] * t[x + k];
    }
    for (int x = 0; x < n; x++) row[3 * x] += weight * (gd[(size_t)y * n + x] - (float)acc[x]);
  }
}

/* Forward: the three channels' detail, centred over the interior (M pixels); a[9] its
 * covariance. Returns the trace. */
static double covariance(wv_colour_loss *c, const wv_image *img, double a[9]) {
  int n = c->n, r = c->r;
  size_t nn = (size_t)n * n;
  double M = (double)(n - 2 * r) * (n - 2 * r);
#pragma omp parallel for schedule(static, 1)
  for (int ch = 0; ch < 3; ch++) {
    float *det = c->det + ch * nn;
    detail_forward(c, img, ch, c->tmp + ch * nn, det, c->acc + ch * (size_t)n);
    double s = 0;
    for (int y = r; y < n - r; y++)
      for (int x = r; x < n - r; x++) s += det[(size_t)y * n + x];
    float mu = (float)(s / M);
    for (int y = r; y < n - r; y++)
      for (int x = r; x < n - r; x++) det[(size_t)y * n + x] -= mu;
  }
  for (int i = 0; i < 3; i++)
    for (int j = i; j < 3; j++) {
      const float *di = c->det + i * nn, *dj = c->det + j * nn;
      double s = 0;
      for (size_t k = 0; k < nn; k++) s += (double)di[k] * dj[k];
      a[i * 3 + j] = a[j * 3 + i] = s / M; /* A_ij = mean (d_i - mu_i)(d_j - mu_j) */
    }
  return a[0] + a[4] + a[8];
}

wv_status wv_colour_loss_create(const wv_image *photo, wv_colour_loss **out, wv_error *err) {
  *out = NULL;
  int n = photo->w < photo->h ? photo->w : photo->h;
  if (n > WV_COLOUR_SIDE) n = WV_COLOUR_SIDE;
  int r = wv_gaussian_radius(WV_COLOUR_SIGMA);
  if (2 * r + 1 > TAPS_CAP) return wv_fail(err, WV_ERR_INVALID, "the detail-colour blur has too many taps");
  if (n < 4 * r || photo->c < 3)
    return wv_fail(err, WV_ERR_INVALID, "the detail-colour loss needs an RGB image of at least %d x %d pixels", 4 * r,
                   4 * r);
  wv_colour_loss *c = calloc(1, sizeof *c);
  if (!c) return wv_fail(err, WV_ERR_NOMEM, "out of memory for the detail-colour loss");
  c->w = photo->w, c->h = photo->h, c->n = n, c->r = r;
  c->x0 = (photo->w - n) / 2, c->y0 = (photo->h - n) / 2;
  wv_gaussian_taps(WV_COLOUR_SIGMA, c->g);
  size_t nn = (size_t)n * n;
  c->tmp = malloc(sizeof(float) * 3 * nn), c->det = malloc(sizeof(float) * 3 * nn);
  c->gd = malloc(sizeof(float) * 3 * nn), c->acc = malloc(sizeof(double) * 3 * (size_t)n);
  if (!c->tmp || !c->det || !c->gd || !c->acc) {
    wv_colour_loss_free(c);
    return wv_fail(err, WV_ERR_NOMEM, "out of memory for the detail-colour loss");
  }
  double a[9], t = covariance(c, photo, a);
  c->flat = !(t > 1e-20);
  for (int k = 0; k < 9; k++) c->photo[k] = c->flat ? 0.0 : a[k] / t;
  *out = c;
  return WV_OK;
}

wv_status wv_colour_loss_eval(wv_colour_loss *c, const wv_image *render, wv_image *d, float weight, double *value,
                              wv_error *err) {
  if (render->w != c->w || render->h != c->h || render->c < 3)
    return wv_fail(err, WV_ERR_INVALID, "the render is %d x %d but the photo %d x %d", render->w, render->h, c->w,
                   c->h);
  *value = 0;
  if (c->flat) return WV_OK; /* a photo without detail says nothing of its colour */
  double a[9], gn[9], ga[9];
  double t = covariance(c, render, a);
  /* L = sum_ij (A_ij / t - P_ij)^2, t = trace A */
  double l = 0, dot = 0;
  for (int k = 0; k < 9; k++) {
    double nk = t > 1e-20 ? a[k] / t : 0.0;
    l += (nk - c->photo[k]) * (nk - c->photo[k]);
    gn[k] = 2 * (nk - c->photo[k]);
    dot += gn[k] * a[k];
  }
  *value = l;
  if (!d || !(t > 1e-20)) return WV_OK; /* a flat render: no direction to move its detail's colour */
  /* backward of N = A / t: dL/dA_ij = gN_ij / t - delta_ij sum_kl gN_kl A_kl / t^2 */
  for (int k = 0; k < 9; k++) ga[k] = gn[k] / t - (k % 4 == 0 ? dot / (t * t) : 0.0);
  int n = c->n;
  size_t nn = (size_t)n * n;
  double M = (double)(n - 2 * c->r) * (n - 2 * c->r);
#pragma omp parallel for schedule(static, 1)
  for (int i = 0; i < 3; i++) {
    /* backward of A_ij = mean (d_i - mu_i)(d_j - mu_j): dL/dd_i = sum_j (gA_ij + gA_ji) (d_j - mu_j) / M
     * (the centring's own term sums to zero; det is zero outside the interior, so gd is too) */
    float *gd = c->gd + i * nn;
    double w[3];
    for (int j = 0; j < 3; j++) w[j] = (ga[i * 3 + j] + ga[j * 3 + i]) / M;
    for (size_t p = 0; p < nn; p++)
      gd[p] = (float)(w[0] * c->det[p] + w[1] * c->det[nn + p] + w[2] * c->det[2 * nn + p]);
    detail_backward(c, gd, c->tmp + i * nn, d, i, weight, c->acc + i * (size_t)n);
  }
  return WV_OK;
}
