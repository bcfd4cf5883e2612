/* woven: the detail-colour loss L_k (include/woven/loss.h): how the colour of the
 * pixel-scale detail varies, compared between photo and render, and its adjoint. A
 * one-colour cloth shows its weave as light and shade (the R, G and B detail move
 * together); a two-colour one (denim) along the line between its two yarn colours. The
 * Gram and spectrum terms see neither, so a fit could put hues on warp and weft that the
 * photo does not have, or merge two that it has. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "woven/loss.h"

struct wv_colour_loss {
  int w, h;          /* image size */
  int n, x0, y0;     /* crop side and corner */
  int r;             /* blur radius: the interior starts r pixels inside the crop */
  float *x, *b;      /* n*n one channel of the crop, its blur */
  float *det;        /* 3*n*n the detail, centred over the interior */
  float *g;          /* n*n gradient scratch */
  double photo[9];   /* the photo's normalised covariance */
  int flat;          /* the photo has no detail: nothing to match, L_k = 0 */
};

void wv_colour_loss_free(wv_colour_loss *c) {
  if (!c) return;
  free(c->x), free(c->b), free(c->det), free(c->g);
  free(c);
}

/* Forward: det_c = crop_c - blur(crop_c) on the interior, centred; a[9] its covariance
 * over the interior (M pixels). Returns the trace. */
static double covariance(wv_colour_loss *c, const wv_image *img, double a[9], wv_error *err, wv_status *st) {
  int n = c->n, r = c->r, m = n - 2 * r;
  double M = (double)m * m, mu[3];
  for (int ch = 0; ch < 3; ch++) {
    for (int y = 0; y < n; y++)
      for (int x = 0; x < n; x++) c->x[(size_t)y * n + x] = wv_image_px(img, c->x0 + x, c->y0 + y)[ch];
    if ((*st = wv_blur_plane(c->x, c->b, n, n, 1, WV_COLOUR_SIGMA, err))) return 0;
    float *d = c->det + (size_t)ch * n * n;
    double s = 0;
    memset(d, 0, sizeof(float) * (size_t)n * n);
    for (int y = r; y < n - r; y++)
      for (int x = r; x < n - r; x++) {
        size_t i = (size_t)y * n + x;
        d[i] = c->x[i] - c->b[i]; /* det = x - blur(x) */
        s += d[i];
      }
    mu[ch] = s / M;
    for (int y = r; y < n - r; y++)
      for (int x = r; x < n - r; x++) d[(size_t)y * n + x] -= (float)mu[ch];
  }
  for (int i = 0; i < 3; i++)
    for (int j = i; j < 3; j++) {
      const float *di = c->det + (size_t)i * n * n, *dj = c->det + (size_t)j * n * n;
      double s = 0;
      for (size_t k = 0; k < (size_t)n * n; k++) s += (double)di[k] * dj[k];
      a[i * 3 + j] = a[j * 3 + i] = s / M; /* A_ij = mean (d_i - mu_i)(d_j - mu_j) */
    }
  return a[0] + a[4] + a[8];
}

wv_status wv_colour_loss_create(const wv_image *photo, wv_colour_loss **out, wv_error *err) {
  *out = NULL;
  int n = photo->w < photo->h ? photo->w : photo->h;
  if (n > WV_COLOUR_SIDE) n = WV_COLOUR_SIDE;
  int r = (int)ceil(3.0 * WV_COLOUR_SIGMA);
  if (n < 4 * r || photo->c < 3)
    return wv_fail(err, WV_ERR_INVALID, "the detail-colour loss needs an RGB image of at least %d x %d pixels", 4 * r,
                   4 * r);
  wv_colour_loss *c = calloc(1, sizeof *c);
  if (!c) return wv_fail(err, WV_ERR_NOMEM, "out of memory for the detail-colour loss");
  c->w = photo->w, c->h = photo->h, c->n = n, c->r = r;
  c->x0 = (photo->w - n) / 2, c->y0 = (photo->h - n) / 2;
  size_t nn = (size_t)n * n;
  c->x = malloc(sizeof(float) * nn), c->b = malloc(sizeof(float) * nn), c->g = malloc(sizeof(float) * nn);
  c->det = malloc(sizeof(float) * 3 * nn);
  wv_status st = WV_OK;
  if (!c->x || !c->b || !c->g || !c->det) st = wv_fail(err, WV_ERR_NOMEM, "out of memory for the detail-colour loss");
  double a[9];
  double t = st ? 0 : covariance(c, photo, a, err, &st);
  c->flat = !(t > 1e-20);
  for (int k = 0; k < 9 && !st; k++) c->photo[k] = c->flat ? 0.0 : a[k] / t;
  if (st) {
    wv_colour_loss_free(c);
    return st;
  }
  *out = c;
  return WV_OK;
}

wv_status wv_colour_loss_eval(wv_colour_loss *c, const wv_image *render, wv_image *d, float weight, double *value,
                              wv_error *err) {
  if (render->w != c->w || render->h != c->h || render->c < 3)
    return wv_fail(err, WV_ERR_INVALID, "the render is %d x %d but the photo %d x %d", render->w, render->h, c->w,
                   c->h);
  double a[9], gn[9], ga[9];
  wv_status st = WV_OK;
  *value = 0;
  if (c->flat) return WV_OK; /* a photo without detail says nothing of its colour */
  double t = covariance(c, render, a, err, &st);
  if (st) return st;
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
  int n = c->n, r = c->r, m = n - 2 * r;
  double M = (double)m * m;
  for (int i = 0; i < 3; i++) {
    /* backward of A_ij = mean (d_i - mu_i)(d_j - mu_j): dL/dd_i = sum_j (gA_ij + gA_ji) (d_j - mu_j) / M
     * (the centring's own term sums to zero) */
    memset(c->g, 0, sizeof(float) * (size_t)n * n);
    for (int y = r; y < n - r; y++)
      for (int x = r; x < n - r; x++) {
        size_t p = (size_t)y * n + x;
        double s = 0;
        for (int j = 0; j < 3; j++) s += (ga[i * 3 + j] + ga[j * 3 + i]) * c->det[(size_t)j * n * n + p];
        c->g[p] = (float)(s / M);
      }
    /* backward of det = x - blur(x): g - blur^T(g). The clamped blur is its own transpose
     * here: g is zero within r pixels of the crop's edge, so no tap is clamped. */
    if ((st = wv_blur_plane(c->g, c->b, n, n, 1, WV_COLOUR_SIGMA, err))) return st;
    for (int y = 0; y < n; y++)
      for (int x = 0; x < n; x++) {
        size_t p = (size_t)y * n + x;
        wv_image_px(d, c->x0 + x, c->y0 + y)[i] += weight * (c->g[p] - c->b[p]);
      }
  }
  return WV_OK;
}
