/* The fit: it lowers the loss and moves toward the target, it is deterministic,
 * and a resumed fit equals an uninterrupted one. Small scenes keep it fast. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "testutil.h"
#include "woven/descriptor.h"
#include "woven/capture.h"
#include "woven/fit.h"
#include "woven/imgops.h"
#include "woven/io.h"
#include "woven/metrics.h"
#include "woven/photo.h"
#include "woven/render.h"

/* the centre 96 x 96 of flat45 */
static void small_scene(wv_scene *s) { tu_centre_window(s, "flat45", 96, 96, 16); }

static void target(wv_params *p) {
  wv_params_default("twill", p, NULL);
  p->density[WV_WARP] = 140, p->density[WV_WEFT] = 90;
  p->diffuse[WV_WARP][0] = 0.7, p->diffuse[WV_WARP][1] = 0.3, p->diffuse[WV_WARP][2] = 0.1;
  p->diffuse[WV_WEFT][0] = 0.6, p->diffuse[WV_WEFT][1] = 0.35, p->diffuse[WV_WEFT][2] = 0.15;
  p->noise_level = 1;
}

static void opts(wv_fit_opts *o, int iters) {
  wv_fit_opts_default(o);
  o->iters = iters;
  o->iter_scale = 1;
  o->iter_spp = 4;
  o->lr = 0.03;
}

/* The small scene, the target's parameters, its render as the photo, a descriptor. */
static void setup(wv_scene *s, wv_params *tp, wv_image *photo, wv_descriptor **d) {
  small_scene(s);
  target(tp);
  wv_render_opts ro = {0};
  assert_int_equal(wv_render(s, tp, &ro, photo, NULL, NULL), WV_OK);
  assert_int_equal(wv_descriptor_create_default(d, NULL), WV_OK);
}

static void test_fit_improves(void **state) {
  (void)state;
  wv_scene s;
  wv_params tp, start;
  wv_image photo;
  wv_descriptor *d;
  setup(&s, &tp, &photo, &d);
  wv_params_default("twill", &start, NULL);
  start.density[WV_WARP] = 140, start.density[WV_WEFT] = 90;
  wv_fit_opts o;
  opts(&o, 30);
  o.discrete_every = 0; /* colours only: the test watches k_d */
  wv_fit_state st;
  wv_error err = {0};
  assert_int_equal(wv_fit_state_init(&st, &start, &o, &err), WV_OK);
  if (wv_fit_run(&st, &s, &photo, d, &o, NULL, NULL, &err)) fail_msg("%s", err.msg);
  assert_int_equal(st.iter, 30);
  double first = st.log[0].loss, last = st.log[29].loss;
  double e0 = 0, e1 = 0;
  for (int y = 0; y < 2; y++)
    for (int c = 0; c < 3; c++) {
      e0 += fabs(start.diffuse[y][c] - tp.diffuse[y][c]);
      e1 += fabs(st.params.diffuse[y][c] - tp.diffuse[y][c]);
    }
  print_message("loss %.5f -> %.5f, k_d error %.3f -> %.3f\n", first, last, e0, e1);
  assert_true(last < 0.6 * first);
  assert_true(e1 < 0.6 * e0);
  for (int i = 0; i < WV_P_COUNT; i++) { /* every parameter stays in its range */
    double lo, hi, v = wv_param_get(&st.params, i);
    wv_param_range(i, &lo, &hi);
    assert_true(v >= lo && v <= hi);
  }
  wv_fit_state_free(&st);
  wv_descriptor_free(d);
  wv_image_free(&photo);
}

/* A callback that stops the fit after *user iterations (as a kill would). */
static int stop_at(void *user, const wv_fit_state *st, const wv_fit_opts *o) {
  (void)o;
  return st->iter >= *(const int *)user;
}

/* 6 + 6 iterations through a checkpoint file equal 12 straight, bit for bit,
 * including the discrete search. */
/* A fit stopped by its caller: its checkpoint written to path (in the temporary
 * folder tmp), the state freed, then read back into st and o2 (the descriptor's name
 * into name). */
static void checkpoint_round_trip(const char *tmp, char path[256], wv_fit_state *st, const wv_fit_opts *o,
                                  wv_fit_opts *o2, char *name, size_t cap) {
  wv_error err = {0};
  snprintf(path, 256, "%s/checkpoint.json", tu_tmpdir(tmp));
  assert_int_equal(wv_fit_checkpoint_write(path, st, o, "default", &err), WV_OK);
  wv_fit_state_free(st);
  if (wv_fit_checkpoint_read(path, st, o2, name, cap, &err)) fail_msg("%s", err.msg);
}

static void test_resume_equals_straight(void **state) {
  (void)state;
  wv_scene s;
  wv_params tp, start;
  wv_image photo;
  wv_descriptor *d;
  setup(&s, &tp, &photo, &d);
  wv_params_default("twill", &start, NULL);
  wv_fit_opts o;
  opts(&o, 12);
  o.discrete_every = 3;
  wv_error err = {0};
  wv_fit_state a, b;
  assert_int_equal(wv_fit_state_init(&a, &start, &o, &err), WV_OK);
  assert_int_equal(wv_fit_run(&a, &s, &photo, d, &o, NULL, NULL, &err), WV_OK);
  int tried = 0;
  for (int i = 0; i < 12; i++) tried += a.log[i].discrete_tried;
  assert_true(tried > 0);
  /* interrupted after 6, as if killed (the caller stops it: fewer iterations would be
   * another schedule) */
  int six = 6;
  assert_int_equal(wv_fit_state_init(&b, &start, &o, &err), WV_OK);
  assert_int_equal(wv_fit_run(&b, &s, &photo, d, &o, stop_at, &six, &err), WV_OK);
  assert_int_equal(b.iter, 6);
  wv_fit_opts o2;
  char name[32], path[256];
  checkpoint_round_trip("fit_resume", path, &b, &o, &o2, name, sizeof name);
  assert_string_equal(name, "default");
  assert_int_equal(b.iter, 6);
  assert_int_equal(o2.iters, 12);
  assert_int_equal(wv_fit_run(&b, &s, &photo, d, &o2, NULL, NULL, &err), WV_OK);
  assert_memory_equal(&a.params, &b.params, sizeof a.params);
  for (int i = 0; i < 12; i++) assert_true(a.log[i].loss == b.log[i].loss);
  wv_fit_state_free(&a), wv_fit_state_free(&b);
  /* older checkpoints still read: version 1 (Adam's moments of the reflection model's
   * parameters only) and 2 (and k_t's): the same moments, 0 for the parameters after them */
  wv_fit_state c, v1;
  assert_int_equal(wv_fit_checkpoint_read(path, &c, &o2, name, sizeof name, &err), WV_OK);
  char old_path[300];
  snprintf(old_path, sizeof old_path, "%s.old", path);
  for (int ver = 2; ver >= 1; ver--) {
    int nm = ver == 1 ? WV_P_REFLECT_COUNT : WV_P_KST_WARP_R;
    json_t *root = json_load_file(path, 0, NULL);
    assert_non_null(root);
    json_object_set_new(root, "version", json_integer(ver));
    for (int k = 0; k < 2; k++) {
      json_t *m = json_object_get(root, k ? "adam_v" : "adam_m");
      while ((int)json_array_size(m) > nm) json_array_remove(m, json_array_size(m) - 1);
    }
    assert_int_equal(json_dump_file(root, old_path, 0), 0);
    json_decref(root);
    assert_int_equal(wv_fit_checkpoint_read(old_path, &v1, &o2, name, sizeof name, &err), WV_OK);
    for (int i = 0; i < WV_P_COUNT; i++) {
      assert_true(v1.adam_m[i] == (i < nm ? c.adam_m[i] : 0.0f));
      assert_true(v1.adam_v[i] == (i < nm ? c.adam_v[i] : 0.0f));
    }
    wv_fit_state_free(&v1);
  }
  remove(old_path);
  assert_true(c.adam_v[0] != 0.0f);
  wv_fit_state_free(&c);
  /* a damaged checkpoint is refused with its name */
  FILE *f = fopen(path, "w");
  fputs("{\"kind\": \"woven-fit-checkpoint\", \"version\": 1}", f);
  fclose(f);
  assert_int_not_equal(wv_fit_checkpoint_read(path, &b, &o2, name, sizeof name, &err), WV_OK);
  assert_non_null(strstr(err.msg, path));
  wv_descriptor_free(d);
  wv_image_free(&photo);
}

