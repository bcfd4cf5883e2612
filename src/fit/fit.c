/* woven: the fit (include/woven/fit.h): Adam on the continuous parameters against the
 * weighted image losses of include/woven/loss.h, the random discrete steps, the density
 * alignment, and the fit's checkpoints. */
#include "woven/fit.h"
#include "fit/fit_internal.h"

#include <jansson.h>
#include <math.h>
#include <omp.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "util/hash.h"
#include "util/json.h"
#include "woven/grad.h"
#include "woven/imgops.h"
#include "woven/io.h"
#include "woven/loss.h"
#include "woven/metrics.h"
#include "woven/nn.h"
#include "woven/render.h"

/* The colour split's rule of coverage: a share of warp cells this far from a half (the
 * built-ins give 0, 1/6, 1/4, 3/10 or 3/8) lets the weave decide which yarn type wears
 * which colour, when the two ways round, rendered, differ by this much in how far their
 * share of dark pixels lies from the photo's; start colours whose luminances differ by
 * less than this fraction of their sum count as one colour. */
#define SPLIT_WEAVE_MIN 0.08
#define SPLIT_SHARE_GAP 0.05
#define SPLIT_LUM_SAME 0.05

static double sq(double x) { return x * x; }

/* Rec. 709 luminance of an RGB triple. */
static double luminance(double r, double g, double b) { return 0.2126 * r + 0.7152 * g + 0.0722 * b; }

void wv_fit_opts_default(wv_fit_opts *o) {
  memset(o, 0, sizeof *o);
  o->iters = 200;
  o->lr = 0.01;
  o->w_prior = 0.0005;
  o->w_pixel = 0.2;
  o->w_struct = WV_FIT_W_STRUCT;
  o->w_colour = WV_FIT_W_COLOUR;
  o->colour_split = 1;
  o->down_w = WV_LOSS_DOWN_W, o->down_h = WV_LOSS_DOWN_H;
  o->discrete_every = 5;
  o->iter_scale = 1;
  o->iter_spp = 4;
  o->seed = 1;
  o->checkpoint_every = 10;
  o->align_radius = 230;
  o->density_steps = 1;
  o->register_radius = 6;
  o->distort_degree = 3;
  o->psf_sigma = WV_FIT_PSF_AUTO;
  o->psf_fit = 1;
  o->schedule = 0; /* the window stage did not keep the real photos' quality (docs/fit.md) */
  o->patience = WV_FIT_PATIENCE;
}

/* Every option's range, in one table: wv_fit_opts_validate and the checkpoint
 * reader use it (in_ckpt: stored in checkpoints; 2: optional there). */
typedef struct {
  const char *key;
  size_t off;
  char type; /* 'i' int, 'd' double, 'u' uint64_t */
  double lo, hi;
  int in_ckpt;
} opt_range;
#define OPT(k, t, lo, hi, c) {#k, offsetof(wv_fit_opts, k), t, lo, hi, c}
static const opt_range OPT_RANGES[] = {
    OPT(iters, 'i', 0, WV_FIT_MAX_ITERS, 1),
    OPT(lr, 'd', 1e-9, 1, 1),
    OPT(w_prior, 'd', 0, 1e6, 1),
    OPT(w_pixel, 'd', 0, 1e6, 1),
    OPT(down_w, 'i', 1, 1024, 1),
    OPT(down_h, 'i', 1, 1024, 1),
    OPT(discrete_every, 'i', 0, WV_FIT_MAX_ITERS, 1),
    OPT(iter_scale, 'i', 1, WV_FIT_MAX_ITER_SCALE, 1),
    OPT(iter_spp, 'i', 1, WV_SCENE_MAX_SPP, 1),
    OPT(seed, 'u', 0, 4611686018427387904.0, 1), /* 2^62 */
    OPT(threads, 'i', 0, 1024, 0),
    OPT(checkpoint_every, 'i', 0, WV_FIT_MAX_ITERS, 0),
    OPT(align_radius, 'i', 0, WV_FIT_MAX_ALIGN_RADIUS, 1),
    OPT(register_radius, 'i', 0, WV_FIT_MAX_REGISTER_RADIUS, 2),
    OPT(distort_degree, 'i', 0, 3, 2),
    OPT(w_struct, 'd', 0, 1e6, 2),
    OPT(w_colour, 'd', 0, 1e6, 2),
    OPT(colour_split, 'i', 0, 1, 2),
    OPT(density_steps, 'i', 0, 1, 2),
    OPT(psf_sigma, 'd', WV_FIT_PSF_AUTO, WV_PSF_MAX_SIGMA, 2),
    OPT(psf_fit, 'i', 0, 1, 2),
    OPT(schedule, 'i', 0, 1, 2),
    OPT(patience, 'i', 0, WV_FIT_MAX_ITERS, 2),
};
#undef OPT
#define N_OPTS (sizeof OPT_RANGES / sizeof OPT_RANGES[0])

static double opt_get(const wv_fit_opts *o, const opt_range *r) {
  const char *p = (const char *)o + r->off;
  if (r->type == 'i') return *(const int *)(const void *)p;
  if (r->type == 'u') return (double)*(const uint64_t *)(const void *)p;
  return *(const double *)(const void *)p;
}

wv_status wv_fit_opts_validate(const wv_fit_opts *o, wv_error *err) {
  char a[32], b[32], c[32];
  for (size_t i = 0; i < N_OPTS; i++) {
    const opt_range *r = &OPT_RANGES[i];
    double v = opt_get(o, r);
    if (!(v >= r->lo && v <= r->hi))
      return wv_fail(err, WV_ERR_INVALID, "fit option '%s' = %s is outside %s..%s", r->key, wv_num_str(v, a),
                     wv_num_str(r->lo, b), wv_num_str(r->hi, c));
  }
  return WV_OK;
}

/* Reads the stored options of a checkpoint ("opts"), each range-checked. */
static wv_status read_opts(json_t *opts, wv_fit_opts *o, wv_error *err) {
  if (!json_is_object(opts)) return wv_fail(err, WV_ERR_INVALID, "missing 'opts'");
  for (size_t i = 0; i < N_OPTS; i++) {
    const opt_range *r = &OPT_RANGES[i];
    if (!r->in_ckpt) continue;
    char *p = (char *)o + r->off;
    wv_status st;
    if (r->type == 'd') {
      st = wv_json_number(opts, "opts", r->key, r->lo, r->hi, r->in_ckpt == 1, (double *)(void *)p, err);
    } else {
      long long v = (long long)opt_get(o, r);
      st = wv_json_integer(opts, "opts", r->key, (long long)r->lo, (long long)r->hi, r->in_ckpt == 1, &v, err);
      if (!st && r->type == 'i') *(int *)(void *)p = (int)v;
      if (!st && r->type == 'u') *(uint64_t *)(void *)p = (uint64_t)v;
    }
    if (st) return st;
  }
  return WV_OK;
}

