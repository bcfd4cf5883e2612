/* The fit's state (include/woven/fit.h): making and freeing it, and the scene it
 * settles on (the registration's offset, the camera blur, the distortion). The
 * optimiser, the registration, the distortion and the checkpoints all use these;
 * nothing here calls them back. */
#include "woven/fit.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "util/hash.h"

wv_status wv_fit_state_init(wv_fit_state *st, const wv_params *start, const wv_fit_opts *o, wv_error *err) {
  memset(st, 0, sizeof *st);
  wv_status s = wv_params_validate(start, err);
  if (s) return s;
  st->start = st->params = *start;
  st->align_wsc_before = st->align_wsc_after = -2; /* not measured */
  st->t_scale = 1, st->t_density_ratio[0] = st->t_density_ratio[1] = 1;
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

void wv_fit_scene(const wv_fit_state *st, const wv_scene *s, wv_scene *out) {
  *out = *s;
  out->fabric_offset[0] += st->offset_mm[0];
  out->fabric_offset[1] += st->offset_mm[1];
  if (st->psf_done) out->psf_sigma = st->psf_sigma;
  if (st->distort_extent_mm > 0) {
    out->distort_extent_mm = st->distort_extent_mm;
    for (int k = 0; k < 2; k++)
      for (int t = 0; t < WV_DISTORT_TERMS; t++) out->distort[k][t] += st->distort[k][t];
  }
}

void wv_fit_scene_t(const wv_fit_state *st, const wv_scene *s_t, wv_scene *out) {
  if (!st->t_related) { /* not measured yet: one camera's view of one cloth */
    wv_fit_scene(st, s_t, out);
    return;
  }
  *out = *s_t;
  if (st->psf_done) out->psf_sigma = st->psf_sigma;
  if (st->t_found) {
    /* its yarns 1 / t_scale times as many pixels apart: a field of view t_scale times as wide */
    double half = 0.5 * s_t->vfov_deg * 3.14159265358979323846 / 180;
    out->vfov_deg = 2 * atan(st->t_scale * tan(half)) * 180 / 3.14159265358979323846;
    out->rotation_deg += st->t_rotation_deg;
  }
  out->fabric_offset[0] += st->t_offset_mm[0];
  out->fabric_offset[1] += st->t_offset_mm[1];
  if (st->t_distort_extent_mm > 0) {
    out->distort_extent_mm = st->t_distort_extent_mm;
    for (int k = 0; k < 2; k++)
      for (int t = 0; t < WV_DISTORT_TERMS; t++) out->distort[k][t] += st->t_distort[k][t];
  }
}

void wv_fit_params_t(const wv_fit_state *st, const wv_params *p, wv_params *out) {
  *out = *p;
  for (int k = 0; k < 2; k++) {
    double r = st->t_density_ratio[k] > 0 ? st->t_density_ratio[k] : 1; /* 0: a state not made here */
    double d = p->density[k] * r;
    out->density[k] = d < WV_DENSITY_MIN ? WV_DENSITY_MIN : d > WV_DENSITY_MAX ? WV_DENSITY_MAX : d;
  }
}