/* The stopping rule on a log: a loss falling 3% an iteration has not converged; once flat,
 * it has after `patience` iterations; a small fall (0.5% over the patience) counts as flat,
 * a larger one (3%) does not. */
static void test_stopping_rule(void **state) {
  (void)state;
  wv_fit_record log[80];
  memset(log, 0, sizeof log);
  for (int i = 0; i < 80; i++) log[i].loss = i < 30 ? pow(0.97, i) : pow(0.97, 30);
  for (int to = 1; to <= 30; to++) assert_false(wv_fit_converged(log, 0, to, 10));
  int stop = 0;
  for (int to = 1; to <= 80 && !stop; to++)
    if (wv_fit_converged(log, 0, to, 10)) stop = to;
  print_message("a loss flat after 30 iterations: converged after %d\n", stop);
  assert_true(stop > 30 && stop <= 30 + 10 + WV_FIT_SMOOTH);
  assert_false(wv_fit_converged(log, 0, 80, 0)); /* patience 0: never */
  assert_false(wv_fit_converged(log, 40, 50, 10)); /* too few iterations in the stage */
  for (int i = 0; i < 80; i++) log[i].loss = 1 - 0.0005 * i; /* 0.5% in 10 iterations */
  assert_true(wv_fit_converged(log, 0, 60, 10));
  for (int i = 0; i < 80; i++) log[i].loss = pow(0.997, i); /* 3% in 10 iterations */
  assert_false(wv_fit_converged(log, 0, 60, 10));
  /* a pair: the reflection photo's loss still falls by 3% in 10 iterations under a flat,
   * ten times larger transmission loss (the sum falls by 0.3%): not converged; once the
   * reflection's is flat too, converged */
  for (int i = 0; i < 80; i++) log[i].loss_t = 10, log[i].loss = log[i].loss_t + pow(0.997, i);
  assert_false(wv_fit_converged(log, 0, 60, 10));
  for (int i = 0; i < 80; i++) log[i].loss = log[i].loss_t + pow(0.97, i < 30 ? i : 30);
  assert_true(wv_fit_converged(log, 0, 60, 10));
  /* ... and a transmission loss still falling keeps it going */
  for (int i = 0; i < 80; i++) log[i].loss_t = 10 * pow(0.997, i), log[i].loss = log[i].loss_t + pow(0.97, 30);
  assert_false(wv_fit_converged(log, 0, 60, 10));
  /* a pair's iterations on the transmission photo alone (t_alone), after 40 on the reflection
   * photo whose loss still fell: the rule reads them alone, from their first. Flat: converged
   * once there are enough of them; falling by 3% in 10 iterations: not */
  memset(log, 0, sizeof log);
  for (int i = 0; i < 80; i++) {
    log[i].loss = i < 40 ? pow(0.97, i) : 5;
    log[i].t_alone = i >= 40, log[i].loss_t = i < 40 ? 0 : log[i].loss;
  }
  assert_false(wv_fit_converged(log, 0, 40 + 10, 10));
  assert_true(wv_fit_converged(log, 0, 60, 10));
  for (int i = 40; i < 80; i++) log[i].loss = log[i].loss_t = 5 * pow(0.997, i - 40);
  assert_false(wv_fit_converged(log, 0, 60, 10));
  /* ... which still falling end when they reach their share of the iterations
   * (WV_FIT_T_SHARE of 100: 25), at iteration 65 of a pair's fit, not at the limit */
  wv_fit_opts o;
  opts(&o, 100);
  wv_params p;
  target(&p);
  wv_fit_state st;
  wv_error err = {0};
  assert_int_equal(wv_fit_state_init(&st, &p, &o, &err), WV_OK);
  st.pair = 1;
  memcpy(st.log, log, sizeof log);
  for (st.iter = 41; st.iter <= 80; st.iter++)
    assert_int_equal(wv_fit_finished(&st, &o), st.iter >= 40 + (int)(100 * WV_FIT_T_SHARE));
  wv_fit_state_free(&st);
}

/* A fit that starts at the target stops long before its 200 iterations (the rule ends
 * each stage), and not with patience 0; stopped by its caller and resumed through a
 * checkpoint it stops at the same iteration with the same parameters. */

static void test_fit_stops(void **state) {
  (void)state;
  wv_scene s;
  wv_params tp;
  wv_image photo;
  wv_descriptor *d;
  setup(&s, &tp, &photo, &d);
  wv_fit_opts o;
  opts(&o, 200);
  o.align_radius = o.register_radius = o.distort_degree = 0;
  o.colour_split = 0;
  o.psf_sigma = 0;
  assert_int_equal(o.patience, WV_FIT_PATIENCE); /* on by default */
  assert_true(WV_FIT_PATIENCE > 0);
  o.patience = 10;
  o.schedule = 1; /* both stages: the rule ends each */
  wv_error err = {0};
  wv_fit_state a, b;
  assert_int_equal(wv_fit_state_init(&a, &tp, &o, &err), WV_OK);
  if (wv_fit_run(&a, &s, &photo, d, &o, NULL, NULL, &err)) fail_msg("%s", err.msg);
  int from = -1;
  assert_int_equal(wv_fit_stage(&a, &o, &from), 2);
  assert_true(wv_fit_finished(&a, &o));
  print_message("from the target: stopped after %d iterations (last stage from %d)\n", a.iter, from);
  assert_true(a.iter < o.iters); /* the rule ended it, not the iteration limit */
  assert_true(from > 0 && from < a.iter); /* two stages */
  assert_true(wv_fit_converged(a.log, from, a.iter, o.patience));
  assert_false(wv_fit_converged(a.log, from, a.iter - 1, o.patience)); /* it stopped at once */
  /* stopped by the caller half-way, written, read and continued */
  int half = a.iter / 2;
  assert_int_equal(wv_fit_state_init(&b, &tp, &o, &err), WV_OK);
  assert_int_equal(wv_fit_run(&b, &s, &photo, d, &o, stop_at, &half, &err), WV_OK);
  assert_int_equal(b.iter, half);
  assert_false(wv_fit_finished(&b, &o));
  wv_fit_opts o2;
  char name[32], path[256];
  checkpoint_round_trip("fit_stops", path, &b, &o, &o2, name, sizeof name);
  assert_int_equal(o2.schedule, 1);
  assert_int_equal(o2.patience, o.patience);
  assert_int_equal(wv_fit_run(&b, &s, &photo, d, &o2, NULL, NULL, &err), WV_OK);
  assert_int_equal(b.iter, a.iter);
  assert_memory_equal(&a.params, &b.params, sizeof a.params);
  wv_fit_state_free(&b);
  /* without the rule every iteration runs */
  o.patience = 0;
  assert_int_equal(wv_fit_state_init(&b, &tp, &o, &err), WV_OK);
  o.iters = 3 * a.iter / 2; /* enough to pass where the rule stopped */
  assert_int_equal(wv_fit_run(&b, &s, &photo, d, &o, NULL, NULL, &err), WV_OK);
  assert_int_equal(b.iter, o.iters);
  wv_fit_state_free(&a), wv_fit_state_free(&b);
  wv_descriptor_free(d);
  wv_image_free(&photo);
}

