/* The back-lit capture as a linear function of the transmission colours: the radiance of a
 * back-lit scene is k_st S_t + k_t F_t + k_f F_f on each yarn plus the light through the gaps
 * (kernel/kernel_impl.h, wv_shade_trans), so with the geometry fixed it is an affine map of
 * the eighteen colours, and so is its camera blur. The blurred basis is kept; each capture is
 * then the response of a weighted sum (wv_scene_capture: the blur, then the response). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "render/render_internal.h"
#include "woven/grad.h"

#define TB_TYPES 6 /* k_t, k_st, k_f, each warp then weft: WV_P_KT_WARP_R + 3 type + channel */
#define WV_TRANS_MATCH_RIDGE 1e-3 /* the match's pull toward the start, relative to the cells' evidence */
#define TB_WIDTHS 8 /* band images kept of as many widths: a search over widths visits each once */

struct wv_trans_basis {
  wv_scene scene;
  wv_params p; /* what it was made of (its colours 0) */
  int w, h;
  float *base, *basis[TB_TYPES]; /* blurred radiance: all colours 0; each type's colour 1, minus base */
  float *mask;                   /* the response's falloff at each pixel */
  double *slope;                 /* d capture / d blurred radiance at the last capture */
  /* the band's two images (k_f warp, weft) at each width made so far, the oldest replaced
   * past TB_WIDTHS: they depend on the geometry alone, which the basis keeps */
  double band_width[TB_WIDTHS];
  float *band[TB_WIDTHS][2];
  int nband;
};

static double *colour_of(wv_params *p, int type) {
  return type < 2 ? p->transmission[type] : type < 4 ? p->transmission_specular[type - 2] : p->transmission_forward[type - 4];
}

void wv_trans_basis_free(wv_trans_basis *b) {
  if (!b) return;
  free(b->base), free(b->mask), free(b->slope);
  for (int t = 0; t < TB_TYPES; t++) free(b->basis[t]);
  for (int k = 0; k < TB_WIDTHS; k++) free(b->band[k][0]), free(b->band[k][1]);
  free(b);
}

/* The radiance of q, blurred as the camera blurs it, into out (w * h * 3). */
static wv_status blurred(const wv_scene *s, const wv_params *q, const wv_render_opts *opt, double *tmp, float *out,
                         wv_error *err) {
  wv_image cap = {0}, rad = {0};
  wv_status st = wv_render(s, q, opt, &cap, &rad, err);
  wv_image_free(&cap);
  if (st) return st;
  size_t n = (size_t)s->width * s->height * 3;
  double *in = tmp + n;
  for (size_t i = 0; i < n; i++) in[i] = rad.data[i];
  wv_image_free(&rad);
  if ((st = wv_psf_apply(s->psf_sigma, s->width, s->height, 3, in, tmp, 0, err))) return st;
  for (size_t i = 0; i < n; i++) out[i] = (float)tmp[i];
  return WV_OK;
}

/* Keeps the basis's band images as those of its width (b->p.forward_width). */
static wv_status band_keep(wv_trans_basis *b, wv_error *err) {
  size_t n = (size_t)b->w * b->h * 3;
  int k = b->nband % TB_WIDTHS;
  for (int t = 0; t < 2; t++)
    if (!b->band[k][t] && !(b->band[k][t] = malloc(sizeof(float) * n)))
      return wv_fail(err, WV_ERR_NOMEM, "out of memory for the transmission basis");
  for (int t = 0; t < 2; t++) memcpy(b->band[k][t], b->basis[TB_TYPES - 2 + t], sizeof(float) * n);
  b->band_width[k] = b->p.forward_width;
  b->nband++;
  return WV_OK;
}