wv_status wv_fit_check_sizes(const wv_scene *s, const wv_descriptor *d, const wv_fit_opts *o, wv_error *err) {
  int need = d ? wv_descriptor_min_side(d) : 0, scale = o->iter_scale > 0 ? o->iter_scale : 1;
  need = need > WV_FIT_MIN_SIDE ? need : WV_FIT_MIN_SIDE;
  if (s->width < need || s->height < need)
    return wv_fail(err, WV_ERR_INVALID, "the scene's image (%d x %d) is too small for a fit (at least %d x %d%s%s)",
                   s->width, s->height, need, need, d ? " for descriptor " : "", d ? wv_descriptor_name(d) : "");
  int w = s->width / scale, h = s->height / scale, dmin = d ? wv_descriptor_min_side(d) : 0;
  if (w < dmin || h < dmin || w < o->down_w || h < o->down_h)
    return wv_fail(err, WV_ERR_INVALID,
                   "iterating at 1/%d scale makes the scene's %d x %d image %d x %d, too small for the fit (at "
                   "least %d x %d); use a smaller --iter-scale",
                   scale, s->width, s->height, w, h, dmin > o->down_w ? dmin : o->down_w,
                   dmin > o->down_h ? dmin : o->down_h);
  return WV_OK;
}

void wv_fit_beta_prior(const char *pattern, double *mu, double *sigma) {
  if (!strncmp(pattern, "twill", 5)) *mu = 1.0, *sigma = 0.5;
  else if (!strncmp(pattern, "satin", 5)) *mu = 0.1, *sigma = 0.5;
  else *mu = 1.0, *sigma = 1.0;
}

wv_status wv_fit_state_init(wv_fit_state *st, const wv_params *start, const wv_fit_opts *o, wv_error *err) {
  memset(st, 0, sizeof *st);
  wv_status s = wv_params_validate(start, err);
  if (s) return s;
  st->start = st->params = *start;
  st->rng = wv_mix64(o->seed ^ 0x666974ULL);
  st->log_cap = o->iters > 0 ? o->iters : 1;
  st->log = calloc((size_t)st->log_cap, sizeof *st->log);
  if (!st->log) return wv_fail(err, WV_ERR_NOMEM, "out of memory for the fit log");
  return WV_OK;
}

void wv_fit_state_free(wv_fit_state *st) {
  free(st->log);
  st->log = NULL;
}

int wv_fit_converged(const wv_fit_record *log, int from, int to, int patience) {
  int first = from + WV_FIT_SMOOTH - 1; /* the first iteration with a whole window in the stage */
  if (patience <= 0 || to - patience <= first) return 0;
  double before = INFINITY, recent = INFINITY;
  for (int j = first; j < to; j++) {
    double m = 0;
    for (int k = j - WV_FIT_SMOOTH + 1; k <= j; k++) m += log[k].loss;
    m /= WV_FIT_SMOOTH;
    if (j < to - patience) before = m < before ? m : before;
    else recent = m < recent ? m : recent;
  }
  return !(recent < (1 - WV_FIT_MIN_GAIN) * before);
}

/* The last iteration (exclusive) the stage may reach. */
static int stage_limit(const wv_fit_opts *o, int stage) {
  return stage == 0 ? (int)(o->iters * WV_FIT_WINDOW_SHARE) : o->iters;
}

/* The stage after iteration `done` (iterations from .. done - 1 in the stage so far): the
 * next one when the stage reached its limit or converged. */
static int stage_after(const wv_fit_record *log, const wv_fit_opts *o, int stage, int *from, int done) {
  while (stage < 2 && (done >= stage_limit(o, stage) || wv_fit_converged(log, *from, done, o->patience)))
    if (++stage < 2) *from = done;
  return stage;
}

int wv_fit_stage(const wv_fit_state *st, const wv_fit_opts *o, int *from) {
  int f = 0, stage = stage_after(st->log, o, o->schedule ? 0 : 1, &f, 0);
  for (int i = 1; i <= st->iter && stage < 2; i++) stage = stage_after(st->log, o, stage, &f, i);
  if (from) *from = f;
  return stage;
}

int wv_fit_finished(const wv_fit_state *st, const wv_fit_opts *o) { return wv_fit_stage(st, o, NULL) == 2; }

/* What stays fixed during a fit: the target at the iteration resolution. */
typedef struct {
  wv_scene scene;
  wv_image photo;
  wv_image render, dcap;
  wv_image_loss *loss; /* the photo's side of every image loss term */
  const wv_fit_opts *o;
  wv_fit_timing *timing;
  wv_footprints *fp; /* the iteration scene's camera geometry, made once */
  wv_fit_opts wopts; /* a window's options (o points here) */
} fit_ctx;

static void ctx_free(fit_ctx *c) {
  wv_image_free(&c->photo), wv_image_free(&c->render), wv_image_free(&c->dcap);
  wv_image_loss_free(c->loss);
  wv_footprints_free(c->fp);
}

static wv_status ctx_init(fit_ctx *c, const wv_scene *s, const wv_image *photo, wv_descriptor *d, int scale,
                          int spp, const wv_fit_opts *o, wv_fit_timing *timing, wv_error *err) {
  wv_fit_opts keep = c->wopts; /* o may point to it */
  memset(c, 0, sizeof *c);
  c->wopts = keep;
  c->o = o == &c->wopts ? &c->wopts : o, c->timing = timing;
  wv_fit_opts so = *o;
  so.iter_scale = scale;
  wv_status st = wv_fit_check_sizes(s, d, &so, err);
  if (st) return st;
  c->scene = *s;
  if (scale > 1) {
    c->scene.width = s->width / scale, c->scene.height = s->height / scale;
    c->scene.falloff_sigma = s->falloff_sigma / scale;
    c->scene.psf_sigma = s->psf_sigma / scale; /* the blur in pixels of the smaller image */
  }
  if (spp > 0) c->scene.spp = spp;
  if (photo->w != s->width || photo->h != s->height)
    return wv_fail(err, WV_ERR_INVALID, "the photo is %d x %d but the scene renders %d x %d", photo->w, photo->h,
                   s->width, s->height);
  if (c->scene.width == photo->w && c->scene.height == photo->h) {
    if ((st = wv_image_alloc(&c->photo, photo->w, photo->h, 3, err))) return st;
    memcpy(c->photo.data, photo->data, sizeof(float) * 3 * (size_t)photo->w * photo->h);
  } else if ((st = wv_image_downsample(photo, c->scene.width, c->scene.height, &c->photo, err))) {
    return st;
  }
  wv_loss_weights lw = {o->w_pixel, o->w_struct, o->down_w, o->down_h, o->w_colour};
  if ((st = wv_image_loss_create(&c->photo, d, NULL, &lw, &c->loss, err))) return st;
  if ((st = wv_image_alloc(&c->dcap, c->scene.width, c->scene.height, 3, err))) return st;
  return wv_footprints_create(&c->scene, o->threads, &c->fp, err);
}

/* Loss of p; with grad != NULL also dL/dtheta (file units), and with dpsf != NULL
 * dL/dsigma of the iteration scene's camera blur (its pixels). */