static void test_photo_load(void **state) {
  (void)state;
  const char *dir = tu_tmpdir("photo");
  char path[256];
  wv_scene s;
  small_scene(&s); /* 96 x 96 */
  wv_image img, out;
  wv_error err = {0};
  /* a 200 x 100 grey-ramp photo: centre crop 100 x 100, area-averaged to 96 x 96 */
  wv_image_alloc(&img, 200, 100, 3, NULL);
  for (int y = 0; y < 100; y++)
    for (int x = 0; x < 200; x++)
      for (int c = 0; c < 3; c++) wv_image_px(&img, x, y)[c] = (float)x / 199.0f;
  snprintf(path, sizeof path, "%s/ramp.png", dir);
  assert_int_equal(wv_image_write_png(path, &img, 16, NULL), WV_OK);
  wv_photo_info info;
  assert_int_equal(wv_photo_load(path, &s, NULL, &out, &info, &err), WV_OK);
  assert_int_equal(out.w, 96);
  assert_int_equal(info.crop[0], 50);
  assert_int_equal(info.crop[2], 100);
  /* output pixel 0 covers input columns [50, 50 + 100/96): column 50 fully, 51 for 1/24 */
  double want = (50.0 + 51.0 / 24.0) / (1.0 + 1.0 / 24.0) / 199.0;
  assert_true(fabs(wv_image_px(&out, 0, 0)[0] - want) < 1e-4);
  wv_image_free(&out);
  /* an explicit crop outside the photo, and a photo much smaller than the scene */
  wv_crop bad = {150, 0, 100, 100};
  assert_int_equal(wv_photo_load(path, &s, &bad, &out, NULL, &err), WV_ERR_INVALID);
  assert_non_null(strstr(err.msg, "crop"));
  /* x + w beyond INT_MAX: refused (not wrapped and copied from far outside), with the
   * photo's real size */
  wv_crop huge = {2147483600, 0, 800, 100};
  assert_int_equal(wv_photo_load(path, &s, &huge, &out, NULL, &err), WV_ERR_INVALID);
  assert_non_null(strstr(err.msg, "outside the 200 x 100 photo"));
  s.width = s.height = 300;
  assert_int_equal(wv_photo_load(path, &s, NULL, &out, NULL, &err), WV_ERR_INVALID);
  assert_non_null(strstr(err.msg, "much smaller"));
  wv_image_free(&img);
}

/* Sizes the fit cannot work at are refused before it starts (the descriptor's
 * minimum, also at the iteration scale), and so are options out of range. */
/* The camera blur's fits: a 128 x 128 flat45 window at 16 spp, a twill of 110 yarns/inch. */
static void psf_setup(wv_scene *s, wv_params *p) {
  wv_error err = {0};
  assert_int_equal(wv_scene_preset("flat45", s, &err), WV_OK);
  s->width = s->height = 128, s->spp = 16, s->vfov_deg = 14;
  assert_int_equal(wv_params_default("twill31z", p, &err), WV_OK);
  p->density[0] = p->density[1] = 110;
}

/* The camera blur measured from a photo: none on a plain render, the scene's on a
 * blurred one (the estimate starts from the truth, so only the blur is in question). */
static void test_psf_estimate(void **state) {
  (void)state;
  wv_error err = {0};
  wv_scene s;
  wv_params p;
  psf_setup(&s, &p);
  double want[3] = {0, 0.6, 1.2};
  for (int i = 0; i < 3; i++) {
    wv_scene sb = s;
    sb.psf_sigma = want[i];
    wv_image photo;
    assert_int_equal(wv_render(&sb, &p, NULL, &photo, NULL, &err), WV_OK);
    double sigma, d;
    assert_int_equal(wv_psf_estimate(&s, &photo, &p, 0, &sigma, &d, &err), WV_OK);
    printf("camera blur %.1f px: measured %.2f (1 - WSC %.4f)\n", want[i], sigma, d);
    assert_true(fabs(sigma - want[i]) <= 0.15);
    wv_image_free(&photo);
  }
}

/* A measured blur that is off is fitted with the parameters: from 0.4 px toward the
 * photo's 1.0 px; with psf_fit off it stays where it was measured. */
static void test_psf_fitted(void **state) {
  (void)state;
  wv_error err = {0};
  wv_scene s;
  wv_params p;
  psf_setup(&s, &p);
  wv_scene sb = s;
  sb.psf_sigma = 1.0;
  wv_image photo;
  assert_int_equal(wv_render(&sb, &p, NULL, &photo, NULL, &err), WV_OK);
  wv_descriptor *d;
  assert_int_equal(wv_descriptor_create("default", NULL, &d, &err), WV_OK);
  double end[2];
  for (int fit = 0; fit < 2; fit++) {
    wv_fit_opts o;
    wv_fit_opts_default(&o);
    o.iters = 60, o.discrete_every = 0, o.align_radius = 0, o.register_radius = 0, o.distort_degree = 0;
    o.psf_fit = fit;
    wv_fit_state st;
    assert_int_equal(wv_fit_state_init(&st, &p, &o, &err), WV_OK);
    st.psf_done = 1, st.psf_sigma = st.psf_start = 0.4, st.psf_fit = fit; /* as if measured so */
    assert_int_equal(wv_fit_run(&st, &s, &photo, d, &o, NULL, NULL, &err), WV_OK);
    end[fit] = st.psf_sigma;
    printf("camera blur measured 0.4 px, photo's 1.0 px: %s %.3f px, loss %.5f -> %.5f\n",
           fit ? "fitted" : "kept", st.psf_sigma, st.log[0].loss, st.log[o.iters - 1].loss);
    if (fit) assert_true(st.log[o.iters - 1].loss < st.log[0].loss);
    wv_fit_state_free(&st);
  }
  assert_true(end[0] == 0.4);
  assert_true(fabs(end[1] - 1.0) < 0.15);
  /* who decides: a measured blur is fitted, a given one is not */
  for (int given = 0; given < 2; given++) {
    wv_fit_opts o;
    wv_fit_opts_default(&o);
    o.iters = 2, o.discrete_every = 0, o.align_radius = 0, o.register_radius = 0, o.distort_degree = 0;
    if (given) o.psf_sigma = 0.7;
    wv_fit_state st;
    assert_int_equal(wv_fit_state_init(&st, &p, &o, &err), WV_OK);
    assert_int_equal(wv_fit_run(&st, &s, &photo, d, &o, NULL, NULL, &err), WV_OK);
    assert_int_equal(st.psf_fit, !given);
    if (given) assert_true(st.psf_sigma == 0.7);
    wv_fit_state_free(&st);
  }
  wv_descriptor_free(d);
  wv_image_free(&photo);
}

/* A twill's (or any built-in's) parameters: heightfield, diffuse and specular colours, roughness of warp and
 * weft, then twist, inclination and diffuse blend. */
static void twill_params(wv_params *p, const double beta[2], const double kd[2][3], const double ks[2][3],
                         const double alpha[2], double psi, double umax, double w) {
  for (int y = 0; y < 2; y++) {
    p->heightfield[y] = beta[y], p->roughness[y] = alpha[y];
    for (int c = 0; c < 3; c++) p->diffuse[y][c] = kd[y][c], p->specular[y][c] = ks[y][c];
  }
  p->twist_deg = psi, p->inclination_deg = umax, p->diffuse_blend = w;
}

/* A built-in of densities d0, d1, noise level q and seed as truth, and a start with its
 * densities (set both up with twill_params). */
static void truth_and_start(const char *pattern, double d0, double d1, int q, int64_t seed, wv_params *truth,
                            wv_params *start) {
  assert_int_equal(wv_params_default(pattern, truth, NULL), WV_OK);
  truth->density[0] = d0, truth->density[1] = d1, truth->noise_level = q, truth->seed = seed;
  *start = *truth;
  start->noise_level = 2, start->seed = 1;
}

