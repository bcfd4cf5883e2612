/* The gradient integrator, the differentiable renderer: capture and dL/dtheta
 * in one pass (woven/grad.h).
 *
 * Per pixel, the 8-wide row loop (render/rows.c; gradient_double.c in
 * double) returns the radiance and, per yarn
 * type, the sums radiance is linear in (specular and diffuse factors) with
 * their derivatives with respect to the non-linear parameters. The sensor
 * response is per pixel, so its adjoint dL/dradiance is known as soon as the
 * pixel's radiance is: one pass, no stored image, no second render. When the
 * adjoint depends on the capture (wv_render_record), those per-pixel sums are
 * kept instead and wv_record_grad does the same accumulation afterwards. A camera blur
 * (the scene's psf_sigma) couples pixels: the response then waits for every pixel's
 * radiance, the records are always kept, and the adjoint passes through the blur's
 * transpose (wv_psf_apply). */
#include "woven/grad.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "render/render_internal.h"

#define DEG (3.14159265358979323846 / 180.0)

/* The albedos the adjoint pass weighs the per-type sums with; with the light behind
 * the cloth (transmit) the diffuse sums are the diffuse transmission's, weighed by kt. */
typedef struct {
  double kd[2][3], ks[2][3], kt[2][3];
  int transmit;
} wv_grad_model;

/* In float mode the floats the forward renderer uses, widened exactly. */
static void albedos_from_fabric(const wv_fabric *f, wv_grad_model *g) {
  for (int y = 0; y < 2; y++)
    for (int c = 0; c < 3; c++) g->kd[y][c] = f->P.kd[y][c], g->ks[y][c] = f->P.ks[y][c], g->kt[y][c] = f->P.kt[y][c];
}
static void albedos_from_double(const wv_shade_params_d *P, wv_grad_model *g) {
  for (int y = 0; y < 2; y++)
    for (int c = 0; c < 3; c++) g->kd[y][c] = P->kd[y][c], g->ks[y][c] = P->ks[y][c], g->kt[y][c] = P->kt[y][c];
}

/* Gradient slots per type, for the linear parameters. */
static const int KD_ID[2] = {WV_P_KD_WARP_R, WV_P_KD_WEFT_R};
static const int KS_ID[2] = {WV_P_KS_WARP_R, WV_P_KS_WEFT_R};
static const int KT_ID[2] = {WV_P_KT_WARP_R, WV_P_KT_WEFT_R};
static const int BETA_ID[2] = {WV_P_BETA_WARP, WV_P_BETA_WEFT};
static const int ALPHA_ID[2] = {WV_P_ALPHA_WARP, WV_P_ALPHA_WEFT};

/* Add a pixel's contribution given gr[c] = dL/dradiance_c. */
static void accumulate(const wv_grad_model *gm, const double JJ[2][WV_J_COUNT], const double gr[3], double *g) {
  const int *DF_ID = gm->transmit ? KT_ID : KD_ID;
  const double(*kdf)[3] = gm->transmit ? gm->kt : gm->kd; /* the diffuse sums' albedo */
  for (int y = 0; y < 2; y++) {
    const double *J = JJ[y];
    double ws = 0, wd = 0; /* dL/dS and dL/dDF of this type */
    for (int c = 0; c < 3; c++) {
      g[DF_ID[y] + c] += gr[c] * J[WV_J_DF];
      g[KS_ID[y] + c] += gr[c] * J[WV_J_S];
      ws += gr[c] * gm->ks[y][c];
      wd += gr[c] * kdf[y][c];
    }
    g[BETA_ID[y]] += ws * J[WV_J_S_BETA] + wd * J[WV_J_DF_BETA];
    g[ALPHA_ID[y]] += ws * J[WV_J_S_ALPHA];
    g[WV_P_UMAX_DEG] += ws * J[WV_J_S_UMAX] + wd * J[WV_J_DF_UMAX];
    g[WV_P_TWIST_DEG] += ws * J[WV_J_S_PSI];
    g[WV_P_BLEND] += wd * J[WV_J_DF_BLEND];
  }
}