wv_status wv_trans_basis_create(const wv_scene *s, const wv_params *p, const wv_render_opts *opt,
                                wv_trans_basis **out, wv_error *err) {
  *out = NULL;
  if (!wv_scene_transmits(s)) return wv_fail(err, WV_ERR_INVALID, "the scene is not back-lit: no light through the cloth");
  wv_trans_basis *b = calloc(1, sizeof *b);
  size_t n = (size_t)s->width * s->height * 3;
  double *tmp = malloc(sizeof *tmp * 2 * n);
  int ok = b && tmp;
  if (b) {
    b->scene = *s, b->w = s->width, b->h = s->height;
    ok = ok && (b->base = malloc(sizeof(float) * n)) && (b->mask = malloc(sizeof(float) * n / 3)) &&
         (b->slope = malloc(sizeof(double) * n));
    for (int t = 0; t < TB_TYPES; t++) ok = ok && (b->basis[t] = malloc(sizeof(float) * n));
  }
  wv_status st = ok ? WV_OK : wv_fail(err, WV_ERR_NOMEM, "out of memory for the transmission basis");
  wv_params q = *p;
  for (int t = 0; t < TB_TYPES; t++) memset(colour_of(&q, t), 0, sizeof(double) * 3);
  if (b) b->p = q;
  if (!st) st = blurred(s, &q, opt, tmp, b->base, err);
  for (int t = 0; t < TB_TYPES && !st; t++) {
    wv_params u = q;
    for (int c = 0; c < 3; c++) colour_of(&u, t)[c] = 1.0;
    if (!(st = blurred(s, &u, opt, tmp, b->basis[t], err)))
      for (size_t i = 0; i < n; i++) b->basis[t][i] -= b->base[i];
  }
  if (!st)
    for (int y = 0; y < b->h; y++)
      for (int x = 0; x < b->w; x++) b->mask[(size_t)y * b->w + x] = (float)wv_response_mask(s, x, y);
  if (!st) st = band_keep(b, err);
  free(tmp);
  if (st) {
    wv_trans_basis_free(b);
    return st;
  }
  *out = b;
  return WV_OK;
}

wv_status wv_trans_basis_forward_width(wv_trans_basis *b, const wv_params *p, const wv_render_opts *opt,
                                       wv_error *err) {
  if (p->forward_width == b->p.forward_width) return WV_OK;
  size_t n = (size_t)b->w * b->h * 3;
  int kept = b->nband < TB_WIDTHS ? b->nband : TB_WIDTHS;
  for (int k = 0; k < kept; k++)
    if (b->band_width[k] == p->forward_width) {
      for (int t = 0; t < 2; t++) memcpy(b->basis[TB_TYPES - 2 + t], b->band[k][t], sizeof(float) * n);
      b->p.forward_width = p->forward_width;
      return WV_OK;
    }
  double *tmp = malloc(sizeof *tmp * 2 * n);
  if (!tmp) return wv_fail(err, WV_ERR_NOMEM, "out of memory for the transmission basis");
  wv_params q = b->p;
  q.forward_width = p->forward_width;
  wv_status st = WV_OK;
  for (int t = TB_TYPES - 2; t < TB_TYPES && !st; t++) { /* k_f warp, weft */
    wv_params u = q;
    for (int c = 0; c < 3; c++) colour_of(&u, t)[c] = 1.0;
    if (!(st = blurred(&b->scene, &u, opt, tmp, b->basis[t], err)))
      for (size_t i = 0; i < n; i++) b->basis[t][i] -= b->base[i];
  }
  free(tmp);
  if (!st) b->p.forward_width = q.forward_width;
  return st ? st : band_keep(b, err);
}

wv_status wv_trans_basis_capture(wv_trans_basis *b, const wv_params *p, wv_image *capture, wv_error *err) {
  float k[TB_TYPES][3];
  wv_params q = *p;
  for (int t = 0; t < TB_TYPES; t++)
    for (int c = 0; c < 3; c++) k[t][c] = (float)colour_of(&q, t)[c];
  wv_status st = wv_image_alloc(capture, b->w, b->h, 3, err);
  if (st) return st;
  enum { B = 64 }; /* pixels a block: the response's powers are taken a block at once */
  size_t n = (size_t)b->w * b->h, nb = (n + B - 1) / B;
#pragma omp parallel for schedule(static)
  for (size_t q0 = 0; q0 < nb; q0++) {
    size_t i0 = q0 * B;
    int m = n - i0 < B ? (int)(n - i0) : B;
    float v[B * 3];
    double mask[B];
    for (int j = 0; j < m; j++) {
      size_t i = i0 + (size_t)j;
      mask[j] = b->mask[i];
      for (int c = 0; c < 3; c++) {
        float x = b->base[3 * i + c];
        for (int t = 0; t < TB_TYPES; t++) x += k[t][c] * b->basis[t][3 * i + c];
        v[3 * j + c] = x;
      }
    }
    wv_respond_n(&b->scene, mask, m, 3, v, capture->data + 3 * i0, b->slope + 3 * i0);
  }
  return WV_OK;
}