/* The colour split alone (one iteration that does not move) from start on the whole
 * flat45 photo of truth, with the registration's radius reg (0: none): the parameters it
 * keeps, and its choice. */
static int split_params(const wv_params *truth, const wv_params *start, int reg, wv_params *out) {
  wv_error err = {0};
  wv_scene s;
  assert_int_equal(wv_scene_preset("flat45", &s, &err), WV_OK);
  wv_descriptor *d;
  assert_int_equal(wv_descriptor_create("default", NULL, &d, &err), WV_OK);
  wv_image photo;
  assert_int_equal(wv_render(&s, truth, NULL, &photo, NULL, &err), WV_OK);
  wv_fit_opts o;
  wv_fit_opts_default(&o);
  o.iters = 1, o.lr = 1e-9, o.discrete_every = 0, o.align_radius = 0, o.register_radius = reg, o.distort_degree = 0;
  o.psf_sigma = 0.5;
  wv_fit_state st;
  assert_int_equal(wv_fit_state_init(&st, start, &o, &err), WV_OK);
  assert_int_equal(wv_fit_run(&st, &s, &photo, d, &o, NULL, NULL, &err), WV_OK);
  *out = st.params;
  int choice = st.colour_split;
  wv_fit_state_free(&st);
  wv_image_free(&photo);
  wv_descriptor_free(d);
  return choice;
}

/* split_params without the registration: the luminances of warp and weft it keeps. */
static int split_of(const wv_params *truth, const wv_params *start, double lum[2]) {
  wv_params p;
  int choice = split_params(truth, start, 0, &p);
  for (int y = 0; y < 2; y++)
    lum[y] = 0.2126 * p.diffuse[y][0] + 0.7152 * p.diffuse[y][1] + 0.0722 * p.diffuse[y][2];
  printf("split %d: warp luminance %.3f, weft %.3f\n", choice, lum[WV_WARP], lum[WV_WEFT]);
  return choice;
}

/* The colour split on a two-colour 2/1 twill whose floats run across: the weft,
 * near-white, covers two thirds. The start (a network estimate of such a photo) has the
 * colours the wrong way round, and the loss alone prefers the split that keeps them so
 * (the darker colour on the weft); the rule of coverage puts it on the warp. */
static void test_colour_split(void **state) {
  (void)state;
  wv_params truth, start;
  truth_and_start("twill21z_90", 115, 98, 5, 1016823926, &truth, &start);
  twill_params(&truth, (double[2]){1.647, 1.790}, (double[2][3]){{0.044, 0.087, 0.281}, {0.758, 0.748, 0.688}},
               (double[2][3]){{0.209, 0.295, 0.530}, {0.871, 0.865, 0.830}}, (double[2]){0.620, 0.886}, -30, 28.6, 0.35);
  twill_params(&start, (double[2]){1.574, 1.842}, (double[2][3]){{0.598, 0.603, 0.477}, {0.105, 0.140, 0.771}},
               (double[2][3]){{0.826, 0.496, 0.486}, {0.302, 0.590, 0.945}}, (double[2]){0.801, 0.774}, -4.1, 24.8,
               0.387);
  double lum[2];
  int choice = split_of(&truth, &start, lum);
  assert_true(choice == 1 || choice == 3);
  assert_true(lum[WV_WARP] < 0.5 * lum[WV_WEFT]);
}

/* The same weave with high, steep weft floats: their shading puts 0.64 of the photo's
 * pixels in the darker colour, although the dark warp covers a third. Read from the
 * weave alone, that share would put the dark colour on the weft; the renders of the two
 * ways round, which carry the shading, keep it on the warp, as the start has it. */
static void test_colour_split_sees_shading(void **state) {
  (void)state;
  wv_params truth, start;
  truth_and_start("twill21z_90", 81, 82, 0, 1634604451, &truth, &start);
  twill_params(&truth, (double[2]){1.266, 1.953}, (double[2][3]){{0.034, 0.095, 0.314}, {0.789, 0.779, 0.719}},
               (double[2][3]){{0.184, 0.308, 0.561}, {0.888, 0.883, 0.848}}, (double[2]){0.571, 0.824}, -30, 34.1,
               0.851);
  twill_params(&start, (double[2]){0.627, 1.380}, (double[2][3]){{0.021, 0.267, 0.726}, {0.905, 0.771, 0.861}},
               (double[2][3]){{0.081, 0.794, 0.849}, {0.939, 0.926, 0.975}}, (double[2]){0.455, 0.540}, -15.2, 40.0,
               0.984);
  double lum[2];
  split_of(&truth, &start, lum);
  assert_true(lum[WV_WARP] < 0.5 * lum[WV_WEFT]);
}

/* A satin with floats across whose warp is magenta and weft near-black: the weft covers
 * four fifths. The photo's two colours differ in hue more than in brightness, so a render's
 * two clusters can come out in the other order by luminance; they are matched to the
 * photo's by colour, and the darker colour stays on the weft, as the start has it. */
static void test_colour_split_matches_hues(void **state) {
  (void)state;
  wv_params truth, start;
  truth_and_start("satin5_90", 77, 127, 4, 936823642, &truth, &start);
  twill_params(&truth, (double[2]){0.808, 0.324}, (double[2][3]){{0.978, 0.052, 0.800}, {0.034, 0.034, 0.034}},
               (double[2][3]){{0.985, 0.135, 0.860}, {0.949, 0.949, 0.949}}, (double[2]){0.304, 0.650}, 0, 38.9,
               0.770);
  twill_params(&start, (double[2]){0.743, 0.965}, (double[2][3]){{0.566, 0.035, 0.644}, {0.287, 0.051, 0.288}},
               (double[2][3]){{0.786, 0.121, 0.615}, {0.718, 0.294, 0.517}}, (double[2]){0.555, 0.466}, -2.3, 35.6,
               0.447);
  double lum[2];
  split_of(&truth, &start, lum);
  assert_true(lum[WV_WEFT] < 0.5 * lum[WV_WARP]);
}

/* A two-colour plain weave of unequal densities, a teal warp and a grey weft: each yarn
 * type covers half, so the weave does not tell which wears which colour, and the loss
 * prefers the way round of the start (a network estimate of such a photo), which is wrong.
 * Registered on the photo, the right way round scores higher and is kept; without the
 * registration, the loss's choice stays. */
static void test_colour_split_registered(void **state) {
  (void)state;
  wv_params truth, start;
  truth_and_start("plain", 124, 95, 0, 900056871, &truth, &start);
  twill_params(&truth, (double[2]){0.827, 1.010}, (double[2][3]){{0.016, 0.826, 0.494}, {0.520, 0.520, 0.520}},
               (double[2][3]){{0.841, 0.992, 0.971}, {0.534, 0.534, 0.534}}, (double[2]){0.094, 0.229}, 0, 16.7,
               0.643);
  truth.yarn_width = 0.885;
  twill_params(&start, (double[2]){0.632, 0.712}, (double[2][3]){{0.679, 0.582, 0.665}, {0.028, 0.505, 0.386}},
               (double[2][3]){{0.954, 0.871, 0.853}, {0.029, 0.844, 0.649}}, (double[2]){0.045, 0.226}, -1.2, 18.6,
               0.958);
  for (int reg = 0; reg <= 6; reg += 6) {
    wv_params p;
    int choice = split_params(&truth, &start, reg, &p);
    printf("register radius %d: split %d, warp red %.3f, weft red %.3f\n", reg, choice, p.diffuse[WV_WARP][0],
           p.diffuse[WV_WEFT][0]);
    assert_true(choice >= 1 && choice <= 4);
    if (reg) assert_true(p.diffuse[WV_WARP][0] < 0.5 * p.diffuse[WV_WEFT][0]); /* the teal on the warp */
    else assert_true(p.diffuse[WV_WEFT][0] < 0.5 * p.diffuse[WV_WARP][0]);
  }
}