/* What the adjoint pass needs of a pixel once it is rendered. */
typedef struct {
  double cap[3];   /* the capture (in double mode the unrounded double value) */
  double slope[3]; /* d capture / d radiance reaching the sensor (after the blur), 0 where clipped */
  double rad[3];   /* the radiance, before the camera blur */
  double J[2][WV_J_COUNT]; /* the pixel's sums / spp */
} pixel_rec;

/* The same, kept by a float-mode record: the capture and the sums are floats
 * there, so they are stored as floats (about half the memory: under glibc's
 * 32 MB limit for an 800 x 300 image, so the allocator reuses the block from
 * one fit iteration to the next instead of mapping fresh pages). */
typedef struct {
  double slope[3];
  float cap[3], rad[3];
  float J[2][WV_J_COUNT]; /* the sums, before the division by spp */
} pixel_rec_f;

struct wv_grad_record {
  int w, h, dbl, spp;
  double psf_sigma; /* the scene's camera blur (0: none) */
  wv_grad_model gm;
  pixel_rec *px;    /* double mode: w * h, row-major */
  pixel_rec_f *pxf; /* float mode */
};

/* Value i of a record's w x h x 3 radiance (before the camera blur) and of its slope. */
static double rec_rad(const wv_grad_record *rec, size_t i) {
  return rec->dbl ? rec->px[i / 3].rad[i % 3] : rec->pxf[i / 3].rad[i % 3];
}
static double rec_slope(const wv_grad_record *rec, size_t i) {
  return rec->dbl ? rec->px[i / 3].slope[i % 3] : rec->pxf[i / 3].slope[i % 3];
}

/* Sensor response of one pixel and its slope; in float mode exactly
 * wv_scene_response's arithmetic, so the capture is wv_render's. */
static void respond(const wv_scene *s, int dbl, int px, int py, const double rad[3], float cap[3], pixel_rec *rec) {
  double m = wv_response_mask(s, px, py);
  for (int c = 0; c < 3; c++) {
    if (dbl) {
      rec->cap[c] = wv_respond_d(s, m, rad[c], &rec->slope[c]);
      cap[c] = (float)rec->cap[c];
    } else {
      cap[c] = wv_respond_f(s, m, (float)rad[c], &rec->slope[c]);
      rec->cap[c] = cap[c];
    }
  }
}

/* The pixel's radiance and sums into its record. */
static void keep(int spp, const wv_grad_pixel *pix, pixel_rec *rec) {
  for (int c = 0; c < 3; c++) rec->rad[c] = pix->rad[c];
  for (int y = 0; y < 2; y++)
    for (int j = 0; j < WV_J_COUNT; j++) rec->J[y][j] = pix->J[y][j] / (double)spp;
}

/* A float-mode pixel stored, and read back exactly. */
static void rec_store(pixel_rec_f *o, const pixel_rec *r, const wv_grad_pixel *pix) {
  for (int c = 0; c < 3; c++) o->slope[c] = r->slope[c], o->cap[c] = (float)r->cap[c], o->rad[c] = (float)pix->rad[c];
  for (int y = 0; y < 2; y++)
    for (int j = 0; j < WV_J_COUNT; j++) o->J[y][j] = (float)pix->J[y][j];
}
static void rec_load(const pixel_rec_f *o, int spp, pixel_rec *r) {
  for (int c = 0; c < 3; c++) r->slope[c] = o->slope[c], r->cap[c] = o->cap[c], r->rad[c] = o->rad[c];
  for (int y = 0; y < 2; y++)
    for (int j = 0; j < WV_J_COUNT; j++) r->J[y][j] = (double)o->J[y][j] / (double)spp;
}

/* With a camera blur the response acts on the blurred radiance, which needs every
 * pixel's radiance first: the records' captures and slopes are made here, after the
 * render (wv_scene_capture's arithmetic through wv_psf_apply). */