wv_status wv_trans_basis_grad(const wv_trans_basis *b, const wv_image *dcapture, double grad[WV_P_COUNT],
                              wv_error *err) {
  if (dcapture->w != b->w || dcapture->h != b->h || dcapture->c != 3)
    return wv_fail(err, WV_ERR_INVALID, "the adjoint is %d x %d x %d but the capture %d x %d x 3", dcapture->w,
                   dcapture->h, dcapture->c, b->w, b->h);
  double *rows = calloc((size_t)b->h * TB_TYPES * 3, sizeof *rows);
  if (!rows) return wv_fail(err, WV_ERR_NOMEM, "out of memory for the transmission colours' gradient");
  /* each row's sums, then the rows in order: the same sum on any number of threads */
#pragma omp parallel for schedule(static)
  for (int y = 0; y < b->h; y++) {
    double *r = rows + (size_t)y * TB_TYPES * 3;
    for (int x = 0; x < b->w; x++)
      for (int c = 0; c < 3; c++) {
        size_t i = ((size_t)y * b->w + x) * 3 + c;
        double a = b->slope[i] * dcapture->data[i];
        for (int t = 0; t < TB_TYPES; t++) r[t * 3 + c] += a * b->basis[t][i];
      }
  }
  for (int k = 0; k < TB_TYPES * 3; k++) grad[WV_P_KT_WARP_R + k] = 0;
  for (int y = 0; y < b->h; y++)
    for (int k = 0; k < TB_TYPES * 3; k++) grad[WV_P_KT_WARP_R + k] += rows[(size_t)y * TB_TYPES * 3 + k];
  free(rows);
  return WV_OK;
}