static wv_status evaluate(fit_ctx *c, const wv_params *p, wv_fit_record *rec, double grad[WV_P_COUNT],
                          double *dpsf, wv_error *err) {
  const wv_fit_opts *o = c->o;
  wv_render_opts ro = {c->scene.spp, o->threads, NULL, NULL, c->fp};
  double t0 = omp_get_wtime();
  wv_image_free(&c->render);
  /* With a gradient wanted, render once and keep each pixel's derivative sums:
   * the adjoint depends on the render, so it is applied afterwards. */
  wv_grad_record *record = NULL;
  wv_status st = grad ? wv_render_record(&c->scene, p, &ro, NULL, &c->render, &record, err)
                      : wv_render(&c->scene, p, &ro, &c->render, NULL, err);
  if (st) return st;
  double t1 = omp_get_wtime();
  c->timing->render += t1 - t0;
  /* the image terms (and with a gradient wanted, dL/dcapture) */
  wv_loss_terms lt;
  if ((st = wv_image_loss_eval(c->loss, &c->render, &lt, grad ? &c->dcap : NULL, err))) goto fail;
  /* L_p on beta */
  double mu, sg;
  wv_fit_beta_prior(p->pattern, &mu, &sg);
  double lp = 0;
  for (int y = 0; y < 2; y++) lp += (p->heightfield[y] - mu) * (p->heightfield[y] - mu) / (2 * sg * sg);
  rec->gram = lt.gram, rec->pixel = lt.pixel, rec->prior = lp, rec->structure = lt.structure, rec->colour = lt.colour;
  rec->loss = lt.total + o->w_prior * lp;
  double t3 = omp_get_wtime();
  c->timing->descriptor += t3 - t1;
  if (!grad) return WV_OK;
  st = wv_record_grad(record, &c->dcap, grad, NULL, err);
  if (!st && dpsf) st = wv_record_grad_psf(record, &c->dcap, dpsf, err);
  wv_record_free(record);
  if (st) return st;
  c->timing->gradient += omp_get_wtime() - t3;
  grad[WV_P_BETA_WARP] += o->w_prior * (p->heightfield[WV_WARP] - mu) / (sg * sg);
  grad[WV_P_BETA_WEFT] += o->w_prior * (p->heightfield[WV_WEFT] - mu) / (sg * sg);
  return WV_OK;
fail:
  wv_record_free(record);
  return st;
}

wv_status wv_fit_loss(const wv_scene *s, const wv_image *photo, wv_descriptor *d, const wv_params *p,
                      const wv_fit_opts *o, wv_fit_record *out, wv_error *err) {
  fit_ctx c;
  wv_fit_timing t = {0};
  wv_status st = ctx_init(&c, s, photo, d, 1, 0, o, &t, err);
  if (!st) st = evaluate(&c, p, out, NULL, NULL, err);
  ctx_free(&c);
  return st;
}

static uint64_t next_rand(uint64_t *state) {
  *state += 0x9e3779b97f4a7c15ULL;
  return wv_mix64(*state);
}

/* One random step of a discrete parameter (SPEC section 7 schedule). Returns 0
 * when the step would leave the range (nothing to try). */
static int discrete_step(wv_params *p, uint64_t *rng, int iter, int iters, int density_steps) {
  uint64_t r = next_rand(rng);
  int which = (int)(r % 3), sign = (r >> 8) & 1 ? 1 : -1;
  if (which && !density_steps) return 0; /* the same draws either way: only what is tried differs */
  double frac = (double)iter / (iters > 0 ? iters : 1);
  double dstep = frac < 0.5 ? 10 : frac < 0.75 ? 5 : 2;
  if (which == 0) {
    int q = p->noise_level + sign;
    if (q < 0 || q > 10) return 0;
    p->noise_level = q;
  } else {
    double *dens = &p->density[which - 1];
    double v = *dens + sign * dstep;
    if (v < WV_DENSITY_MIN || v > WV_DENSITY_MAX) return 0;
    *dens = v;
  }
  return 1;
}

void wv_fit_centre_window(const wv_scene *s, int w, int h, wv_scene *out) {
  *out = *s;
  double t = tan(0.5 * s->vfov_deg * 3.14159265358979323846 / 180.0) * h / s->height;
  out->vfov_deg = 2.0 * atan(t) * 180.0 / 3.14159265358979323846;
  out->width = w, out->height = h;
}

wv_status wv_fit_centre_crop(const wv_image *full, int w, int h, wv_image *out, wv_error *err) {
  wv_status rc = wv_image_alloc(out, w, h, 3, err);
  if (rc) return rc;
  int x0 = (full->w - w) / 2, y0 = (full->h - h) / 2;
  for (int y = 0; y < h; y++)
    memcpy(wv_image_px(out, 0, y), wv_image_px(full, x0, y0 + y), sizeof(float) * 3 * (size_t)w);
  return WV_OK;
}

static wv_status align_densities(wv_fit_state *st, const wv_scene *s, const wv_image *photo, const wv_fit_opts *o,
                                 wv_error *err) {
  int w = s->width < 160 ? s->width : 160, h = s->height < 80 ? s->height : 80;
  w -= (s->width - w) % 2, h -= (s->height - h) % 2; /* keep the window centred on whole pixels */
  wv_scene win;
  wv_fit_centre_window(s, w, h, &win);
  win.spp = o->iter_spp;
  wv_image ref;
  wv_status rc = wv_fit_centre_crop(photo, w, h, &ref, err);
  if (rc) return rc;
  wv_footprints *fp = NULL;
  if ((rc = wv_footprints_create(&win, o->threads, &fp, err))) {
    wv_image_free(&ref);
    return rc;
  }
  wv_render_opts ro = {win.spp, o->threads, NULL, NULL, fp};
  /* Coordinate search: one density at a time over +-R with the other fixed, until
   * a full round changes nothing (each density alone already moves the SSIM). */
  wv_params cur = st->params;
  for (int y = 0; y < 2; y++) cur.density[y] = floor(cur.density[y] + 0.5);
  double best = -2, before = -2;
  wv_image img;
  if (!(rc = wv_render(&win, &cur, &ro, &img, NULL, err))) {
    rc = wv_ssim(&ref, &img, WV_SSIM_LUMA, &before, err);
    wv_image_free(&img);
  }
  best = before;
  int unchanged = 0;
  for (int pass = 0; pass < 6 && unchanged < 2 && !rc; pass++) {
    int y = pass & 1;
    int R = pass < 2 ? o->align_radius : (o->align_radius < 5 ? o->align_radius : 5); /* later rounds refine */
    double centre = cur.density[y], best_d = centre;
    for (int k = -R; k <= R && !rc; k++) {
      wv_params trial = cur;
      trial.density[y] = centre + k;
      if (k == 0 || trial.density[y] < WV_DENSITY_MIN || trial.density[y] > WV_DENSITY_MAX) continue; /* k = 0 is best already */
      if ((rc = wv_render(&win, &trial, &ro, &img, NULL, err))) break;
      double v;
      rc = wv_ssim(&ref, &img, WV_SSIM_LUMA, &v, err);
      wv_image_free(&img);
      if (!rc && v > best) best = v, best_d = trial.density[y];
    }
    unchanged = best_d == centre ? unchanged + 1 : 0;
    cur.density[y] = best_d;
  }
  wv_image_free(&ref);
  wv_footprints_free(fp);
  if (rc) return rc;
  st->params.density[0] = cur.density[0], st->params.density[1] = cur.density[1];
  st->align_ssim_before = before, st->align_ssim_after = best;
  st->aligned = 1;
  return WV_OK;
}

/* An image's two colours as ratios to their neighbourhood's mean colour (linear values,
 * so illumination and the falloff cancel): 2-means over every pixel, r[0] the darker
 * cluster, *dark_share the share of pixels in it. Returns 0 when the image has no colour
 * detail to split. */