static wv_status respond_blurred(const wv_scene *s, int x0, int y0, wv_grad_record *rec, wv_image *capture_out,
                                 wv_error *err) {
  size_t np = (size_t)rec->w * rec->h, n = np * 3;
  double *a = malloc(2 * n * sizeof *a);
  if (!a) return wv_fail(err, WV_ERR_NOMEM, "out of memory for the camera blur");
  for (size_t i = 0; i < n; i++) a[i] = rec_rad(rec, i);
  wv_status st = wv_psf_apply(rec->psf_sigma, rec->w, rec->h, 3, a, a + n, 0, err);
  for (size_t k = 0; k < np && !st; k++) {
    int i = (int)(k % (size_t)rec->w), r = (int)(k / (size_t)rec->w);
    double b[3];
    for (int c = 0; c < 3; c++) b[c] = rec->dbl ? a[n + 3 * k + c] : (double)(float)a[n + 3 * k + c];
    float cap[3];
    pixel_rec tmp, *pr = rec->dbl ? &rec->px[k] : &tmp;
    respond(s, rec->dbl, x0 + i, y0 + r, b, cap, pr);
    if (!rec->dbl)
      for (int c = 0; c < 3; c++) rec->pxf[k].slope[c] = tmp.slope[c], rec->pxf[k].cap[c] = (float)tmp.cap[c];
    if (capture_out) memcpy(wv_image_px(capture_out, i, r), cap, sizeof cap);
  }
  free(a);
  return st;
}

/* Add a pixel's contribution (and its dot term, in g[WV_P_COUNT]); with gb != NULL (a
 * camera blur) gb holds dL/dradiance already, made by the blur's adjoint. */
static void backward_pixel(const wv_grad_model *gm, const pixel_rec *rec, const float dc[3], const double *gb,
                           double *g) {
  double gr[3];
  for (int c = 0; c < 3; c++) {
    g[WV_P_COUNT] += (double)dc[c] * rec->cap[c];
    gr[c] = gb ? gb[c] : (double)dc[c] * rec->slope[c];
  }
  accumulate(gm, (const double(*)[WV_J_COUNT])rec->J, gr, g);
}

enum { NG = WV_P_COUNT + 1 }; /* the gradient, then the dot */

/* The totals out, angles converted from per radian to per degree. */
static void output(const double total[NG], double grad[WV_P_COUNT], double *dot) {
  for (int i = 0; i < WV_P_COUNT; i++) grad[i] = total[i];
  grad[WV_P_UMAX_DEG] *= DEG;
  grad[WV_P_TWIST_DEG] *= DEG;
  if (dot) *dot = total[WV_P_COUNT];
}

/* The render: either with an adjoint (fused: gradient rows out, nothing kept)
 * or without (every pixel's record kept in rec). */