wv_status wv_trans_basis_match(const wv_trans_basis *b, const wv_image *photo, int cells_w, int cells_h,
                               wv_trans_match mode, wv_params *p, double *residual, wv_error *err) {
  if (photo->w != b->w || photo->h != b->h || photo->c != 3)
    return wv_fail(err, WV_ERR_INVALID, "the photo is %d x %d but the transmission basis %d x %d", photo->w, photo->h,
                   b->w, b->h);
  if (cells_w < 1 || cells_h < 1 || cells_w > b->w || cells_h > b->h)
    return wv_fail(err, WV_ERR_INVALID, "%d x %d cells do not fit a %d x %d image", cells_w, cells_h, b->w, b->h);
  int nc = cells_w * cells_h;
  /* per cell and channel: the valid pixels' count, the photo's mean radiance, the base's and each basis's */
  double *acc = calloc((size_t)nc * 3 * (3 + TB_TYPES), sizeof *acc);
  if (!acc) return wv_fail(err, WV_ERR_NOMEM, "out of memory for the transmission colours' match");
  const wv_scene *s = &b->scene;
  double top = s->clip > 0 ? s->clip : INFINITY;
  for (int y = 0; y < b->h; y++)
    for (int x = 0; x < b->w; x++) {
      size_t i = (size_t)y * b->w + x;
      double m = b->mask[i];
      if (m < 0.1) continue; /* the falloff's dark edge: the decoding divides by it */
      int cell = (y * cells_h / b->h) * cells_w + x * cells_w / b->w;
      for (int c = 0; c < 3; c++) {
        double v = wv_decode(s, (float)(photo->data[3 * i + c] / m)) / s->exposure;
        if (!(v * s->exposure < 0.999 * top)) continue; /* clipped: its radiance is unknown */
        double *a = acc + ((size_t)cell * 3 + c) * (3 + TB_TYPES);
        a[0] += 1, a[1] += v, a[2] += b->base[3 * i + c];
        for (int t = 0; t < TB_TYPES; t++) a[3 + t] += b->basis[t][3 * i + c];
      }
    }
  wv_params q = *p;
  double res = 0, tot = 0;
  for (int c = 0; c < 3; c++) {
    /* the unknowns x_u, each weighing the colours it moves (W): those are sum_u W[u][t] x_u; the
     * types t0 .. t1 - 1 move (k_t and k_st, or k_f alone), the others are held */
    int t0 = mode == WV_TRANS_MATCH_FORWARD ? TB_TYPES - 2 : 0, t1 = mode == WV_TRANS_MATCH_FORWARD ? TB_TYPES : 4;
    int nu = mode == WV_TRANS_MATCH_SPLIT ? 2 : t1 - t0;
    double W[TB_TYPES][TB_TYPES] = {{0}}, x[TB_TYPES], lo[TB_TYPES], hi[TB_TYPES];
    for (int t = t0; t < t1; t++) {
      double k0 = colour_of(&q, t)[c];
      int u = t - t0;
      if (mode == WV_TRANS_MATCH_SPLIT) W[t / 2][t] = k0, x[t / 2] = 1, lo[t / 2] = 0, hi[t / 2] = INFINITY;
      else W[u][t] = 1, x[u] = k0, wv_param_range(WV_P_KT_WARP_R + 3 * t + c, &lo[u], &hi[u]);
    }
    /* the normal equations of sum over cells (base + sum_u x_u f_u - photo)^2, each cell its mean,
     * f_u = sum_t W[u][t] basis_t */
    double A[TB_TYPES][TB_TYPES] = {{0}}, r[TB_TYPES] = {0};
    for (int cell = 0; cell < nc; cell++) {
      const double *a = acc + ((size_t)cell * 3 + c) * (3 + TB_TYPES);
      if (a[0] < 1) continue;
      double e = (a[1] - a[2]) / a[0], f[TB_TYPES] = {0};
      for (int t = 0; t < TB_TYPES; t++) /* the held colours */
        if (t < t0 || t >= t1) e -= colour_of(&q, t)[c] * a[3 + t] / a[0];
      for (int u = 0; u < nu; u++)
        for (int t = t0; t < t1; t++) f[u] += W[u][t] * a[3 + t] / a[0];
      for (int u = 0; u < nu; u++) {
        r[u] += f[u] * e;
        for (int v = 0; v < nu; v++) A[u][v] += f[u] * f[v];
      }
    }
    double trace = 0;
    for (int u = 0; u < nu; u++) trace += A[u][u];
    double ridge = WV_TRANS_MATCH_RIDGE * trace / nu + 1e-30;
    for (int u = 0; u < nu; u++) A[u][u] += ridge, r[u] += ridge * x[u];
    /* the box-constrained minimum by coordinate descent: a convex quadratic of a few unknowns */
    for (int sweep = 0; sweep < 200; sweep++)
      for (int u = 0; u < nu; u++) {
        double g = r[u];
        for (int v = 0; v < nu; v++)
          if (v != u) g -= A[u][v] * x[v];
        double y = g / A[u][u];
        x[u] = y < lo[u] ? lo[u] : y > hi[u] ? hi[u] : y;
      }
    for (int t = t0; t < t1; t++) {
      double k = 0, klo, khi;
      for (int u = 0; u < nu; u++) k += W[u][t] * x[u];
      wv_param_range(WV_P_KT_WARP_R + 3 * t + c, &klo, &khi);
      colour_of(p, t)[c] = k < klo ? klo : k > khi ? khi : k;
    }
    for (int cell = 0; cell < nc; cell++) { /* the matched colours' residual over the cells */
      const double *a = acc + ((size_t)cell * 3 + c) * (3 + TB_TYPES);
      if (a[0] < 1) continue;
      double v = a[2];
      for (int t = 0; t < TB_TYPES; t++) v += colour_of(p, t)[c] * a[3 + t];
      res += (v - a[1]) * (v - a[1]) / (a[0] * a[0]), tot += a[1] * a[1] / (a[0] * a[0]);
    }
  }
  if (residual) *residual = tot > 0 ? res / tot : 0;
  free(acc);
  return WV_OK;
}