static int colour_clusters(const wv_scene *s, const wv_image *ph, double r[2][3], double *dark_share, wv_error *err) {
  size_t n = (size_t)ph->w * ph->h;
  wv_image lin = {0}, mean = {0};
  if (wv_image_alloc(&lin, ph->w, ph->h, 3, err)) return 0;
  for (size_t i = 0; i < 3 * n; i++) lin.data[i] = wv_decode(s, ph->data[i]);
  if (wv_image_blur(&lin, 4.0, &mean, err)) {
    wv_image_free(&lin);
    return 0;
  }
  for (size_t i = 0; i < 3 * n; i++) lin.data[i] /= mean.data[i] + 1e-4f;
  wv_image_free(&mean);
  /* start: the pixels below and above the mean luminance ratio */
  double cen[2][3] = {{0}}, cnt[2] = {0};
  for (size_t i = 0; i < n; i++) {
    const float *v = lin.data + 3 * i;
    int k = luminance(v[0], v[1], v[2]) > 1.0;
    for (int ch = 0; ch < 3; ch++) cen[k][ch] += v[ch];
    cnt[k]++;
  }
  for (int it = 0; it < 10; it++) {
    for (int k = 0; k < 2; k++)
      for (int ch = 0; ch < 3; ch++) cen[k][ch] = cnt[k] > 0 ? cen[k][ch] / cnt[k] : 1.0;
    double acc[2][3] = {{0}}, nk[2] = {0};
    for (size_t i = 0; i < n; i++) {
      const float *v = lin.data + 3 * i;
      double d0 = 0, d1 = 0;
      for (int ch = 0; ch < 3; ch++) d0 += (v[ch] - cen[0][ch]) * (v[ch] - cen[0][ch]), d1 += (v[ch] - cen[1][ch]) * (v[ch] - cen[1][ch]);
      int k = d1 < d0;
      for (int ch = 0; ch < 3; ch++) acc[k][ch] += v[ch];
      nk[k]++;
    }
    memcpy(cen, acc, sizeof cen), memcpy(cnt, nk, sizeof cnt);
  }
  wv_image_free(&lin);
  for (int k = 0; k < 2; k++)
    for (int ch = 0; ch < 3; ch++) r[k][ch] = cnt[k] > 0 ? cen[k][ch] / cnt[k] : 1.0;
  double l0 = luminance(r[0][0], r[0][1], r[0][2]);
  double l1 = luminance(r[1][0], r[1][1], r[1][2]);
  *dark_share = cnt[0] / (cnt[0] + cnt[1] > 0 ? cnt[0] + cnt[1] : 1);
  if (l0 > l1) {
    for (int ch = 0; ch < 3; ch++) {
      double t = r[0][ch];
      r[0][ch] = r[1][ch], r[1][ch] = t;
    }
    *dark_share = 1 - *dark_share;
  }
  return cnt[0] > 0 && cnt[1] > 0 && fabs(l1 - l0) > 1e-3;
}

/* A start that splits warp and weft colours. A start with one diffuse colour for both
 * yarn types is a symmetric point the gradient does not leave (both colours move
 * alike), while a two-colour photo needs them apart. Candidates: the photo's two local
 * colours (colour_clusters), once and twice as far apart (yarns of one or two pixels
 * mix them), on the warp and the weft each way round, scaled to the start's mean
 * diffuse colour; and both yarns given that mean (a one-colour cloth, where the start
 * split the hues: per-channel detail the photo lacks). The candidate with the lowest
 * loss (the start included) is kept.
 * The loss sees yarns of one or two pixels at no phase (its pixel term is downsampled),
 * so it cannot tell which yarn type wears which colour. The weave can when one yarn type
 * covers more of the cloth than the other (a 2/1 twill, a satin): the way round whose
 * render has a share of dark pixels nearer the photo's is kept (the renders carry the
 * yarns' shading, which moves that share away from the weave's coverage), and a start
 * with the colours the other way round is not. Where both cover half (plain, basket, 2/2
 * twills), the swap is a shift of the weave, which the registration after the fit finds. */
static wv_status colour_split(fit_ctx *c, wv_fit_state *st, wv_error *err) {
  double r[2][3], dark_share = 0.5;
  wv_fit_record base = {0};
  wv_status rc = evaluate(c, &st->params, &base, NULL, NULL, err);
  if (rc || !colour_clusters(&c->scene, &c->photo, r, &dark_share, err)) return rc;
  wv_weave w;
  double warp_share = 0.5;
  if (!wv_params_weave(&st->params, &w, NULL)) {
    int n = 0;
    for (int i = 0; i < w.rows; i++)
      for (int j = 0; j < w.cols; j++) n += w.p[i][j] != 0;
    warp_share = (double)n / (w.rows * w.cols);
  }
  wv_params cand_p[6];
  double cand_loss[6], lo, hi, gap[2] = {0, 0};
  for (int cand = 1; cand <= 5; cand++) {
    double alpha = cand <= 2 ? 1.0 : cand <= 4 ? 2.0 : 0.0; /* 5: both the mean colour */
    int dark = (cand & 1) ? WV_WARP : WV_WEFT;              /* the yarn type given the darker colour */
    wv_params *p = &cand_p[cand];
    *p = st->params;
    for (int ch = 0; ch < 3; ch++) {
      double m = 0.5 * (st->params.diffuse[WV_WARP][ch] + st->params.diffuse[WV_WEFT][ch]);
      for (int k = 0; k < 2; k++) {
        int y = k == 0 ? dark : 1 - dark, id = y == WV_WARP ? WV_P_KD_WARP_R + ch : WV_P_KD_WEFT_R + ch;
        wv_param_range(id, &lo, &hi);
        double v = m * (1 + alpha * (r[k][ch] - 1));
        p->diffuse[y][ch] = v < lo ? lo : v > hi ? hi : v;
      }
    }
    cand_loss[cand] = INFINITY;
  }
  /* the yarn type the darker colour must go on, or -1: either */
  int need = -1;
  if (fabs(warp_share - 0.5) >= SPLIT_WEAVE_MIN) {
    for (int cand = 1; cand <= 2 && !rc; cand++) {
      wv_fit_record rec = {0};
      double rr[2][3], share = 0.5;
      if ((rc = evaluate(c, &cand_p[cand], &rec, NULL, NULL, err))) break;
      cand_loss[cand] = rec.loss;
      if (colour_clusters(&c->scene, &c->render, rr, &share, err)) {
        /* the render's clusters matched to the photo's by colour: yarns that differ in hue
         * more than in brightness can order them the other way by luminance */
        double same = 0, swapped = 0;
        for (int ch = 0; ch < 3; ch++)
          same += sq(rr[0][ch] - r[0][ch]) + sq(rr[1][ch] - r[1][ch]),
              swapped += sq(rr[0][ch] - r[1][ch]) + sq(rr[1][ch] - r[0][ch]);
        if (swapped < same) share = 1 - share;
      }
      gap[cand - 1] = fabs(share - dark_share);
    }
    if (!rc && fabs(gap[0] - gap[1]) >= SPLIT_SHARE_GAP) need = gap[0] < gap[1] ? WV_WARP : WV_WEFT;
  }
  double lum[2];
  for (int y = 0; y < 2; y++)
    lum[y] = luminance(st->params.diffuse[y][0], st->params.diffuse[y][1], st->params.diffuse[y][2]);
  int start_dark = lum[WV_WARP] < lum[WV_WEFT] ? WV_WARP : WV_WEFT;
  int start_ok = need < 0 || start_dark == need || fabs(lum[0] - lum[1]) < SPLIT_LUM_SAME * (lum[0] + lum[1]);
  double best = start_ok ? base.loss : INFINITY;
  int choice = 0;
  wv_params best_p = st->params;
  for (int cand = 1; cand <= 5 && !rc; cand++) {
    int dark = (cand & 1) ? WV_WARP : WV_WEFT;
    if (cand <= 4 && need >= 0 && dark != need) continue;
    if (cand_loss[cand] == INFINITY) {
      wv_fit_record rec = {0};
      if ((rc = evaluate(c, &cand_p[cand], &rec, NULL, NULL, err))) break;
      cand_loss[cand] = rec.loss;
    }
    if (cand_loss[cand] < best) best = cand_loss[cand], choice = cand, best_p = cand_p[cand];
  }
  st->params = best_p;
  st->colour_split = choice;
  return rc;
}