static wv_status run(const wv_scene *s, const wv_params *p, const wv_render_opts *opt, const wv_grad_opts *go,
                     const wv_image *dcap, double grad[WV_P_COUNT], double *dot, wv_image *capture_out,
                     wv_grad_record **rec_out, wv_error *err) {
  if (capture_out) memset(capture_out, 0, sizeof *capture_out);
  if (rec_out) *rec_out = NULL;
  if (!s || !p) return wv_fail(err, WV_ERR_INVALID, "render_grad: a scene and parameters are required");
  if (s->psf_sigma > 0 && !rec_out) {
    /* the blur couples pixels: record every pixel, then run the adjoint over the records */
    wv_grad_record *r = NULL;
    wv_status st = run(s, p, opt, go, NULL, NULL, NULL, capture_out, &r, err);
    if (!st) st = wv_record_grad(r, dcap, grad, dot, err);
    wv_record_free(r);
    if (st && capture_out) wv_image_free(capture_out);
    return st;
  }
  int x0 = 0, y0 = 0, W = s->width, H = s->height, dbl = go && go->double_precision;
  if (go && (go->width || go->height)) {
    x0 = go->x0, y0 = go->y0, W = go->width, H = go->height;
    if (W < 1 || H < 1 || x0 < 0 || y0 < 0 || x0 > s->width - W || y0 > s->height - H)
      return wv_fail(err, WV_ERR_INVALID, "window %d x %d at (%d, %d) is not inside the %d x %d image", W, H, x0,
                     y0, s->width, s->height);
  }
  wv_fabric fab;
  int spp;
  wv_status st = wv_render_setup(s, p, opt, W, H, &fab, &spp, err);
  if (st) return st;
  wv_camera_rig rig;
  if ((st = wv_rig_prepare_opts(s, opt, &rig, err))) return st;
  if (!rec_out && (!dcap || !dcap->data || dcap->w != W || dcap->h != H || dcap->c != 3))
    return wv_fail(err, WV_ERR_INVALID, "dL/dcapture must be a %d x %d RGB image (got %d x %d x %d)", W, H,
                   dcap ? dcap->w : 0, dcap ? dcap->h : 0, dcap ? dcap->c : 0);

  wv_grad_model gm;
  wv_shade_params_d Pd; /* double mode: the parameters in double */
  if (dbl) {
    wv_shade_params_double(p, &Pd);
    albedos_from_double(&Pd, &gm);
  } else {
    albedos_from_fabric(&fab, &gm);
  }
  gm.transmit = rig.transmit;

  double *rows = NULL;
  wv_grad_record *rec = NULL;
  if (rec_out) {
    rec = calloc(1, sizeof *rec);
    if (rec && dbl) rec->px = malloc((size_t)W * H * sizeof *rec->px);
    if (rec && !dbl) rec->pxf = malloc((size_t)W * H * sizeof *rec->pxf);
    if (!rec || (!rec->px && !rec->pxf)) {
      wv_record_free(rec);
      return wv_fail(err, WV_ERR_NOMEM, "out of memory for the derivatives of %d x %d pixels", W, H);
    }
    rec->w = W, rec->h = H, rec->dbl = dbl, rec->spp = spp, rec->gm = gm, rec->psf_sigma = s->psf_sigma;
  } else if (!(rows = calloc((size_t)H * NG, sizeof *rows))) {
    return wv_fail(err, WV_ERR_NOMEM, "out of memory for %d gradient rows", H);
  }
  if (capture_out && (st = wv_image_alloc(capture_out, W, H, 3, err))) {
    free(rows);
    wv_record_free(rec);
    return st;
  }
  int threads = opt && opt->threads > 0 ? opt->threads : omp_get_max_threads();
  int rows_done = 0;
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
  for (int r = 0; r < H; r++) {
    if (opt && opt->progress && omp_get_thread_num() == 0) {
      int d;
#pragma omp atomic read
      d = rows_done;
      opt->progress(opt->progress_user, (double)d / H);
    }
    wv_grad_pixel pix[8];
    for (int i = 0; i < W; i++) {
      if (i % 8 == 0 && !dbl) wv_render_row(&rig, &fab, y0 + r, x0 + i, W - i < 8 ? W - i : 8, spp, NULL, pix);
      if (dbl) wv_grad_pixel_d(&rig, &fab, &Pd, x0 + i, y0 + r, spp, &pix[i % 8]);
      pixel_rec local, *pr = rec && dbl ? &rec->px[(size_t)r * W + i] : &local;
      float cap[3];
      keep(spp, &pix[i % 8], pr);
      /* with a camera blur the response comes after the loop, on the blurred radiance */
      if (!(s->psf_sigma > 0)) respond(s, dbl, x0 + i, y0 + r, pr->rad, cap, pr);
      if (rec && !dbl) rec_store(&rec->pxf[(size_t)r * W + i], pr, &pix[i % 8]);
      if (s->psf_sigma > 0) continue;
      if (capture_out) memcpy(wv_image_px(capture_out, i, r), cap, sizeof cap);
      if (rows) backward_pixel(&gm, pr, wv_image_px(dcap, i, r), NULL, rows + (size_t)r * NG);
    }
#pragma omp atomic update
    rows_done++;
  }
  if (opt && opt->progress) opt->progress(opt->progress_user, 1.0);
  if (rec && s->psf_sigma > 0 && (st = respond_blurred(s, x0, y0, rec, capture_out, err))) {
    wv_record_free(rec);
    if (capture_out) wv_image_free(capture_out);
    return st;
  }
  if (rows) { /* reduce in row order: the sum does not depend on the thread schedule */
    double total[NG];
    memset(total, 0, sizeof total);
    for (int r = 0; r < H; r++)
      for (int i = 0; i < NG; i++) total[i] += rows[(size_t)r * NG + i];
    output(total, grad, dot);
    free(rows);
  }
  if (rec_out) *rec_out = rec;
  return WV_OK;
}