static void test_limits(void **state) {
  (void)state;
  wv_descriptor *d;
  wv_error err = {0};
  assert_int_equal(wv_descriptor_create("default", NULL, &d, &err), WV_OK);
  wv_fit_opts o;
  wv_fit_opts_default(&o);
  wv_scene s;
  tu_centre_window(&s, "flat45", 64, 48, 4);
  assert_int_equal(wv_fit_check_sizes(&s, d, &o, &err), WV_OK);
  s.height = 32; /* above WV_FIT_MIN_SIDE, below the descriptor's minimum */
  assert_int_equal(wv_fit_check_sizes(&s, d, &o, &err), WV_ERR_INVALID);
  assert_non_null(strstr(err.msg, "64 x 32"));
  tu_centre_window(&s, "flat45", 160, 96, 4);
  o.iter_scale = 2; /* 80 x 48: fine; 3: 53 x 32, too small */
  assert_int_equal(wv_fit_check_sizes(&s, d, &o, &err), WV_OK);
  o.iter_scale = 3;
  assert_int_equal(wv_fit_check_sizes(&s, d, &o, &err), WV_ERR_INVALID);
  assert_non_null(strstr(err.msg, "iter-scale"));
  wv_fit_opts_default(&o);
  o.down_w = 0;
  assert_int_equal(wv_fit_opts_validate(&o, &err), WV_ERR_INVALID);
  assert_non_null(strstr(err.msg, "'down_w' = 0"));
  wv_fit_opts_default(&o);
  o.register_radius = 100000; /* (2R+1)^2 would overflow */
  assert_int_equal(wv_fit_opts_validate(&o, &err), WV_ERR_INVALID);
  wv_descriptor_free(d);
}

/* The noise level comes back by the sweep at the iterations' end: from a start at level 0,
 * a target of level 6 (its segments' heights spread +-60%) is found within one level, and
 * without the sweep (nor discrete steps) the level stays where it started. */
static void test_noise_sweep(void **state) {
  (void)state;
  wv_scene s;
  small_scene(&s);
  wv_params tp;
  target(&tp);
  tp.noise_level = 6;
  tp.heightfield[WV_WARP] = tp.heightfield[WV_WEFT] = 1.5;
  wv_image photo;
  wv_render_opts ro = {0};
  assert_int_equal(wv_render(&s, &tp, &ro, &photo, NULL, NULL), WV_OK);
  wv_descriptor *d;
  assert_int_equal(wv_descriptor_create_default(&d, NULL), WV_OK);
  wv_params start = tp;
  start.noise_level = 0;
  for (int sweep = 1; sweep >= 0; sweep--) {
    wv_fit_opts o;
    opts(&o, 2);
    o.discrete_every = 0, o.colour_split = 0, o.psf_sigma = 0, o.patience = 0;
    o.align_radius = o.register_radius = o.distort_degree = 0;
    o.noise_sweep = sweep;
    wv_fit_state st;
    wv_error err = {0};
    assert_int_equal(wv_fit_state_init(&st, &start, &o, &err), WV_OK);
    if (wv_fit_run(&st, &s, &photo, d, &o, NULL, NULL, &err)) fail_msg("%s", err.msg);
    print_message("sweep %d: noise level %d (target 6)\n", sweep, st.params.noise_level);
    if (sweep) assert_true(abs(st.params.noise_level - 6) <= 1);
    else assert_int_equal(st.params.noise_level, 0);
    wv_fit_state_free(&st);
  }
  wv_descriptor_free(d);
  wv_image_free(&photo);
}


/* The density alignment's window SSIM prefers a weave too fine to show over one out of
 * phase with the photo (the registration comes after it); the weave's spectrum does not
 * depend on the phase, so densities that lower it are not kept. The photo: the start's
 * own twill, shifted half a yarn on the sample. */
static void test_align_keeps_spectrum(void **state) {
  (void)state;
  wv_error err = {0};
  wv_scene s0, s;
  assert_int_equal(wv_scene_preset("flat45", &s0, &err), WV_OK);
  s0.vfov_deg = 14;
  wv_scene_centre_window(&s0, 160, 160, &s);
  s.spp = 16;
  wv_params tp;
  assert_int_equal(wv_params_default("twill", &tp, &err), WV_OK);
  tp.density[WV_WARP] = 140, tp.density[WV_WEFT] = 90;
  wv_scene sp = s;
  sp.fabric_offset[0] = 0.5 * 25.4 / tp.density[WV_WARP], sp.fabric_offset[1] = 0.5 * 25.4 / tp.density[WV_WEFT];
  wv_image photo;
  assert_int_equal(wv_render(&sp, &tp, NULL, &photo, NULL, &err), WV_OK);
  wv_descriptor *d;
  assert_int_equal(wv_descriptor_create_default(&d, &err), WV_OK);
  wv_fit_opts o;
  wv_fit_opts_default(&o);
  o.iters = 0, o.align_radius = 70, o.register_radius = 0, o.distort_degree = 0, o.psf_sigma = 0;
  wv_fit_state st;
  assert_int_equal(wv_fit_state_init(&st, &tp, &o, &err), WV_OK);
  if (wv_fit_run(&st, &s, &photo, d, &o, NULL, NULL, &err)) fail_msg("%s", err.msg);
  print_message("alignment: densities %.0f %.0f, window SSIM %.3f -> %.3f, WSC %.3f -> %.3f\n", st.params.density[0],
                st.params.density[1], st.align_ssim_before, st.align_ssim_after, st.align_wsc_before,
                st.align_wsc_after);
  assert_true(st.aligned);
  assert_true(st.align_wsc_after > -2 && st.align_wsc_after < st.align_wsc_before); /* the search did move */
  assert_true(st.params.density[WV_WARP] == 140 && st.params.density[WV_WEFT] == 90);
  wv_fit_state_free(&st);
  wv_descriptor_free(d);
  wv_image_free(&photo);
}

/* The pair scenes of the pair tests: 64 x 64 centre windows of flat45 and flat45-back at 4 spp. */
static void pair_scenes(wv_scene *s, wv_scene *sb) {
  tu_centre_window(s, "flat45", 64, 64, 4);
  tu_centre_window(sb, "flat45-back", 64, 64, 4);
}

/* A pair's fit with its discrete and after-the-iterations steps off, every iteration run. */
static void pair_opts(wv_fit_opts *o, int iters) {
  opts(o, iters);
  o->discrete_every = 0, o->colour_split = 0, o->noise_sweep = 0, o->width_sweep = 0, o->patience = 0;
  o->align_radius = 0, o->register_radius = 0, o->distort_degree = 0, o->psf_sigma = 0;
}

/* tp rendered in both scenes, as a photo pair. */
static void pair_photos(const wv_scene *s, const wv_scene *sb, const wv_params *tp, wv_image *photo, wv_image *photo_t) {
  wv_render_opts ro = {0};
  assert_int_equal(wv_render(s, tp, &ro, photo, NULL, NULL), WV_OK);
  assert_int_equal(wv_render(sb, tp, &ro, photo_t, NULL, NULL), WV_OK);
}

/* A photo pair: the target rendered in flat45 and flat45-back. The pair's fit runs the
 * reflection photo's iterations first, (1 - WV_FIT_T_SHARE) of them with patience 0, and
 * their parameters are exactly those of a fit of the reflection photo alone with as many
 * iterations; then the transmission colours' iterations, on the back-lit photo alone, the
 * colours first matched to its brightness (wv_trans_basis_match). They move from the start
 * (the prior: k_t half of k_d, k_st = k_s) toward the target's (k_st a fifth of k_s), and
 * the back-lit loss falls; fitted to the front-lit photo alone the colours stay exactly at
 * the start. */
