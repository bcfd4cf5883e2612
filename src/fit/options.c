/* The fit's options (include/woven/fit.h): their defaults, their ranges in one table, and
 * the options a checkpoint stores, as JSON and back. */
#include "woven/fit.h"
#include "fit/fit_internal.h"

#include <stddef.h>
#include <string.h>

#include "util/json.h"
#include "woven/loss.h"

void wv_fit_opts_default(wv_fit_opts *o) {
  memset(o, 0, sizeof *o);
  o->iters = 200;
  o->lr = 0.02;
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
  o->noise_sweep = 1;
  o->width_sweep = 1;
  o->forward_sweep = 1;
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
    OPT(noise_sweep, 'i', 0, 1, 2),
    OPT(width_sweep, 'i', 0, 1, 2),
    OPT(forward_sweep, 'i', 0, 1, 2),
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
wv_status wv_fit_opts_read_json(json_t *opts, wv_fit_opts *o, wv_error *err) {
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

json_t *wv_fit_opts_json(const wv_fit_opts *o) {
  json_t *j = json_pack("{s:i,s:f,s:f,s:f,s:i,s:i,s:i,s:i,s:i,s:I,s:i}", "iters", o->iters, "lr", o->lr, "w_prior",
                        o->w_prior, "w_pixel", o->w_pixel, "down_w", o->down_w, "down_h", o->down_h, "discrete_every",
                        o->discrete_every, "iter_scale", o->iter_scale, "iter_spp", o->iter_spp, "seed",
                        (json_int_t)o->seed, "align_radius", o->align_radius);
  json_object_set_new(j, "register_radius", json_integer(o->register_radius));
  json_object_set_new(j, "w_struct", json_real(o->w_struct));
  json_object_set_new(j, "w_colour", json_real(o->w_colour));
  json_object_set_new(j, "colour_split", json_integer(o->colour_split));
  json_object_set_new(j, "density_steps", json_integer(o->density_steps));
  json_object_set_new(j, "psf_fit", json_integer(o->psf_fit));
  json_object_set_new(j, "schedule", json_integer(o->schedule));
  json_object_set_new(j, "patience", json_integer(o->patience));
  json_object_set_new(j, "noise_sweep", json_integer(o->noise_sweep));
  json_object_set_new(j, "width_sweep", json_integer(o->width_sweep));
  json_object_set_new(j, "forward_sweep", json_integer(o->forward_sweep));
  return j;
}