wv_status wv_render_grad_ex(const wv_scene *s, const wv_params *p, const wv_render_opts *opt,
                            const wv_grad_opts *go, const wv_image *dcap, double grad[WV_P_COUNT], double *dot,
                            wv_image *capture_out, wv_error *err) {
  if (!grad) return wv_fail(err, WV_ERR_INVALID, "render_grad: no gradient array");
  return run(s, p, opt, go, dcap, grad, dot, capture_out, NULL, err);
}

wv_status wv_render_record(const wv_scene *s, const wv_params *p, const wv_render_opts *opt,
                           const wv_grad_opts *g, wv_image *capture, wv_grad_record **rec, wv_error *err) {
  if (!rec) return wv_fail(err, WV_ERR_INVALID, "render_record: no record pointer");
  return run(s, p, opt, g, NULL, NULL, NULL, capture, rec, err);
}

wv_status wv_record_grad(const wv_grad_record *rec, const wv_image *dcap, double grad[WV_P_COUNT], double *dot,
                         wv_error *err) {
  if (!rec || !grad) return wv_fail(err, WV_ERR_INVALID, "record_grad: a record and a gradient array are required");
  if (!dcap || !dcap->data || dcap->w != rec->w || dcap->h != rec->h || dcap->c != 3)
    return wv_fail(err, WV_ERR_INVALID, "dL/dcapture must be a %d x %d RGB image (got %d x %d x %d)", rec->w,
                   rec->h, dcap ? dcap->w : 0, dcap ? dcap->h : 0, dcap ? dcap->c : 0);
  double total[NG], *gb = NULL;
  size_t n = (size_t)rec->w * rec->h * 3;
  if (rec->psf_sigma > 0) {
    /* dL/dradiance = K^T (slope .* dL/dcapture), K the camera blur */
    gb = malloc(2 * n * sizeof *gb);
    if (!gb) return wv_fail(err, WV_ERR_NOMEM, "out of memory for the camera blur's adjoint");
    for (size_t i = 0; i < n; i++)
      gb[i] = (double)dcap->data[i] * rec_slope(rec, i);
    wv_status st = wv_psf_apply(rec->psf_sigma, rec->w, rec->h, 3, gb, gb + n, 1, err);
    if (st) {
      free(gb);
      return st;
    }
  }
  memset(total, 0, sizeof total);
  /* The same per-row partials as the fused pass, made in parallel and summed in row order:
   * bitwise the same result whatever the threads. */
  double *rows = calloc((size_t)rec->h * NG, sizeof *rows);
  if (!rows) {
    free(gb);
    return wv_fail(err, WV_ERR_NOMEM, "out of memory for %d gradient rows", rec->h);
  }
#pragma omp parallel for schedule(static)
  for (int r = 0; r < rec->h; r++) {
    double *rr = rows + (size_t)r * NG;
    for (int i = 0; i < rec->w; i++) {
      size_t k = (size_t)r * rec->w + i;
      pixel_rec pr;
      if (!rec->dbl) rec_load(&rec->pxf[k], rec->spp, &pr);
      backward_pixel(&rec->gm, rec->dbl ? &rec->px[k] : &pr, wv_image_px(dcap, i, r), gb ? gb + n + 3 * k : NULL,
                     rr);
    }
  }
  for (int r = 0; r < rec->h; r++)
    for (int k = 0; k < NG; k++) total[k] += rows[(size_t)r * NG + k];
  free(rows);
  free(gb);
  output(total, grad, dot);
  return WV_OK;
}