/* The first stage's window: the centre of the scene, 1/WV_FIT_WINDOW_DIV of each side, the
 * same pixels as the whole image there; the whole image when the window would be too small
 * for the fit. */
static void stage_window(const wv_scene *s, const wv_descriptor *d, const wv_fit_opts *o, int *w, int *h) {
  *w = s->width / WV_FIT_WINDOW_DIV, *h = s->height / WV_FIT_WINDOW_DIV;
  *w -= (s->width - *w) % 2, *h -= (s->height - *h) % 2; /* centred on whole pixels */
  wv_scene win;
  wv_fit_centre_window(s, *w, *h, &win);
  if (wv_fit_check_sizes(&win, d, o, NULL)) *w = s->width, *h = s->height;
}

/* The context of a stage: 0 the centre window, 1 the whole image. */
static wv_status stage_ctx(fit_ctx *c, int stage, const wv_scene *s, const wv_image *photo, wv_descriptor *d,
                           const wv_fit_opts *o, wv_fit_timing *timing, wv_error *err) {
  int w = s->width, h = s->height;
  if (stage == 0) stage_window(s, d, o, &w, &h);
  if (w == s->width && h == s->height) return ctx_init(c, s, photo, d, o->iter_scale, o->iter_spp, o, timing, err);
  wv_scene win;
  wv_image pw;
  wv_fit_centre_window(s, w, h, &win);
  wv_status rc = wv_fit_centre_crop(photo, w, h, &pw, err);
  if (rc) return rc;
  /* the pixel term's cells as large as the whole image's (there they are the centre cells):
   * smaller ones would fit the window's light to a detail the whole image's term ignores */
  c->wopts = *o;
  c->wopts.down_w = (o->down_w * w + s->width / 2) / s->width;
  c->wopts.down_h = (o->down_h * h + s->height / 2) / s->height;
  if (c->wopts.down_w < 1) c->wopts.down_w = 1;
  if (c->wopts.down_h < 1) c->wopts.down_h = 1;
  rc = ctx_init(c, &win, &pw, d, o->iter_scale, o->iter_spp, &c->wopts, timing, err);
  wv_image_free(&pw);
  return rc;
}

