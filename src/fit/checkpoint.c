/* The fit's checkpoints (include/woven/fit.h): the state and the options as JSON, written
 * atomically and read back with every value checked, so a resumed fit continues exactly. */
#include "woven/analysis.h"
#include "woven/fit.h"
#include "fit/fit_internal.h"

#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/json_file.h"
#include "util/json.h"
#include "woven/io.h"

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
  json_object_set_new(root, "version", json_integer(4)); /* 4: Adam's moments of every WV_P_COUNT parameter */
  json_object_set_new(root, "descriptor", json_string(descriptor_name));
  json_object_set_new(root, "iter", json_integer(st->iter));
  json_object_set_new(root, "aligned", json_boolean(st->aligned));
  json_object_set_new(root, "pair", json_boolean(st->pair));
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
  json_object_set_new(root, "opts", wv_fit_opts_json(o));
  json_object_set_new(root, "colour_split", json_integer(st->colour_split));
  if (st->open_measured) json_object_set_new(root, "open_area_photo", json_real(st->open_photo));
  if (st->pair) { /* the transmission colours' quasi-Newton memory: a resume steps as a straight run */
    const wv_nn_lbfgs *q = &st->t_qn;
    double sf[WV_NN_LBFGS_MEM * WV_NN_LBFGS_DIM], yf[WV_NN_LBFGS_MEM * WV_NN_LBFGS_DIM];
    for (int k = 0; k < q->count; k++)
      for (int i = 0; i < q->n; i++) sf[k * q->n + i] = q->s[k][i], yf[k * q->n + i] = q->y[k][i];
    json_t *qn = json_pack("{s:i,s:i,s:b,s:b,s:f}", "n", q->n, "count", q->count, "has_prev", q->has_prev, "stuck",
                           q->stuck, "f_prev", q->f_prev);
    json_object_set_new(qn, "s", darray(sf, q->count * q->n)); /* pair k at k * n, oldest first */
    json_object_set_new(qn, "y", darray(yf, q->count * q->n));
    json_object_set_new(qn, "x_prev", darray(q->x_prev, q->n));
    json_object_set_new(qn, "g_prev", darray(q->g_prev, q->n));
    json_object_set_new(root, "colours_qn", qn);
  }
  if (st->t_related) { /* a pair's back-lit photo as its own view of the cloth */
    json_t *v = json_pack("{s:b,s:f,s:f,s:b,s:b,s:[f,f],s:[f,f],s:f,s:f,s:f,s:f,s:f}", "found", st->t_found, "scale",
                          st->t_scale, "rotation_deg", st->t_rotation_deg, "registered", st->t_registered, "distorted",
                          st->t_distorted, "density_ratio", st->t_density_ratio[0], st->t_density_ratio[1], "offset_mm",
                          st->t_offset_mm[0], st->t_offset_mm[1], "extent_mm", st->t_distort_extent_mm,
                          "reg_ssim_before", st->t_reg_ssim_before, "reg_ssim_after", st->t_reg_ssim_after,
                          "dist_ssim_before", st->t_dist_ssim_before, "dist_ssim_after", st->t_dist_ssim_after);
    json_object_set_new(v, "x", darray(st->t_distort[0], WV_DISTORT_TERMS));
    json_object_set_new(v, "y", darray(st->t_distort[1], WV_DISTORT_TERMS));
    json_object_set_new(root, "view_t", v);
  }
  json_object_set_new(root, "camera_blur",
                      json_pack("{s:b,s:f,s:f,s:b,s:f,s:f}", "done", st->psf_done, "sigma_px", st->psf_sigma, "measured_px",
                                st->psf_start, "fitted", st->psf_fit, "adam_m", (double)st->psf_m, "adam_v",
                                (double)st->psf_v));
  json_t *log = json_array();
  for (int i = 0; i < st->iter; i++) {
    const wv_fit_record *r = &st->log[i];
    json_array_append_new(log, json_pack("[i,f,f,f,f,i,i,f,f,f,i]", r->iter, r->loss, r->gram, r->prior, r->pixel,
                                         r->discrete_tried, r->discrete_kept, r->structure, r->colour, r->loss_t,
                                         r->t_alone));
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

/* The back-lit photo's own view (wv_fit_state.t_*), every value checked. */
static wv_status read_view_t(json_t *v, wv_fit_state *st, wv_error *err) {
  const char *flags[3] = {"found", "registered", "distorted"};
  int *fv[3] = {&st->t_found, &st->t_registered, &st->t_distorted};
  for (int i = 0; i < 3; i++) {
    json_t *b = json_object_get(v, flags[i]);
    if (!json_is_boolean(b)) return wv_fail(err, WV_ERR_INVALID, "'view_t.%s' must be true or false", flags[i]);
    *fv[i] = json_is_true(b);
  }
  st->t_related = 1;
  wv_status rc;
  if ((rc = wv_json_number(v, "view_t", "scale", WV_RELATE_SCALE_MIN, WV_RELATE_SCALE_MAX, 1, &st->t_scale, err)) ||
      (rc = wv_json_number(v, "view_t", "rotation_deg", -WV_RELATE_MAX_ROT, WV_RELATE_MAX_ROT, 1, &st->t_rotation_deg,
                           err)) ||
      (rc = wv_json_number(v, "view_t", "extent_mm", 0, WV_SCENE_MAX_MM, 1, &st->t_distort_extent_mm, err)) ||
      (rc = wv_json_number(v, "view_t", "reg_ssim_before", -2, 2, 1, &st->t_reg_ssim_before, err)) ||
      (rc = wv_json_number(v, "view_t", "reg_ssim_after", -2, 2, 1, &st->t_reg_ssim_after, err)) ||
      (rc = wv_json_number(v, "view_t", "dist_ssim_before", -2, 2, 1, &st->t_dist_ssim_before, err)) ||
      (rc = wv_json_number(v, "view_t", "dist_ssim_after", -2, 2, 1, &st->t_dist_ssim_after, err)) ||
      (rc = read_darray(v, "density_ratio", st->t_density_ratio, 2, WV_DENSITY_MIN / WV_DENSITY_MAX,
                        WV_DENSITY_MAX / WV_DENSITY_MIN, err)) ||
      (rc = read_darray(v, "offset_mm", st->t_offset_mm, 2, -WV_SCENE_MAX_OFFSET_MM, WV_SCENE_MAX_OFFSET_MM, err)) ||
      (rc = read_darray(v, "x", st->t_distort[0], WV_DISTORT_TERMS, -WV_SCENE_MAX_OFFSET_MM, WV_SCENE_MAX_OFFSET_MM,
                        err)) ||
      (rc = read_darray(v, "y", st->t_distort[1], WV_DISTORT_TERMS, -WV_SCENE_MAX_OFFSET_MM, WV_SCENE_MAX_OFFSET_MM,
                        err)))
    return rc;
  return WV_OK;
}

/* A pair's colours' quasi-Newton memory (wv_fit_state.t_qn), every value checked. */
static wv_status read_colours_qn(json_t *v, wv_fit_state *st, wv_error *err) {
  wv_nn_lbfgs *q = &st->t_qn;
  int n = 0, count = 0;
  double sf[WV_NN_LBFGS_MEM * WV_NN_LBFGS_DIM], yf[WV_NN_LBFGS_MEM * WV_NN_LBFGS_DIM];
  wv_status rc;
  /* 0 before the colours' first step, else one coordinate per transmission colour that moves: all
   * of them, or all but k_f (no forward band) */
  const int all = WV_P_COUNT - WV_P_REFLECT_COUNT, no_band = WV_P_KF_WARP_R - WV_P_REFLECT_COUNT;
  if ((rc = wv_json_int(v, "colours_qn", "n", 0, all, 1, &n, err)) ||
      (rc = wv_json_int(v, "colours_qn", "count", 0, WV_NN_LBFGS_MEM, 1, &count, err)))
    return rc;
  if (n != 0 && n != no_band && n != all)
    return wv_fail(err, WV_ERR_INVALID, "'colours_qn.n' must be 0, %d or %d", no_band, all);
  wv_nn_lbfgs_reset(q, n);
  json_t *hp = json_object_get(v, "has_prev");
  if (!json_is_boolean(hp)) return wv_fail(err, WV_ERR_INVALID, "'colours_qn.has_prev' must be true or false");
  q->has_prev = json_is_true(hp);
  json_t *sk = json_object_get(v, "stuck");
  if (!json_is_boolean(sk)) return wv_fail(err, WV_ERR_INVALID, "'colours_qn.stuck' must be true or false");
  q->stuck = json_is_true(sk);
  if ((rc = wv_json_number(v, "colours_qn", "f_prev", WV_JSON_FINITE, 1, &q->f_prev, err)) ||
      (rc = wv_json_numbers(v, "colours_qn", "s", count * n, WV_JSON_FINITE, 1, sf, err)) ||
      (rc = wv_json_numbers(v, "colours_qn", "y", count * n, WV_JSON_FINITE, 1, yf, err)) ||
      (rc = wv_json_numbers(v, "colours_qn", "x_prev", n, WV_JSON_FINITE, 1, q->x_prev, err)) ||
      (rc = wv_json_numbers(v, "colours_qn", "g_prev", n, WV_JSON_FINITE, 1, q->g_prev, err)))
    return rc;
  q->count = count;
  for (int k = 0; k < count; k++)
    for (int i = 0; i < n; i++) q->s[k][i] = sf[k * n + i], q->y[k][i] = yf[k * n + i];
  return WV_OK;
}

/* Every value of a checkpoint is checked: it sizes arrays, seeds the search and
 * moves the weave; messages name the key (the caller adds the file). */
static wv_status read_checkpoint(json_t *root, const char *path, wv_fit_state *st, wv_fit_opts *o,
                                 char *descriptor_name, size_t name_cap, wv_error *err) {
  wv_status rc;
  json_t *kind = json_object_get(root, "kind");
  json_t *ver = json_object_get(root, "version");
  if (!json_is_string(kind) || strcmp(json_string_value(kind), "woven-fit-checkpoint") || !json_is_integer(ver) ||
      json_integer_value(ver) < 1 || json_integer_value(ver) > 4)
    return wv_fail(err, WV_ERR_FORMAT, "not a woven fit checkpoint (version 1 to 4)");
  /* moments of the reflection model's parameters only (version 1), and k_t's (version 2), and
   * k_st's (version 3): the others start at 0 */
  json_int_t v = json_integer_value(ver);
  int nm = v == 1 ? WV_P_REFLECT_COUNT : v == 2 ? WV_P_KST_WARP_R : v == 3 ? WV_P_KF_WARP_R : WV_P_COUNT;
  wv_fit_opts_default(o);
  o->register_radius = 0; /* absent in checkpoints older than the registration */
  o->w_struct = 0, o->colour_split = 0; /* absent before the structure term: a resume stays without it */
  o->w_colour = 0;                       /* absent before the detail-colour term: likewise */
  o->psf_sigma = 0;                      /* absent before the camera blur: none */
  o->psf_fit = 0;                        /* absent before the blur was fitted: as measured */
  o->distort_degree = 0;                 /* absent before the distortion: none */
  o->schedule = o->patience = 0;         /* absent before the schedule: every iteration alike, all of them */
  o->noise_sweep = 0;                    /* absent before the sweep: the discrete steps alone */
  o->width_sweep = 0;                    /* absent before the width sweep: the width as it started */
  o->forward_sweep = 0;                  /* absent before the forward band: its width as it started */
  if ((rc = wv_fit_opts_read_json(json_object_get(root, "opts"), o, err))) return rc;
  wv_params start;
  if ((rc = read_params_obj(root, path, "start", &start, err))) return rc;
  if ((rc = wv_fit_state_init(st, &start, o, err))) return rc;
  if ((rc = read_params_obj(root, path, "params", &st->params, err))) return rc;
  double am[WV_P_COUNT] = {0}, av[WV_P_COUNT] = {0};
  if ((rc = read_darray(root, "adam_m", am, nm, -1e30, 1e30, err))) return rc;
  if ((rc = read_darray(root, "adam_v", av, nm, 0, 1e30, err))) return rc;
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
  json_t *pr = json_object_get(root, "pair"); /* absent before it existed: one photo */
  if (pr && !json_is_boolean(pr)) return wv_fail(err, WV_ERR_INVALID, "'pair' must be true or false");
  st->pair = json_is_true(pr);
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
  /* a pair's open area measured on its gap glow (absent: not measured, the width is searched) */
  st->open_measured = json_object_get(root, "open_area_photo") != NULL;
  if (st->open_measured && (rc = wv_json_number(root, NULL, "open_area_photo", -1, 1, 1, &st->open_photo, err)))
    return rc;
  json_t *vt = json_object_get(root, "view_t"); /* a pair's back-lit view; absent: not measured yet */
  if (vt && (rc = read_view_t(vt, st, err))) return rc;
  json_t *qn = json_object_get(root, "colours_qn"); /* absent before it existed: no curvature seen */
  /* before version 4 there was no forward band: the memory moves the other colours */
  if (qn && (rc = read_colours_qn(qn, st, err))) return rc;
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
    if (!json_is_array(e) || json_array_size(e) < 7 || json_array_size(e) > 11)
      return wv_fail(err, WV_ERR_INVALID, "'log[%d]' must be an array of 7 to 11 values", i);
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
    r->structure = r->colour = r->loss_t = 0; /* absent in older checkpoints */
    r->t_alone = 0;
    double *extra[3] = {&r->structure, &r->colour, &r->loss_t};
    for (int k = 7; k < (int)json_array_size(e) && k < 10; k++) {
      snprintf(name, sizeof name, "log[%d][%d]", i, k);
      if ((rc = wv_json_number_value(json_array_get(e, (size_t)k), name, -1e30, 1e30, extra[k - 7], err))) return rc;
    }
    if (json_array_size(e) > 10) { /* the 11th: the transmission photo alone (absent before) */
      snprintf(name, sizeof name, "log[%d][10]", i);
      if ((rc = wv_json_integer_value(json_array_get(e, 10), name, 0, 1, &x, err))) return rc;
      r->t_alone = (int)x;
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
  st->align_wsc_before = st->align_wsc_after = -2; /* not measured */
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