wv_status wv_record_grad_psf(const wv_grad_record *rec, const wv_image *dcap, double *dsigma, wv_error *err) {
  if (!rec || !dsigma) return wv_fail(err, WV_ERR_INVALID, "record_grad_psf: a record and an output are required");
  if (!dcap || !dcap->data || dcap->w != rec->w || dcap->h != rec->h || dcap->c != 3)
    return wv_fail(err, WV_ERR_INVALID, "dL/dcapture must be a %d x %d RGB image (got %d x %d x %d)", rec->w,
                   rec->h, dcap ? dcap->w : 0, dcap ? dcap->h : 0, dcap ? dcap->c : 0);
  *dsigma = 0;
  if (!(rec->psf_sigma > 0)) return WV_OK;
  /* capture = respond(K radiance): dL/dsigma = sum dL/dcapture .* slope .* (dK/dsigma radiance) */
  size_t n = (size_t)rec->w * rec->h * 3;
  double *a = malloc(2 * n * sizeof *a);
  if (!a) return wv_fail(err, WV_ERR_NOMEM, "out of memory for the camera blur's derivative");
  for (size_t i = 0; i < n; i++) a[i] = rec_rad(rec, i);
  wv_status st = wv_psf_apply_dsigma(rec->psf_sigma, rec->w, rec->h, 3, a, a + n, err);
  double sum = 0;
  for (size_t i = 0; i < n && !st; i++)
    sum += (double)dcap->data[i] * rec_slope(rec, i) * a[n + i];
  free(a);
  if (!st) *dsigma = sum;
  return st;
}

void wv_record_free(wv_grad_record *rec) {
  if (!rec) return;
  free(rec->px);
  free(rec->pxf);
  free(rec);
}

wv_status wv_render_grad(const wv_scene *s, const wv_params *p, const wv_render_opts *opt, const wv_image *dcap,
                         double grad[WV_P_COUNT], wv_image *capture_out, wv_error *err) {
  return wv_render_grad_ex(s, p, opt, NULL, dcap, grad, NULL, capture_out, err);
}

wv_status wv_grad_check(const wv_scene *s, const wv_params *p, const wv_render_opts *opt, const wv_grad_opts *g,
                        const wv_image *dcap, double rel_step, wv_grad_check_entry out[WV_P_COUNT], wv_error *err) {
  if (!(rel_step > 0 && rel_step < 0.5)) return wv_fail(err, WV_ERR_INVALID, "rel_step %g is outside (0, 0.5)", rel_step);
  double grad[WV_P_COUNT], dummy[WV_P_COUNT];
  wv_status st = wv_render_grad_ex(s, p, opt, g, dcap, grad, NULL, NULL, err);
  if (st) return st;
  for (int i = 0; i < WV_P_COUNT; i++) {
    double lo, hi, x = wv_param_get(p, i);
    wv_param_range(i, &lo, &hi);
    double h = rel_step * (hi - lo), xp = x + h, xm = x - h;
    if (xp > hi) xp = x; /* at a range edge: one-sided, inward */
    if (xm < lo) xm = x;
    wv_params q = *p;
    double Lp, Lm;
    wv_param_set(&q, i, xp);
    if ((st = wv_render_grad_ex(s, &q, opt, g, dcap, dummy, &Lp, NULL, err))) return st;
    wv_param_set(&q, i, xm);
    if ((st = wv_render_grad_ex(s, &q, opt, g, dcap, dummy, &Lm, NULL, err))) return st;
    double num = (Lp - Lm) / (xp - xm), a = grad[i];
    double scale = fabs(a) > fabs(num) ? fabs(a) : fabs(num);
    out[i].analytic = a, out[i].numeric = num;
    out[i].rel_err = scale > 0 ? fabs(a - num) / scale : 0.0;
  }
  return WV_OK;
}