wv_status wv_fit_run(wv_fit_state *st, const wv_scene *s, const wv_image *photo, wv_descriptor *d,
                     const wv_fit_opts *o, wv_fit_callback cb, void *user, wv_error *err) {
  wv_status vs = wv_fit_opts_validate(o, err);
  if (vs) return vs;
  if (o->iters > st->log_cap) {
    wv_fit_record *nl = realloc(st->log, sizeof *nl * (size_t)o->iters);
    if (!nl) return wv_fail(err, WV_ERR_NOMEM, "out of memory for the fit log");
    st->log = nl, st->log_cap = o->iters;
  }
  int from = 0, stage = wv_fit_stage(st, o, &from);
  if (stage < 2) st->aligned = st->registered = st->distorted = 0; /* more iterations: align again after them */
  /* One context per stage (the coarse one and the full one), each made once: the photo's
   * side of the loss and the camera geometry do not change between iterations. */
  fit_ctx cx[2];
  int made[2] = {0, 0};
  double scale = o->iter_scale;
  memset(cx, 0, sizeof cx);
  double t_start = omp_get_wtime();
  wv_status rc = wv_fit_check_sizes(s, d, o, err);
  if (!rc && (photo->w != s->width || photo->h != s->height))
    rc = wv_fail(err, WV_ERR_INVALID, "the photo is %d x %d but the scene renders %d x %d", photo->w, photo->h,
                 s->width, s->height);
  if (!rc && !st->psf_done) {
    /* the camera blur: given by the options or the scene, else measured on the start */
    double tp = omp_get_wtime();
    st->psf_sigma = o->psf_sigma >= 0 ? o->psf_sigma : s->psf_sigma;
    if (o->psf_sigma < 0 && !(s->psf_sigma > 0)) {
      wv_scene se;
      wv_fit_scene(st, s, &se);
      rc = wv_psf_estimate(&se, photo, &st->params, o->threads, &st->psf_sigma, NULL, err);
    }
    st->psf_done = !rc;
    st->psf_start = st->psf_sigma;
    /* a measured blur is fitted with the parameters (a given one, or none measured, stays) */
    st->psf_fit = o->psf_fit && o->psf_sigma < 0 && !(s->psf_sigma > 0) && st->psf_sigma > 0;
    st->timing.discrete += omp_get_wtime() - tp;
  }
  wv_scene sb; /* the scene with the fit's camera blur */
  wv_fit_scene(st, s, &sb);
  if (!rc && st->iter == 0 && o->colour_split && o->iters > 0) {
    /* at the full iteration scale: the split reads the colours of single yarns */
    double td = omp_get_wtime();
    wv_fit_timing saved = st->timing;
    if (!(rc = stage_ctx(&cx[1], 1, s, photo, d, o, &st->timing, err))) {
      made[1] = 1;
      cx[1].scene.psf_sigma = sb.psf_sigma / scale;
      rc = colour_split(&cx[1], st, err);
    }
    st->timing.render = saved.render, st->timing.descriptor = saved.descriptor; /* counted as a discrete step */
    st->timing.discrete += omp_get_wtime() - td;
  }
  while (!rc && stage < 2) {
    int k = stage > 0;
    fit_ctx *c = &cx[k];
    if (!made[k]) {
      if ((rc = stage_ctx(c, k, s, photo, d, o, &st->timing, err))) break;
      made[k] = 1;
    }
    c->scene.psf_sigma = (st->psf_done ? st->psf_sigma : s->psf_sigma) / scale;
    wv_fit_record rec = {0};
    rec.iter = st->iter;
    double g[WV_P_COUNT] = {0};
    double dpsf = 0;
    if ((rc = evaluate(c, &st->params, &rec, g, st->psf_fit ? &dpsf : NULL, err))) break;
    int t = st->iter + 1;
    /* Discrete search: a random step is kept only if it lowers the loss. It is compared with
     * this iteration's render (the parameters the gradient was taken at), so it costs one
     * forward render; the continuous parameters then take their Adam step from there (the
     * discrete ones are not among them). */
    if (o->discrete_every > 0 && t % o->discrete_every == 0) {
      double td = omp_get_wtime();
      wv_fit_timing saved = st->timing;
      wv_params trial = st->params;
      if (discrete_step(&trial, &st->rng, st->iter, o->iters, o->density_steps)) {
        wv_fit_record alt = {0};
        if ((rc = evaluate(c, &trial, &alt, NULL, NULL, err))) break;
        rec.discrete_tried = 1;
        if (alt.loss < rec.loss) {
          st->params = trial;
          rec.discrete_kept = 1;
        }
      }
      /* account the search as its own item, not as render/descriptor time */
      double spent = omp_get_wtime() - td;
      st->timing.render = saved.render, st->timing.descriptor = saved.descriptor;
      st->timing.discrete += spent;
    }
    /* Adam in normalised coordinates z = (theta - lo) / (hi - lo), projected onto [0, 1];
     * z is remade from the parameters every step, so a resumed fit repeats this exactly. */
    float z[WV_P_COUNT], gz[WV_P_COUNT];
    for (int i = 0; i < WV_P_COUNT; i++) {
      double lo, hi;
      wv_param_range(i, &lo, &hi);
      double gi = g[i] * (hi - lo);
      gz[i] = isfinite(gi) ? (float)gi : 0.0f;
      z[i] = (float)((wv_param_get(&st->params, i) - lo) / (hi - lo));
    }
    wv_nn_adam adam = {WV_P_COUNT, (float)o->lr, 0.9f, 0.999f, 1e-8f, 0.0f, st->iter, st->adam_m, st->adam_v};
    wv_nn_adam_step_box(&adam, z, gz, 0.0f, 1.0f);
    for (int i = 0; i < WV_P_COUNT; i++) {
      double lo, hi;
      wv_param_range(i, &lo, &hi);
      wv_param_set(&st->params, i, lo + z[i] * (hi - lo));
    }
    if (st->psf_fit) {
      /* the camera blur, by the same Adam on z = sigma / WV_PSF_RANGE: a measured blur
       * and the parameters trade contrast, so they settle together */
      float zs = (float)(st->psf_sigma / WV_PSF_RANGE), gs = (float)(dpsf / scale * WV_PSF_RANGE);
      if (!isfinite(gs)) gs = 0.0f;
      wv_nn_adam a1 = {1, (float)o->lr, 0.9f, 0.999f, 1e-8f, 0.0f, st->iter, &st->psf_m, &st->psf_v};
      wv_nn_adam_step_box(&a1, &zs, &gs, 0.0f, 1.0f);
      st->psf_sigma = zs * WV_PSF_RANGE;
    }
    st->log[st->iter] = rec;
    st->iter++;
    stage = stage_after(st->log, o, stage, &from, st->iter);
    st->timing.total += omp_get_wtime() - t_start;
    t_start = omp_get_wtime();
    if (cb && cb(user, st, o)) break;
  }
  for (int k = 0; k < 2; k++)
    if (made[k]) ctx_free(&cx[k]);
  wv_fit_scene(st, s, &sb); /* the blur as fitted; the offset as given (the alignment comes before the registration) */
  sb.fabric_offset[0] = s->fabric_offset[0], sb.fabric_offset[1] = s->fabric_offset[1];
  int over = !rc && stage == 2;
  if (over && !st->aligned && o->align_radius > 0) {
    double ta = omp_get_wtime();
    rc = align_densities(st, &sb, photo, o, err);
    st->timing.discrete += omp_get_wtime() - ta;
    st->timing.total += omp_get_wtime() - ta;
  }
  if (!rc && over && !st->registered && o->register_radius > 0) {
    double ta = omp_get_wtime();
    rc = wv_fit_register(st, s, photo, o, err);
    st->timing.registration += omp_get_wtime() - ta;
    st->timing.total += omp_get_wtime() - ta;
  }
  if (!rc && over && !st->distorted && o->distort_degree > 0) {
    double ta = omp_get_wtime();
    rc = wv_fit_distort(st, s, photo, o, err);
    st->timing.distortion += omp_get_wtime() - ta;
    st->timing.total += omp_get_wtime() - ta;
  }
  return rc;
}

/* ---- checkpoints ---- */

static json_t *darray(const double *v, int n) {
  json_t *a = json_array();
  for (int i = 0; i < n; i++) json_array_append_new(a, json_real(v[i]));
  return a;
}

static json_t *params_json(const wv_params *p) {
  char *s = wv_params_to_json(p);
  json_t *o = json_loads(s, 0, NULL);
  free(s);
  return o;
}

wv_status wv_fit_checkpoint_write(const char *path, const wv_fit_state *st, const wv_fit_opts *o,
                                  const char *descriptor_name, wv_error *err) {
  json_t *root = json_object();
  json_object_set_new(root, "kind", json_string("woven-fit-checkpoint"));
  json_object_set_new(root, "version", json_integer(1));
  json_object_set_new(root, "descriptor", json_string(descriptor_name));
  json_object_set_new(root, "iter", json_integer(st->iter));
  json_object_set_new(root, "aligned", json_boolean(st->aligned));
  json_object_set_new(root, "registration",
                      json_pack("{s:b,s:[f,f],s:f,s:f,s:f,s:f}", "done", st->registered, "offset_mm",
                                st->offset_mm[0], st->offset_mm[1], "ncc_before", st->reg_ncc_before, "ncc_after",
                                st->reg_ncc_after, "ssim_before", st->reg_ssim_before, "ssim_after",
                                st->reg_ssim_after));
  json_t *dist = json_pack("{s:b,s:f,s:f,s:f}", "done", st->distorted, "extent_mm", st->distort_extent_mm,
                           "ssim_before", st->dist_ssim_before, "ssim_after", st->dist_ssim_after);
  json_object_set_new(dist, "x", darray(st->distort[0], WV_DISTORT_TERMS));
  json_object_set_new(dist, "y", darray(st->distort[1], WV_DISTORT_TERMS));
  json_object_set_new(root, "distortion", dist);
  json_object_set_new(root, "start", params_json(&st->start));
  json_object_set_new(root, "params", params_json(&st->params));
  double am[WV_P_COUNT], av[WV_P_COUNT];
  for (int i = 0; i < WV_P_COUNT; i++) am[i] = st->adam_m[i], av[i] = st->adam_v[i];
  json_object_set_new(root, "adam_m", darray(am, WV_P_COUNT));
  json_object_set_new(root, "adam_v", darray(av, WV_P_COUNT));
  char rng[32];
  snprintf(rng, sizeof rng, "%016llx", (unsigned long long)st->rng);
  json_object_set_new(root, "rng", json_string(rng));
  json_object_set_new(root, "timing", json_pack("{s:f,s:f,s:f,s:f,s:f}", "render", st->timing.render, "gradient",
                                                st->timing.gradient, "descriptor", st->timing.descriptor,
                                                "discrete", st->timing.discrete, "total", st->timing.total));
  json_object_set_new(root, "opts",
                      json_pack("{s:i,s:f,s:f,s:f,s:i,s:i,s:i,s:i,s:i,s:I,s:i}", "iters", o->iters, "lr", o->lr,
                                "w_prior", o->w_prior, "w_pixel", o->w_pixel, "down_w", o->down_w, "down_h",
                                o->down_h, "discrete_every", o->discrete_every, "iter_scale", o->iter_scale,
                                "iter_spp", o->iter_spp, "seed", (json_int_t)o->seed, "align_radius",
                                o->align_radius));
  json_object_set_new(json_object_get(root, "opts"), "register_radius", json_integer(o->register_radius));
  json_object_set_new(json_object_get(root, "opts"), "w_struct", json_real(o->w_struct));
  json_object_set_new(json_object_get(root, "opts"), "w_colour", json_real(o->w_colour));
  json_object_set_new(json_object_get(root, "opts"), "colour_split", json_integer(o->colour_split));
  json_object_set_new(json_object_get(root, "opts"), "density_steps", json_integer(o->density_steps));
  json_object_set_new(root, "colour_split", json_integer(st->colour_split));
  json_object_set_new(root, "camera_blur",
                      json_pack("{s:b,s:f,s:f,s:b,s:f,s:f}", "done", st->psf_done, "sigma_px", st->psf_sigma, "measured_px",
                                st->psf_start, "fitted", st->psf_fit, "adam_m", (double)st->psf_m, "adam_v",
                                (double)st->psf_v));
  json_object_set_new(json_object_get(root, "opts"), "psf_fit", json_integer(o->psf_fit));
  json_object_set_new(json_object_get(root, "opts"), "schedule", json_integer(o->schedule));
  json_object_set_new(json_object_get(root, "opts"), "patience", json_integer(o->patience));
  json_t *log = json_array();
  for (int i = 0; i < st->iter; i++) {
    const wv_fit_record *r = &st->log[i];
    json_array_append_new(log, json_pack("[i,f,f,f,f,i,i,f,f]", r->iter, r->loss, r->gram, r->prior, r->pixel,
                                         r->discrete_tried, r->discrete_kept, r->structure, r->colour));
  }
  json_object_set_new(root, "log", log);
  char *text = json_dumps(root, JSON_COMPACT | JSON_REAL_PRECISION(17));
  json_decref(root);
  if (!text) return wv_fail(err, WV_ERR_NOMEM, "%s: cannot format checkpoint", path);
  wv_status s = wv_write_file_atomic(path, text, strlen(text), err);
  free(text);
  return s;
}