static void test_fit_pair(void **state) {
  (void)state;
  wv_scene s, sb;
  wv_params tp, start;
  wv_image photo, photo_t;
  wv_descriptor *d;
  pair_scenes(&s, &sb);
  target(&tp);
  for (int y = 0; y < 2; y++)
    for (int c = 0; c < 3; c++)
      tp.transmission[y][c] = 0.15 * tp.diffuse[y][c], tp.transmission_specular[y][c] = 0.2 * tp.specular[y][c];
  start = tp;
  wv_params_transmission_default(&start); /* the prior's k_t and k_st, the only difference */
  pair_photos(&s, &sb, &tp, &photo, &photo_t);
  assert_int_equal(wv_descriptor_create_default(&d, NULL), WV_OK);
  wv_fit_opts o;
  pair_opts(&o, 16);
  int r_iters = (int)(o.iters * (1 - WV_FIT_T_SHARE));
  wv_error err = {0};
  double e[3] = {0, 0, 0}, es[3] = {0, 0, 0}; /* k_t and k_st errors: start, pair fit, reflection-only fit */
  wv_params fitted[2];
  double loss_t_last = 0, loss_t_first = 0, straight[16];
  for (int run = 0; run < 2; run++) {
    wv_fit_state st;
    wv_fit_opts ro = o;
    if (run == 1) ro.iters = r_iters; /* the reflection photo alone, as many iterations as the pair gave it */
    assert_int_equal(wv_fit_state_init(&st, &start, &ro, &err), WV_OK);
    if (wv_fit_run_pair(&st, &s, &photo, run == 0 ? &sb : NULL, run == 0 ? &photo_t : NULL, d, &ro, NULL, NULL, &err))
      fail_msg("%s", err.msg);
    assert_int_equal(st.iter, ro.iters);
    for (int i = 0; i < st.iter; i++) { /* the log: the reflection photo's iterations, then the colours' */
      int t_alone = run == 0 && i >= r_iters;
      assert_int_equal(st.log[i].t_alone, t_alone);
      if (t_alone) assert_true(st.log[i].loss_t == st.log[i].loss && st.log[i].loss > 0);
      else assert_true(st.log[i].loss_t == 0);
      /* the colours' steps are kept only where they lower the back-lit loss */
      if (t_alone && i > r_iters) assert_true(st.log[i].loss_t <= st.log[i - 1].loss_t);
    }
    if (run == 0) {
      loss_t_last = st.log[st.iter - 1].loss_t;
      loss_t_first = st.log[r_iters].loss_t; /* at the colours' chosen start, before their first iteration */
      for (int i = 0; i < st.iter; i++) straight[i] = st.log[i].loss;
    }
    for (int y = 0; y < 2; y++)
      for (int c = 0; c < 3; c++) {
        if (run == 0) e[0] += fabs(start.transmission[y][c] - tp.transmission[y][c]);
        if (run == 0) es[0] += fabs(start.transmission_specular[y][c] - tp.transmission_specular[y][c]);
        e[1 + run] += fabs(st.params.transmission[y][c] - tp.transmission[y][c]);
        es[1 + run] += fabs(st.params.transmission_specular[y][c] - tp.transmission_specular[y][c]);
        if (run == 1)
          assert_true(st.params.transmission[y][c] == start.transmission[y][c] &&
                      st.params.transmission_specular[y][c] == start.transmission_specular[y][c]);
      }
    fitted[run] = st.params;
    wv_fit_state_free(&st);
  }
  /* the back-lit photo moves the transmission colours alone: every other parameter as the
   * reflection photo alone fits it, exactly */
  for (int i = 0; i < WV_P_REFLECT_COUNT; i++)
    assert_true(wv_param_get(&fitted[0], i) == wv_param_get(&fitted[1], i));
  assert_true(fitted[0].density[0] == fitted[1].density[0] && fitted[0].density[1] == fitted[1].density[1]);
  print_message("k_t error: start %.4f, pair %.4f, reflection only %.4f\n", e[0], e[1], e[2]);
  print_message("k_st error: start %.4f, pair %.4f, reflection only %.4f\n", es[0], es[1], es[2]);
  assert_true(e[1] < 0.8 * e[0] && es[1] < 0.8 * es[0]);
  assert_true(e[2] == e[0] && es[2] == es[0]);
  /* the back-lit loss: at the start's colours (the fitted geometry) against the fit's last */
  wv_params at_start = fitted[0];
  memcpy(at_start.transmission, start.transmission, sizeof at_start.transmission);
  memcpy(at_start.transmission_specular, start.transmission_specular, sizeof at_start.transmission_specular);
  wv_fit_record r0;
  assert_int_equal(wv_fit_loss(&sb, &photo_t, d, &at_start, &o, &r0, &err), WV_OK);
  print_message("back-lit loss: the start's colours %.5f, the colours' chosen start %.5f, the fit's last iteration %.5f\n",
                r0.loss - o.w_prior * r0.prior, loss_t_first, loss_t_last);
  /* the chosen start (of the start and four brightness matches, the two lowest each after
   * WV_FIT_T_PROBE steps of the colours' descent, the lower end) is far below the start's
   * colours, and the iterations' steps do not climb from it */
  assert_true(loss_t_first < 0.05 * (r0.loss - o.w_prior * r0.prior));
  assert_true(loss_t_last < 0.05 * (r0.loss - o.w_prior * r0.prior));
  assert_true(loss_t_last <= loss_t_first);
  /* stopped in the colours' iterations, written, read and continued: the same fit (the
   * checkpoint says it is a pair's, and its log which iterations were the colours') */
  for (int at = r_iters - 1; at <= r_iters + 1; at += 2) {
    wv_fit_state b;
    wv_fit_opts o2;
    char name[32], path[256];
    assert_int_equal(wv_fit_state_init(&b, &start, &o, &err), WV_OK);
    assert_int_equal(wv_fit_run_pair(&b, &s, &photo, &sb, &photo_t, d, &o, stop_at, &at, &err), WV_OK);
    assert_int_equal(b.iter, at);
    checkpoint_round_trip("fit_pair_resume", path, &b, &o, &o2, name, sizeof name);
    assert_int_equal(b.pair, 1);
    assert_int_equal(b.iter, at);
    if (at > r_iters) { /* the colours' quasi-Newton memory is in it, and checked when read */
      json_t *root = json_load_file(path, 0, NULL);
      json_t *qn = json_object_get(root, "colours_qn");
      assert_non_null(qn);
      /* every colour, or all but k_f when the sweep found no forward band */
      assert_int_equal(json_integer_value(json_object_get(qn, "n")), b.t_qn.n);
      assert_true(b.t_qn.n == WV_P_COUNT - WV_P_REFLECT_COUNT || b.t_qn.n == WV_P_KF_WARP_R - WV_P_REFLECT_COUNT);
      json_object_set_new(qn, "n", json_integer(5));
      char bad[300];
      snprintf(bad, sizeof bad, "%s.bad", path);
      assert_int_equal(json_dump_file(root, bad, 0), 0);
      json_decref(root);
      wv_fit_state x;
      wv_fit_opts ox;
      char nx[32];
      assert_int_not_equal(wv_fit_checkpoint_read(bad, &x, &ox, nx, sizeof nx, &err), WV_OK);
      assert_non_null(strstr(err.msg, "colours_qn.n"));
      remove(bad);
    }
    assert_int_equal(wv_fit_run_pair(&b, &s, &photo, &sb, &photo_t, d, &o2, NULL, NULL, &err), WV_OK);
    assert_int_equal(b.iter, o.iters);
    assert_memory_equal(&fitted[0], &b.params, sizeof b.params);
    for (int i = 0; i < o.iters; i++) assert_true(b.log[i].loss == straight[i]);
    wv_fit_state_free(&b);
    remove(path);
  }
  wv_image_free(&photo), wv_image_free(&photo_t);
  wv_descriptor_free(d);
}

/* A back-lit photo with a forward band (k_f of a width on the sweep's grid): the pair's fit,
 * from a start without one (k_f 0, the width 0.8), finds the width and brings k_f toward the
 * target's, and its back-lit loss ends below a fifth of that of the same fit without the
 * sweep, whose k_f stays 0 (its colours' iterations do not move it). */
static void test_forward_sweep(void **state) {
  (void)state;
  wv_scene s, sb;
  wv_params tp, start;
  wv_image photo, photo_t;
  wv_descriptor *d;
  pair_scenes(&s, &sb);
  target(&tp);
  const double kf[2][3] = {{0.5, 0.6, 0.3}, {0.2, 0.3, 0.45}};
  for (int y = 0; y < 2; y++)
    for (int c = 0; c < 3; c++)
      tp.transmission[y][c] = 0.3 * tp.diffuse[y][c], tp.transmission_specular[y][c] = 0.2 * tp.specular[y][c],
      tp.transmission_forward[y][c] = kf[y][c];
  tp.forward_width = 0.2;
  start = tp;
  wv_params_transmission_default(&start); /* k_f 0 */
  start.forward_width = 0.8;
  pair_photos(&s, &sb, &tp, &photo, &photo_t);
  assert_int_equal(wv_descriptor_create_default(&d, NULL), WV_OK);
  wv_fit_opts o;
  pair_opts(&o, 16);
  wv_error err = {0};
  double last[2], ef[2] = {0, 0}, e0 = 0;
  for (int run = 0; run < 2; run++) {
    wv_fit_opts ro = o;
    ro.forward_sweep = run == 0;
    wv_fit_state st;
    assert_int_equal(wv_fit_state_init(&st, &start, &ro, &err), WV_OK);
    if (wv_fit_run_pair(&st, &s, &photo, &sb, &photo_t, d, &ro, NULL, NULL, &err)) fail_msg("%s", err.msg);
    last[run] = st.log[st.iter - 1].loss_t;
    for (int y = 0; y < 2; y++)
      for (int c = 0; c < 3; c++) {
        ef[run] += fabs(st.params.transmission_forward[y][c] - kf[y][c]);
        if (run == 0) e0 += kf[y][c];
        if (run == 1) assert_true(st.params.transmission_forward[y][c] == 0.0);
      }
    if (run == 0) assert_true(st.params.forward_width == 0.2);
    if (run == 1) assert_true(st.params.forward_width == 0.8);
    wv_fit_state_free(&st);
  }
  print_message("k_f error: start %.4f, with the sweep %.4f; back-lit loss with the sweep %.5f, without %.5f\n", e0,
                ef[0], last[0], last[1]);
  assert_true(ef[0] < 0.5 * e0);
  assert_true(last[0] < 0.2 * last[1]);
  wv_image_free(&photo), wv_image_free(&photo_t);
  wv_descriptor_free(d);
}

/* A pair's colour split comes after its open area. The target: a 2/2 twill whose densities
 * differ (177 and 113 yarns/inch), a green warp and an orange weft, open gaps (yarn width
 * 0.784); the start: the target without gaps and with one colour, the two's mean. The split
 * (by the reflection photo's loss) then renders its candidates with the gaps the back-lit
 * photo's glow measures and gives the warp the green; before the open area was measured it
 * gave the warp the orange, and the fit kept it (a swap of colours is no shift of the weave
 * when the densities differ). */
static void test_split_after_open_area(void **state) {
  (void)state;
  wv_error err = {0};
  wv_scene s, sb;
  assert_int_equal(wv_scene_preset("flat45", &s, &err), WV_OK);
  assert_int_equal(wv_scene_preset("flat45-back", &sb, &err), WV_OK);
  wv_params tp;
  assert_int_equal(wv_params_default("twill22z", &tp, &err), WV_OK);
  const double kd[2][3] = {{0.493, 0.898, 0.152}, {0.913, 0.433, 0.089}};
  const double ks[2][3] = {{0.753, 0.958, 0.470}, {0.913, 0.435, 0.091}};
  const double kt[2][3] = {{0.320, 0.582, 0.098}, {0.787, 0.373, 0.077}};
  const double kst[2][3] = {{0.396, 0.504, 0.247}, {0.225, 0.107, 0.022}};
  for (int y = 0; y < 2; y++)
    for (int c = 0; c < 3; c++)
      tp.diffuse[y][c] = kd[y][c], tp.specular[y][c] = ks[y][c], tp.transmission[y][c] = kt[y][c],
      tp.transmission_specular[y][c] = kst[y][c];
  tp.density[WV_WARP] = 177, tp.density[WV_WEFT] = 113;
  tp.heightfield[WV_WARP] = 1.5, tp.heightfield[WV_WEFT] = 1.8;
  tp.roughness[WV_WARP] = 0.861, tp.roughness[WV_WEFT] = 0.743;
  tp.twist_deg = 30, tp.inclination_deg = 25.7, tp.diffuse_blend = 0.052, tp.noise_level = 3;
  tp.yarn_width = 0.784, tp.seed = 1177607123;
  wv_image photo, photo_t;
  pair_photos(&s, &sb, &tp, &photo, &photo_t);
  wv_image_quantise8(&photo), wv_image_quantise8(&photo_t);
  wv_params start = tp;
  start.yarn_width = 1, start.seed = 1;
  for (int c = 0; c < 3; c++) start.diffuse[0][c] = start.diffuse[1][c] = 0.5 * (kd[0][c] + kd[1][c]);
  wv_descriptor *d;
  assert_int_equal(wv_descriptor_create_default(&d, NULL), WV_OK);
  wv_fit_opts o;
  opts(&o, 1);
  o.lr = 0.01, o.discrete_every = 0, o.noise_sweep = 0, o.patience = 0;
  o.align_radius = 0, o.register_radius = 0, o.distort_degree = 0, o.psf_sigma = 0;
  wv_fit_state st;
  assert_int_equal(wv_fit_state_init(&st, &start, &o, &err), WV_OK);
  if (wv_fit_run_pair(&st, &s, &photo, &sb, &photo_t, d, &o, NULL, NULL, &err)) fail_msg("%s", err.msg);
  double right = 0, swapped = 0;
  for (int y = 0; y < 2; y++)
    for (int c = 0; c < 3; c++)
      right += fabs(st.params.diffuse[y][c] - kd[y][c]), swapped += fabs(st.params.diffuse[y][c] - kd[1 - y][c]);
  print_message("open area measured %d (width %.3f), split candidate %d: warp (%.2f %.2f %.2f) weft (%.2f %.2f %.2f); "
                "off the target's colours by %.3f, by the swapped ones %.3f\n",
                st.open_measured, st.params.yarn_width, st.colour_split, st.params.diffuse[0][0],
                st.params.diffuse[0][1], st.params.diffuse[0][2], st.params.diffuse[1][0], st.params.diffuse[1][1],
                st.params.diffuse[1][2], right, swapped);
  assert_true(st.open_measured && st.colour_split > 0);
  assert_true(right < swapped);
  wv_fit_state_free(&st);
  wv_image_free(&photo), wv_image_free(&photo_t);
  wv_descriptor_free(d);
}

/* A photo pair's open gaps: from a start without gaps (yarn width 1), the width sweep finds
 * the target's 0.75 (open area 6.25%) on the pair's loss; without it the width stays, and a
 * fit of the reflection photo alone does not search it. */