static wv_status read_params_obj(json_t *o, const char *path, const char *key, wv_params *p, wv_error *err) {
  json_t *v = json_object_get(o, key);
  if (!json_is_object(v)) return wv_fail(err, WV_ERR_FORMAT, "%s: checkpoint has no '%s' parameters", path, key);
  char *s = json_dumps(v, JSON_REAL_PRECISION(17));
  char src[600];
  snprintf(src, sizeof src, "%s '%s'", path, key);
  wv_status st = wv_params_parse(s, src, p, err);
  free(s);
  return st;
}

static wv_status read_darray(json_t *o, const char *key, double *v, int n, double lo, double hi, wv_error *err) {
  json_t *a = json_object_get(o, key);
  if (!json_is_array(a) || (int)json_array_size(a) != n)
    return wv_fail(err, WV_ERR_INVALID, "'%s' must be an array of %d numbers", key, n);
  char name[64];
  for (int i = 0; i < n; i++) {
    snprintf(name, sizeof name, "%s[%d]", key, i);
    wv_status st = wv_json_number_value(json_array_get(a, i), name, lo, hi, &v[i], err);
    if (st) return st;
  }
  return WV_OK;
}

/* Every value of a checkpoint is checked: it sizes arrays, seeds the search and
 * moves the weave; messages name the key (the caller adds the file). */