static void test_width_sweep(void **state) {
  (void)state;
  wv_scene s, sb;
  wv_params tp, start;
  wv_image photo, photo_t;
  wv_descriptor *d;
  pair_scenes(&s, &sb);
  target(&tp);
  tp.yarn_width = 0.75;
  start = tp;
  start.yarn_width = 1.0;
  pair_photos(&s, &sb, &tp, &photo, &photo_t);
  assert_int_equal(wv_descriptor_create_default(&d, NULL), WV_OK);
  wv_fit_opts o;
  opts(&o, 1);
  o.discrete_every = 0, o.colour_split = 0, o.noise_sweep = 0, o.patience = 0, o.lr = 1e-9;
  o.align_radius = 0, o.register_radius = 0, o.distort_degree = 0, o.psf_sigma = 0;
  wv_error err = {0};
  double width[3];
  for (int run = 0; run < 3; run++) { /* the pair with the sweep, the pair without, the reflection alone */
    o.width_sweep = run != 1;
    wv_fit_state st;
    assert_int_equal(wv_fit_state_init(&st, &start, &o, &err), WV_OK);
    if (wv_fit_run_pair(&st, &s, &photo, run < 2 ? &sb : NULL, run < 2 ? &photo_t : NULL, d, &o, NULL, NULL, &err))
      fail_msg("%s", err.msg);
    width[run] = st.params.yarn_width;
    wv_fit_state_free(&st);
  }
  print_message("yarn width: target 0.75, pair with the sweep %.4f, without %.4f, reflection alone %.4f\n", width[0],
                width[1], width[2]);
  assert_true(fabs(width[0] - 0.75) <= 0.0125 + 1e-9);
  assert_true(width[1] == 1.0 && width[2] == 1.0);
  wv_image_free(&photo), wv_image_free(&photo_t);
  wv_descriptor_free(d);
}

/* A pair model's transmission colours are kept as the start only when the pair's loss is
 * lower with them than with the prior's (k_d / 2). */
static void test_pair_start(void **state) {
  (void)state;
  wv_scene s, sb;
  pair_scenes(&s, &sb);
  wv_fit_opts o;
  opts(&o, 1);
  wv_descriptor *d;
  assert_int_equal(wv_descriptor_create_default(&d, NULL), WV_OK);
  for (int run = 0; run < 2; run++) {
    wv_params tp, prior;
    target(&tp);
    prior = tp;
    wv_params_transmission_default(&prior);
    if (run == 0) /* the truth away from the prior: a proposal at the truth is kept */
      for (int y = 0; y < 2; y++)
        for (int c = 0; c < 3; c++) tp.transmission[y][c] = 0.15 * tp.diffuse[y][c];
    else /* the truth at the prior: a proposal far off is not */
      tp = prior;
    wv_image photo, photo_t;
    pair_photos(&s, &sb, &tp, &photo, &photo_t);
    wv_estimate e;
    memset(&e, 0, sizeof e);
    e.scene = s, e.photo = photo, e.desc = d, e.params = tp;
    if (run == 1)
      for (int y = 0; y < 2; y++)
        for (int c = 0; c < 3; c++) e.params.transmission[y][c] = 0.95;
    int kt_model = 1;
    wv_error err = {0};
    if (wv_capture_pair_start(&e, &sb, &photo_t, &o, &kt_model, &err)) fail_msg("%s", err.msg);
    assert_int_equal(kt_model, run == 0 ? 1 : 2);
    for (int y = 0; y < 2; y++)
      for (int c = 0; c < 3; c++) assert_true(e.params.transmission[y][c] == tp.transmission[y][c]);
    wv_image_free(&photo), wv_image_free(&photo_t);
  }
  wv_descriptor_free(d);
}

/* A pair whose back-lit photo is another view: taken 10% closer, the cloth turned by a
 * degree and shifted by 0.3 mm. After the iterations the fit relates the two photos' weaves
 * and registers the back-lit photo on its own (wv_fit_scene_t): its re-render then matches
 * the back-lit photo, where the front-lit photo's view (one camera, one cloth) does not. */
static void test_pair_own_view(void **state) {
  (void)state;
  wv_scene s, sb, view;
  wv_params tp;
  wv_image photo, photo_t;
  wv_descriptor *d;
  tu_centre_window(&s, "flat45", 160, 160, 4);
  tu_centre_window(&sb, "flat45-back", 160, 160, 4);
  target(&tp);
  for (int y = 0; y < 2; y++)
    for (int c = 0; c < 3; c++) tp.transmission[y][c] = 0.4 * tp.diffuse[y][c];
  view = sb;
  for (int k = 0; k < 3; k++) view.cam_pos[k] *= 0.9;
  view.rotation_deg += 1, view.fabric_offset[0] += 0.3;
  pair_photos(&s, &view, &tp, &photo, &photo_t);
  assert_int_equal(wv_descriptor_create_default(&d, NULL), WV_OK);
  wv_fit_opts o;
  opts(&o, 1);
  o.discrete_every = 0, o.colour_split = 0, o.noise_sweep = 0, o.width_sweep = 0, o.patience = 0;
  o.align_radius = 0, o.distort_degree = 0, o.psf_sigma = 0;
  wv_error err = {0};
  wv_fit_state st;
  assert_int_equal(wv_fit_state_init(&st, &tp, &o, &err), WV_OK);
  if (wv_fit_run_pair(&st, &s, &photo, &sb, &photo_t, d, &o, NULL, NULL, &err)) fail_msg("%s", err.msg);
  print_message("back-lit view: related %d, scale %.4f, rotation %.3f, density ratio %.4f / %.4f, offset %.3f / %.3f mm\n",
                st.t_found, st.t_scale, st.t_rotation_deg, st.t_density_ratio[0], st.t_density_ratio[1],
                st.t_offset_mm[0], st.t_offset_mm[1]);
  assert_true(st.t_related && st.t_found && st.t_registered);
  assert_true(fabs(st.t_scale - 0.9) < 0.01 && fabs(st.t_rotation_deg - 1) < 0.3);
  wv_scene own, one;
  wv_params pt;
  wv_fit_scene_t(&st, &sb, &own);
  wv_fit_params_t(&st, &st.params, &pt);
  wv_fit_scene(&st, &sb, &one);
  wv_render_opts ro = {0};
  wv_image r_own, r_one;
  assert_int_equal(wv_render(&own, &pt, &ro, &r_own, NULL, &err), WV_OK);
  assert_int_equal(wv_render(&one, &st.params, &ro, &r_one, NULL, &err), WV_OK);
  double ssim_own, ssim_one;
  assert_int_equal(wv_ssim(&photo_t, &r_own, WV_SSIM_RGB, &ssim_own, &err), WV_OK);
  assert_int_equal(wv_ssim(&photo_t, &r_one, WV_SSIM_RGB, &ssim_one, &err), WV_OK);
  print_message("back-lit SSIM: its own view %.4f, the front-lit photo's view %.4f\n", ssim_own, ssim_one);
  /* (two 4-spp renders with glints: the same view of the same cloth scores about 0.7 here) */
  assert_true(ssim_own > 0.6 && ssim_own > ssim_one + 0.25);
  wv_fit_state_free(&st);
  wv_descriptor_free(d);
  wv_image_free(&photo), wv_image_free(&photo_t), wv_image_free(&r_own), wv_image_free(&r_one);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_fit_improves), cmocka_unit_test(test_resume_equals_straight),
                                     cmocka_unit_test(test_stopping_rule), cmocka_unit_test(test_fit_stops),
                                     cmocka_unit_test(test_photo_load), cmocka_unit_test(test_psf_estimate),
                                     cmocka_unit_test(test_psf_fitted), cmocka_unit_test(test_colour_split),
                                     cmocka_unit_test(test_colour_split_sees_shading),
                                     cmocka_unit_test(test_colour_split_matches_hues),
                                     cmocka_unit_test(test_colour_split_registered),
                                     cmocka_unit_test(test_limits), cmocka_unit_test(test_noise_sweep),
                                     cmocka_unit_test(test_align_keeps_spectrum),
                                     cmocka_unit_test(test_fit_pair), cmocka_unit_test(test_forward_sweep),
      cmocka_unit_test(test_pair_own_view), cmocka_unit_test(test_split_after_open_area),
                                     cmocka_unit_test(test_width_sweep),
                                     cmocka_unit_test(test_pair_start)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