static wv_status read_checkpoint(json_t *root, const char *path, wv_fit_state *st, wv_fit_opts *o,
                                 char *descriptor_name, size_t name_cap, wv_error *err) {
  wv_status rc;
  json_t *kind = json_object_get(root, "kind");
  if (!json_is_string(kind) || strcmp(json_string_value(kind), "woven-fit-checkpoint") ||
      !json_is_integer(json_object_get(root, "version")) || json_integer_value(json_object_get(root, "version")) != 1)
    return wv_fail(err, WV_ERR_FORMAT, "not a woven fit checkpoint (version 1)");
  wv_fit_opts_default(o);
  o->register_radius = 0; /* absent in checkpoints older than the registration */
  o->w_struct = 0, o->colour_split = 0; /* absent before the structure term: a resume stays without it */
  o->w_colour = 0;                       /* absent before the detail-colour term: likewise */
  o->psf_sigma = 0;                      /* absent before the camera blur: none */
  o->psf_fit = 0;                        /* absent before the blur was fitted: as measured */
  o->distort_degree = 0;                 /* absent before the distortion: none */
  o->schedule = o->patience = 0;         /* absent before the schedule: every iteration alike, all of them */
  if ((rc = read_opts(json_object_get(root, "opts"), o, err))) return rc;
  wv_params start;
  if ((rc = read_params_obj(root, path, "start", &start, err))) return rc;
  if ((rc = wv_fit_state_init(st, &start, o, err))) return rc;
  if ((rc = read_params_obj(root, path, "params", &st->params, err))) return rc;
  double am[WV_P_COUNT], av[WV_P_COUNT];
  if ((rc = read_darray(root, "adam_m", am, WV_P_COUNT, -1e30, 1e30, err))) return rc;
  if ((rc = read_darray(root, "adam_v", av, WV_P_COUNT, 0, 1e30, err))) return rc;
  for (int i = 0; i < WV_P_COUNT; i++) st->adam_m[i] = (float)am[i], st->adam_v[i] = (float)av[i];
  /* The RNG state is written as exactly 16 hex digits. */
  json_t *jr = json_object_get(root, "rng");
  const char *rng = json_string_value(jr);
  if (!rng || strlen(rng) != 16 || strspn(rng, "0123456789abcdefABCDEF") != 16)
    return wv_fail(err, WV_ERR_INVALID, "'rng' must be a string of 16 hexadecimal digits");
  st->rng = strtoull(rng, NULL, 16);
  const char *dn = json_string_value(json_object_get(root, "descriptor"));
  if (!dn || !*dn || strlen(dn) >= name_cap) return wv_fail(err, WV_ERR_INVALID, "'descriptor' must be a name");
  long long it = 0;
  if ((rc = wv_json_integer(root, NULL, "iter", 0, o->iters, 1, &it, err))) return rc;
  json_t *log = json_object_get(root, "log");
  if (!json_is_array(log) || (long long)json_array_size(log) != it)
    return wv_fail(err, WV_ERR_INVALID, "'log' must hold one entry per iteration done (%lld)", it);
  json_t *al = json_object_get(root, "aligned");
  if (!json_is_boolean(al)) return wv_fail(err, WV_ERR_INVALID, "'aligned' must be true or false");
  st->aligned = json_is_true(al);
  json_t *cb = json_object_get(root, "camera_blur"); /* absent before it existed: none, settled */
  st->psf_done = 1, st->psf_sigma = 0;
  if (cb) {
    json_t *done = json_object_get(cb, "done");
    if (!json_is_boolean(done)) return wv_fail(err, WV_ERR_INVALID, "'camera_blur.done' must be true or false");
    st->psf_done = json_is_true(done);
    if ((rc = wv_json_number(cb, "camera_blur", "sigma_px", 0, WV_PSF_MAX_SIGMA, 1, &st->psf_sigma, err))) return rc;
    /* absent before the blur was fitted: as measured, no moments */
    double m = 0, v = 0;
    st->psf_start = st->psf_sigma;
    if ((rc = wv_json_number(cb, "camera_blur", "measured_px", 0, WV_PSF_MAX_SIGMA, 0, &st->psf_start, err)) ||
        (rc = wv_json_number(cb, "camera_blur", "adam_m", -1e30, 1e30, 0, &m, err)) ||
        (rc = wv_json_number(cb, "camera_blur", "adam_v", 0, 1e30, 0, &v, err)))
      return rc;
    st->psf_m = (float)m, st->psf_v = (float)v;
    json_t *fitted = json_object_get(cb, "fitted");
    if (fitted && !json_is_boolean(fitted))
      return wv_fail(err, WV_ERR_INVALID, "'camera_blur.fitted' must be true or false");
    st->psf_fit = json_is_true(fitted);
  }
  long long cs = 0; /* the start's colour split (absent before it existed: none) */
  if ((rc = wv_json_integer(root, NULL, "colour_split", 0, 5, 0, &cs, err))) return rc;
  st->colour_split = (int)cs;
  json_t *reg = json_object_get(root, "registration"); /* absent in checkpoints before it existed */
  if (reg) {
    json_t *done = json_object_get(reg, "done"), *off = json_object_get(reg, "offset_mm");
    if (!json_is_boolean(done)) return wv_fail(err, WV_ERR_INVALID, "'registration.done' must be true or false");
    st->registered = json_is_true(done);
    if (!json_is_array(off) || json_array_size(off) != 2)
      return wv_fail(err, WV_ERR_INVALID, "'registration.offset_mm' must be an array of 2 numbers");
    for (int i = 0; i < 2; i++) {
      char name[40];
      snprintf(name, sizeof name, "registration.offset_mm[%d]", i);
      if ((rc = wv_json_number_value(json_array_get(off, i), name, -WV_SCENE_MAX_OFFSET_MM, WV_SCENE_MAX_OFFSET_MM,
                                     &st->offset_mm[i], err)))
        return rc;
    }
    if ((rc = wv_json_number(reg, "registration", "ncc_before", -2, 2, 1, &st->reg_ncc_before, err)) ||
        (rc = wv_json_number(reg, "registration", "ncc_after", -2, 2, 1, &st->reg_ncc_after, err)) ||
        (rc = wv_json_number(reg, "registration", "ssim_before", -2, 2, 1, &st->reg_ssim_before, err)) ||
        (rc = wv_json_number(reg, "registration", "ssim_after", -2, 2, 1, &st->reg_ssim_after, err)))
      return rc;
  } else {
    st->registered = 1; /* an old fit: nothing to redo */
  }
  json_t *dist = json_object_get(root, "distortion"); /* absent in checkpoints before it existed */
  st->distorted = 1;
  if (dist) {
    json_t *done = json_object_get(dist, "done");
    if (!json_is_boolean(done)) return wv_fail(err, WV_ERR_INVALID, "'distortion.done' must be true or false");
    st->distorted = json_is_true(done);
    if ((rc = wv_json_number(dist, "distortion", "extent_mm", 0, WV_SCENE_MAX_MM, 1, &st->distort_extent_mm, err)) ||
        (rc = wv_json_number(dist, "distortion", "ssim_before", -2, 2, 1, &st->dist_ssim_before, err)) ||
        (rc = wv_json_number(dist, "distortion", "ssim_after", -2, 2, 1, &st->dist_ssim_after, err)) ||
        (rc = read_darray(dist, "x", st->distort[0], WV_DISTORT_TERMS, -WV_SCENE_MAX_OFFSET_MM, WV_SCENE_MAX_OFFSET_MM,
                          err)) ||
        (rc = read_darray(dist, "y", st->distort[1], WV_DISTORT_TERMS, -WV_SCENE_MAX_OFFSET_MM, WV_SCENE_MAX_OFFSET_MM,
                          err)))
      return rc;
  }
  snprintf(descriptor_name, name_cap, "%s", dn);
  st->iter = (int)it;
  for (int i = 0; i < st->iter; i++) {
    wv_fit_record *r = &st->log[i];
    json_t *e = json_array_get(log, i);
    /* the 8th value, the structure term, and the 9th, the detail-colour term, are absent in
     * fits made before they existed */
    if (!json_is_array(e) || json_array_size(e) < 7 || json_array_size(e) > 9)
      return wv_fail(err, WV_ERR_INVALID, "'log[%d]' must be an array of 7 to 9 values", i);
    double *v[4] = {&r->loss, &r->gram, &r->prior, &r->pixel};
    long long x;
    char name[40];
    snprintf(name, sizeof name, "log[%d][0]", i);
    if ((rc = wv_json_integer_value(json_array_get(e, 0), name, i, i, &x, err))) return rc;
    r->iter = i;
    for (int k = 0; k < 4; k++) {
      snprintf(name, sizeof name, "log[%d][%d]", i, k + 1);
      if ((rc = wv_json_number_value(json_array_get(e, (size_t)k + 1), name, -1e30, 1e30, v[k], err))) return rc;
    }
    for (int k = 0; k < 2; k++) {
      snprintf(name, sizeof name, "log[%d][%d]", i, k + 5);
      if ((rc = wv_json_integer_value(json_array_get(e, (size_t)k + 5), name, 0, 1, &x, err))) return rc;
      *(k ? &r->discrete_kept : &r->discrete_tried) = (int)x;
    }
    r->structure = r->colour = 0;
    double *extra[2] = {&r->structure, &r->colour};
    for (int k = 7; k < (int)json_array_size(e); k++) {
      snprintf(name, sizeof name, "log[%d][%d]", i, k);
      if ((rc = wv_json_number_value(json_array_get(e, (size_t)k), name, -1e30, 1e30, extra[k - 7], err))) return rc;
    }
  }
  json_t *tm = json_object_get(root, "timing"); /* informative: absent or odd values are not fatal */
  double *tv[5] = {&st->timing.render, &st->timing.gradient, &st->timing.descriptor, &st->timing.discrete,
                   &st->timing.total};
  static const char *tk[5] = {"render", "gradient", "descriptor", "discrete", "total"};
  for (int k = 0; k < 5; k++)
    if ((rc = wv_json_number(tm, "timing", tk[k], 0, 1e12, 0, tv[k], err))) return rc;
  return WV_OK;
}

wv_status wv_fit_checkpoint_read(const char *path, wv_fit_state *st, wv_fit_opts *o, char *descriptor_name,
                                 size_t name_cap, wv_error *err) {
  memset(st, 0, sizeof *st);
  json_t *root;
  wv_status rc = wv_json_load_file(path, &root, err);
  if (rc) return rc;
  rc = read_checkpoint(root, path, st, o, descriptor_name, name_cap, err);
  if (rc) {
    if (err && strncmp(err->msg, path, strlen(path))) wv_error_prefix(err, "%s", path);
    wv_fit_state_free(st);
  }
  json_decref(root);
  return rc;
}
