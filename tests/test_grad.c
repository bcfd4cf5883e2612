/* The differentiable renderer: analytic gradients against central finite
 * differences (double-precision kernel), the float path against the double one,
 * the capture against wv_render, exact zeros, range edges, determinism; with the
 * light in front (cylinder, flat45) and behind the cloth (flat45-back). */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sensor/sensor.h"
#include "testutil.h"
#include "woven/grad.h"
#include "woven/imgops.h"
#include "woven/render.h"


static void fill_random(wv_image *im, tu_rng *r) {
  for (size_t i = 0; i < (size_t)im->w * im->h * im->c; i++) im->data[i] = (float)(2.0 * tu_rnd(r) - 1.0);
}

/* A random point of the parameter space: every continuous parameter uniform
 * inside its range (2% away from the edges, so central differences fit). */
static void random_params(const char *pattern, tu_rng *r, wv_params *p) {
  wv_error err;
  assert_int_equal(wv_params_default(pattern, p, &err), WV_OK);
  for (int i = 0; i < WV_P_KST_WARP_R; i++) {
    double lo, hi;
    wv_param_range(i, &lo, &hi);
    wv_param_set(p, i, lo + (hi - lo) * (0.02 + 0.96 * tu_rnd(r)));
  }
  /* k_st and k_f from k_t, drawing nothing more: the checks' random points stay where they were */
  for (int y = 0; y < 2; y++)
    for (int c = 0; c < 3; c++)
      p->transmission_specular[y][c] = 1.0 - p->transmission[y][c],
      p->transmission_forward[y][c] = 0.02 + 0.1 * p->transmission[y][c]; /* little more light: no clipping */
  p->forward_width = 0.3;
  p->density[0] = 60 + 100 * tu_rnd(r);
  p->density[1] = 60 + 100 * tu_rnd(r);
  p->seed = (int64_t)(tu_rnd(r) * 1000);
}

static wv_scene preset(const char *name) {
  wv_scene s;
  wv_error err;
  assert_int_equal(wv_scene_preset(name, &s, &err), WV_OK);
  return s;
}

/* Largest relative error seen per parameter over the finite-difference checks. */
typedef struct {
  double worst[WV_P_COUNT];
  int checks;
} fd_stats;

static void fd_check(const wv_scene *s, const wv_params *p, int x0, int y0, int w, int h, int spp, tu_rng *r,
                     fd_stats *stats) {
  wv_grad_opts g = {.x0 = x0, .y0 = y0, .width = w, .height = h, .double_precision = 1};
  wv_render_opts o = {0};
  o.spp = spp;
  wv_image dc;
  wv_error err = {0};
  assert_int_equal(wv_image_alloc(&dc, w, h, 3, &err), WV_OK);
  fill_random(&dc, r);
  wv_grad_check_entry e[WV_P_COUNT];
  assert_int_equal(wv_grad_check(s, p, &o, &g, &dc, 1e-5, e, &err), WV_OK);
  for (int i = 0; i < WV_P_COUNT; i++) {
    if (e[i].rel_err >= 1e-3)
      print_error("%s %s at %g: analytic %.9e, finite difference %.9e, relative error %.2e\n", s->name,
                  wv_param_name(i), wv_param_get(p, i), e[i].analytic, e[i].numeric, e[i].rel_err);
    assert_true(e[i].rel_err < 1e-3);
    /* A random adjoint sees every parameter of the model the scene shows, and nothing of
     * the other: transmission colours in front light, reflection albedos in back light. */
    int kt = i >= WV_P_KT_WARP_R, kd = i >= WV_P_KD_WARP_R && i <= WV_P_KS_WEFT_B;
    if (wv_scene_transmits(s) ? kd : kt)
      assert_true(e[i].analytic == 0.0 && e[i].numeric == 0.0);
    else
      assert_true(e[i].analytic != 0.0);
    if (e[i].rel_err > stats->worst[i]) stats->worst[i] = e[i].rel_err;
  }
  stats->checks++;
  wv_image_free(&dc);
}

/* Every parameter, several random points, both presets, with and without the
 * (fixed, hashed) noise; windows at the image centre and, on the cylinder, on
 * its silhouette where every sample is traced. */
static void test_finite_differences(void **state) {
  (void)state;
  static const char *patterns[] = {"twill", "satin", "plain", "satin90"};
  static const char *scenes[] = {"cylinder", "flat45", "flat45-back"};
  tu_rng r = {42};
  fd_stats st;
  memset(&st, 0, sizeof st);
  for (int k = 0; k < 3; k++) {
    wv_scene s = preset(scenes[k]);
    for (int j = 0; j < 4; j++) {
      wv_params p;
      random_params(patterns[j], &r, &p);
      p.noise_level = j % 2 ? 3 : 0;
      p.specular_noise = j % 2;
      if (k >= 1 && j >= 2) p.yarn_width = 0.8; /* open gaps, and gaps beside a yarn over the crossing one */
      fd_check(&s, &p, s.width / 2 - 24, s.height / 2 - 16, 48, 32, 12, &r, &st);
    }
  }
  wv_scene s = preset("cylinder");
  for (int j = 0; j < 2; j++) {
    wv_params p;
    random_params(patterns[j], &r, &p);
    fd_check(&s, &p, 376, j ? s.height - 12 : 0, 48, 12, 12, &r, &st);
  }
  printf("max relative error, analytic vs central difference, over %d checks:\n", st.checks);
  for (int i = 0; i < WV_P_COUNT; i++) printf("  %-18s %.2e\n", wv_param_name(i), st.worst[i]);
}

/* The float kernel (production) computes the same gradient as the double one. */
static void test_float_matches_double(void **state) {
  (void)state;
  tu_rng r = {7};
  static const char *scenes[] = {"cylinder", "flat45", "flat45-back"};
  for (int k = 0; k < 3; k++) {
    wv_scene s = preset(scenes[k]);
    wv_params p;
    random_params(k ? "satin" : "twill", &r, &p);
    if (k == 2) p.yarn_width = 0.85;
    wv_grad_opts gf = {.x0 = s.width / 2 - 32, .y0 = s.height / 2 - 16, .width = 64, .height = 32}, gd = gf;
    gd.double_precision = 1;
    wv_render_opts o = {0};
    o.spp = 16;
    wv_image dc, capf, capd;
    wv_error err;
    assert_int_equal(wv_image_alloc(&dc, 64, 32, 3, &err), WV_OK);
    fill_random(&dc, &r);
    double g1[WV_P_COUNT], g2[WV_P_COUNT], d1, d2;
    assert_int_equal(wv_render_grad_ex(&s, &p, &o, &gf, &dc, g1, &d1, &capf, &err), WV_OK);
    assert_int_equal(wv_render_grad_ex(&s, &p, &o, &gd, &dc, g2, &d2, &capd, &err), WV_OK);
    /* Relative per entry, but an entry 1000x below the largest (a sum with heavy
     * cancellation, e.g. the inclination) is measured against 1e-3 of the largest. */
    double gmax = 0;
    for (int i = 0; i < WV_P_COUNT; i++) gmax = fmax(gmax, fabs(g2[i]));
    for (int i = 0; i < WV_P_COUNT; i++) {
      double rel = fabs(g1[i] - g2[i]) / fmax(fmax(fabs(g1[i]), fabs(g2[i])), 1e-3 * gmax);
      if (rel > 1e-4) print_error("%s: float %.9e double %.9e\n", wv_param_name(i), g1[i], g2[i]);
      assert_true(rel < 1e-4);
    }
    assert_true(fabs(d1 - d2) <= 1e-5 * fabs(d2));
    assert_true(wv_image_mad(&capf, &capd) < 1e-6);
    wv_image_free(&dc), wv_image_free(&capf), wv_image_free(&capd);
  }
}

/* A small version of a preset: same camera and sample, fewer pixels. */
static wv_scene small_scene(const char *name, int w, int h, int spp) {
  wv_scene s = preset(name);
  s.width = w, s.height = h, s.spp = spp;
  return s;
}

/* The capture is exactly wv_render's; a window is exactly a crop of it; the
 * full-image gradient is the sum of the gradients of windows that tile it. */
static void test_capture_and_windows(void **state) {
  (void)state;
  static const char *scenes[] = {"cylinder", "flat45", "flat45-back"};
  tu_rng r = {99};
  for (int k = 0; k < 3; k++) {
    wv_scene s = small_scene(scenes[k], 96, k ? 96 : 36, 8);
    wv_params p;
    random_params("twill", &r, &p);
    p.noise_level = 2;
    if (k == 2) p.yarn_width = 0.7, p.density[0] = p.density[1] = 20; /* gaps a pixel wide: the glow */
    wv_error err;
    wv_image ref, cap, dc, win;
    assert_int_equal(wv_render(&s, &p, NULL, &ref, NULL, &err), WV_OK);
    assert_int_equal(wv_image_alloc(&dc, s.width, s.height, 3, &err), WV_OK);
    fill_random(&dc, &r);
    double g[WV_P_COUNT], dot;
    assert_int_equal(wv_render_grad_ex(&s, &p, NULL, NULL, &dc, g, &dot, &cap, &err), WV_OK);
    assert_int_equal(memcmp(ref.data, cap.data, sizeof(float) * 3 * s.width * s.height), 0);
    /* Other sample counts take the 8-wide path's other branches: 64 (8 columns, a
     * block is one row of the grid), 20 (5 columns, two blocks and a scalar tail). */
    for (int t = 0; t < 2; t++) {
      wv_render_opts o = {.spp = t ? 20 : 64};
      wv_image r2, c2;
      double g2[WV_P_COUNT], d2;
      assert_int_equal(wv_render(&s, &p, &o, &r2, NULL, &err), WV_OK);
      assert_int_equal(wv_render_grad_ex(&s, &p, &o, NULL, &dc, g2, &d2, &c2, &err), WV_OK);
      assert_int_equal(memcmp(r2.data, c2.data, sizeof(float) * 3 * s.width * s.height), 0);
      wv_image_free(&r2), wv_image_free(&c2);
    }
    /* Split into a top and a bottom window. */
    int hh = s.height / 2;
    double gsum[WV_P_COUNT] = {0}, dsum = 0;
    for (int part = 0; part < 2; part++) {
      int y0 = part ? hh : 0, wh = part ? s.height - hh : hh;
      wv_image sub;
      assert_int_equal(wv_image_alloc(&sub, s.width, wh, 3, &err), WV_OK);
      memcpy(sub.data, wv_image_px(&dc, 0, y0), sizeof(float) * 3 * s.width * wh);
      wv_grad_opts go = {.y0 = y0, .width = s.width, .height = wh};
      double gp[WV_P_COUNT], dp;
      assert_int_equal(wv_render_grad_ex(&s, &p, NULL, &go, &sub, gp, &dp, &win, &err), WV_OK);
      assert_int_equal(memcmp(win.data, wv_image_px(&ref, 0, y0), sizeof(float) * 3 * s.width * wh), 0);
      for (int i = 0; i < WV_P_COUNT; i++) gsum[i] += gp[i];
      dsum += dp;
      wv_image_free(&sub), wv_image_free(&win);
    }
    for (int i = 0; i < WV_P_COUNT; i++) assert_true(fabs(gsum[i] - g[i]) <= 1e-12 * fabs(g[i]) + 1e-300);
    assert_true(fabs(dsum - dot) <= 1e-12 * fabs(dot));
    wv_image_free(&ref), wv_image_free(&cap), wv_image_free(&dc);
  }
}

static void grad_window(const wv_scene *s, const wv_params *p, const wv_image *dc, int dbl, double g[WV_P_COUNT]) {
  wv_grad_opts go = {.x0 = s->width / 2 - dc->w / 2,
                     .y0 = s->height / 2 - dc->h / 2,
                     .width = dc->w,
                     .height = dc->h,
                     .double_precision = dbl};
  wv_render_opts o = {0};
  o.spp = 8;
  wv_error err = {0};
  wv_status st = wv_render_grad_ex(s, p, &o, &go, dc, g, NULL, NULL, &err);
  if (st) print_error("%s\n", err.msg);
  assert_int_equal(st, WV_OK);
}

/* Parameters the loss does not depend on get exactly zero. */
static void test_exact_zeros(void **state) {
  (void)state;
  tu_rng r = {5};
  wv_scene s = preset("cylinder");
  wv_params p;
  random_params("twill", &r, &p);
  p.noise_level = 2;
  wv_image dc;
  wv_error err;
  assert_int_equal(wv_image_alloc(&dc, 40, 24, 3, &err), WV_OK);
  double g[WV_P_COUNT];
  for (int dbl = 0; dbl < 2; dbl++) {
    /* Adjoint on red only: green and blue albedos do not matter. */
    fill_random(&dc, &r);
    for (int i = 0; i < 40 * 24; i++) dc.data[3 * i + 1] = dc.data[3 * i + 2] = 0;
    grad_window(&s, &p, &dc, dbl, g);
    for (int y = 0; y < 2; y++)
      for (int c = 1; c < 3; c++) {
        assert_true(g[WV_P_KD_WARP_R + 3 * y + c] == 0.0);
        assert_true(g[WV_P_KS_WARP_R + 3 * y + c] == 0.0);
      }
    assert_true(g[WV_P_KD_WARP_R] != 0.0 && g[WV_P_KS_WEFT_R] != 0.0);
    /* Zero adjoint: everything zero. */
    memset(dc.data, 0, sizeof(float) * 40 * 24 * 3);
    grad_window(&s, &p, &dc, dbl, g);
    for (int i = 0; i < WV_P_COUNT; i++) assert_true(g[i] == 0.0);
    fill_random(&dc, &r);
    /* No specular albedo: roughness and twist (which only shape the specular lobe) do not matter. */
    wv_params q = p;
    memset(q.specular, 0, sizeof q.specular);
    grad_window(&s, &q, &dc, dbl, g);
    assert_true(g[WV_P_ALPHA_WARP] == 0.0 && g[WV_P_ALPHA_WEFT] == 0.0 && g[WV_P_TWIST_DEG] == 0.0);
    assert_true(g[WV_P_KS_WARP_G] != 0.0 && g[WV_P_BETA_WARP] != 0.0);
    /* No diffuse albedo: the blend does not matter. */
    q = p;
    memset(q.diffuse, 0, sizeof q.diffuse);
    grad_window(&s, &q, &dc, dbl, g);
    assert_true(g[WV_P_BLEND] == 0.0);
    assert_true(g[WV_P_KD_WEFT_B] != 0.0);
    /* A fabric of warp only: no weft parameter matters. */
    q = p;
    snprintf(q.pattern, sizeof q.pattern, "custom");
    q.custom_rows = 1;
    snprintf(q.custom[0], sizeof q.custom[0], "1");
    grad_window(&s, &q, &dc, dbl, g);
    int weft[] = {WV_P_BETA_WEFT, WV_P_KD_WEFT_R, WV_P_KD_WEFT_G, WV_P_KD_WEFT_B, WV_P_KS_WEFT_R,
                  WV_P_KS_WEFT_G, WV_P_KS_WEFT_B, WV_P_ALPHA_WEFT};
    for (size_t i = 0; i < sizeof weft / sizeof weft[0]; i++) assert_true(g[weft[i]] == 0.0);
    assert_true(g[WV_P_BETA_WARP] != 0.0 && g[WV_P_ALPHA_WARP] != 0.0);
  }
  wv_image_free(&dc);
}

/* With the light behind the cloth: what transmitted light does not depend on gets exactly zero. */
static void test_exact_zeros_back(void **state) {
  (void)state;
  tu_rng r = {6};
  wv_scene s = preset("flat45-back");
  wv_params p;
  random_params("twill", &r, &p);
  p.noise_level = 2;
  wv_image dc;
  wv_error err;
  assert_int_equal(wv_image_alloc(&dc, 40, 24, 3, &err), WV_OK);
  double g[WV_P_COUNT];
  for (int dbl = 0; dbl < 2; dbl++) {
    /* Adjoint on red only; the reflection albedos never matter here. */
    fill_random(&dc, &r);
    for (int i = 0; i < 40 * 24; i++) dc.data[3 * i + 1] = dc.data[3 * i + 2] = 0;
    grad_window(&s, &p, &dc, dbl, g);
    for (int y = 0; y < 2; y++) {
      for (int c = 0; c < 3; c++)
        assert_true(g[WV_P_KD_WARP_R + 3 * y + c] == 0.0 && g[WV_P_KS_WARP_R + 3 * y + c] == 0.0);
      for (int c = 1; c < 3; c++) {
        assert_true(g[WV_P_KT_WARP_R + 3 * y + c] == 0.0);
        assert_true(g[WV_P_KST_WARP_R + 3 * y + c] == 0.0);
        assert_true(g[WV_P_KF_WARP_R + 3 * y + c] == 0.0);
      }
    }
    assert_true(g[WV_P_KT_WARP_R] != 0.0 && g[WV_P_KT_WEFT_R] != 0.0 && g[WV_P_KST_WEFT_R] != 0.0);
    assert_true(g[WV_P_KF_WARP_R] != 0.0 && g[WV_P_KF_WEFT_R] != 0.0);
    fill_random(&dc, &r);
    /* No specular transmission colour: roughness and twist do not matter. */
    wv_params q = p;
    memset(q.transmission_specular, 0, sizeof q.transmission_specular);
    grad_window(&s, &q, &dc, dbl, g);
    assert_true(g[WV_P_ALPHA_WARP] == 0.0 && g[WV_P_ALPHA_WEFT] == 0.0 && g[WV_P_TWIST_DEG] == 0.0);
    assert_true(g[WV_P_BETA_WARP] != 0.0 && g[WV_P_KT_WEFT_G] != 0.0);
    /* No transmission colour: the blend (of the diffuse transmission) does not matter. */
    q = p;
    memset(q.transmission, 0, sizeof q.transmission);
    grad_window(&s, &q, &dc, dbl, g);
    assert_true(g[WV_P_BLEND] == 0.0);
    assert_true(g[WV_P_KT_WARP_B] != 0.0 && g[WV_P_ALPHA_WEFT] != 0.0);
    /* Warp only, no gaps: no weft parameter matters. With gaps, light passes the crossing
     * weft between the warp yarns: its transmission colour matters, its shape does not. */
    q = p;
    snprintf(q.pattern, sizeof q.pattern, "custom");
    q.custom_rows = 1;
    snprintf(q.custom[0], sizeof q.custom[0], "1");
    grad_window(&s, &q, &dc, dbl, g);
    int weft[] = {WV_P_BETA_WEFT, WV_P_KT_WEFT_R, WV_P_KT_WEFT_G, WV_P_KT_WEFT_B, WV_P_KST_WEFT_R,
                  WV_P_KST_WEFT_G, WV_P_KST_WEFT_B, WV_P_ALPHA_WEFT, WV_P_KF_WEFT_R, WV_P_KF_WEFT_G, WV_P_KF_WEFT_B};
    for (size_t i = 0; i < sizeof weft / sizeof weft[0]; i++) assert_true(g[weft[i]] == 0.0);
    assert_true(g[WV_P_BETA_WARP] != 0.0 && g[WV_P_ALPHA_WARP] != 0.0);
    q.yarn_width = 0.6;
    grad_window(&s, &q, &dc, dbl, g);
    assert_true(g[WV_P_KT_WEFT_R] != 0.0 && g[WV_P_KT_WEFT_B] != 0.0 && g[WV_P_KF_WEFT_R] != 0.0);
    assert_true(g[WV_P_BETA_WEFT] == 0.0 && g[WV_P_ALPHA_WEFT] == 0.0 && g[WV_P_KST_WEFT_R] == 0.0);
  }
  wv_image_free(&dc);
}

/* Gradients stay finite at both ends of every range (in float and double). */
static void test_range_edges(void **state) {
  (void)state;
  tu_rng r = {11};
  static const char *scenes[] = {"cylinder", "flat45", "flat45-back"};
  wv_image dc;
  wv_error err;
  assert_int_equal(wv_image_alloc(&dc, 24, 16, 3, &err), WV_OK);
  fill_random(&dc, &r);
  for (int k = 0; k < 3; k++) {
    wv_scene s = preset(scenes[k]);
    for (int i = 0; i < WV_P_COUNT; i++)
      for (int end = 0; end < 2; end++) {
        wv_params p;
        random_params(k ? "satin" : "twill", &r, &p);
        p.noise_level = end ? 10 : 2; /* Q = 10 can drive a segment's beta to 0 */
        double lo, hi;
        wv_param_range(i, &lo, &hi);
        wv_param_set(&p, i, end ? hi : lo);
        for (int dbl = 0; dbl < 2; dbl++) {
          double g[WV_P_COUNT];
          grad_window(&s, &p, &dc, dbl, g);
          for (int j = 0; j < WV_P_COUNT; j++) {
            if (!isfinite(g[j])) print_error("%s = %g: d/d %s = %g\n", wv_param_name(i), end ? hi : lo, wv_param_name(j), g[j]);
            assert_true(isfinite(g[j]));
          }
        }
      }
    /* Everything at its lower and at its upper end at once. */
    for (int end = 0; end < 2; end++) {
      wv_params p;
      random_params("plain", &r, &p);
      for (int i = 0; i < WV_P_COUNT; i++) {
        double lo, hi;
        wv_param_range(i, &lo, &hi);
        wv_param_set(&p, i, end ? hi : lo);
      }
      double g[WV_P_COUNT];
      grad_window(&s, &p, &dc, 0, g);
      for (int j = 0; j < WV_P_COUNT; j++) assert_true(isfinite(g[j]));
    }
  }
  wv_image_free(&dc);
}

/* The result does not depend on the number of threads (row partials are
 * reduced in row order). */
static void test_deterministic(void **state) {
  (void)state;
  tu_rng r = {3};
  wv_scene s = small_scene("cylinder", 64, 40, 4);
  wv_params p;
  random_params("satin", &r, &p);
  wv_image dc;
  wv_error err;
  assert_int_equal(wv_image_alloc(&dc, 64, 40, 3, &err), WV_OK);
  fill_random(&dc, &r);
  double g1[WV_P_COUNT], g2[WV_P_COUNT];
  wv_render_opts o1 = {0}, o2 = {0};
  o1.threads = 1, o2.threads = 3;
  assert_int_equal(wv_render_grad(&s, &p, &o1, &dc, g1, NULL, &err), WV_OK);
  assert_int_equal(wv_render_grad(&s, &p, &o2, &dc, g2, NULL, &err), WV_OK);
  assert_int_equal(memcmp(g1, g2, sizeof g1), 0);
  wv_image_free(&dc);
}

/* The colour loss of the fit, L = sum W .* down16x8(capture), differentiated
 * through the downsampling adjoint, against finite differences. */
static void test_chain_with_downsampling(void **state) {
  (void)state;
  tu_rng r = {21};
  wv_scene s = small_scene("cylinder", 80, 30, 4);
  s.vfov_deg = 16.89; /* the preset's: the whole cylinder in 30 rows */
  wv_params p;
  random_params("twill", &r, &p);
  wv_image W, dc;
  wv_error err;
  assert_int_equal(wv_image_alloc(&W, 16, 8, 3, &err), WV_OK);
  fill_random(&W, &r);
  assert_int_equal(wv_image_downsample_backward(80, 30, &W, &dc, &err), WV_OK);
  wv_grad_opts g = {.width = 80, .height = 30, .double_precision = 1};
  wv_grad_check_entry e[WV_P_COUNT];
  assert_int_equal(wv_grad_check(&s, &p, NULL, &g, &dc, 1e-5, e, &err), WV_OK);
  for (int i = 0; i < WV_P_COUNT; i++) assert_true(e[i].rel_err < 1e-3);
  wv_image_free(&W), wv_image_free(&dc);
}

/* Render, then differentiate with several adjoints: the same as the fused call. */
static void test_record(void **state) {
  (void)state;
  tu_rng r = {17};
  wv_scene s = small_scene("flat45", 48, 40, 4);
  wv_params p;
  random_params("satin", &r, &p);
  p.noise_level = 1;
  wv_error err;
  wv_image dc, cap1, cap2;
  assert_int_equal(wv_image_alloc(&dc, 32, 24, 3, &err), WV_OK);
  for (int dbl = 0; dbl < 2; dbl++) {
    wv_grad_opts go = {.x0 = 8, .y0 = 10, .width = 32, .height = 24, .double_precision = dbl};
    wv_grad_record *rec;
    assert_int_equal(wv_render_record(&s, &p, NULL, &go, &cap1, &rec, &err), WV_OK);
    for (int k = 0; k < 3; k++) {
      fill_random(&dc, &r);
      double g1[WV_P_COUNT], g2[WV_P_COUNT], d1, d2;
      assert_int_equal(wv_record_grad(rec, &dc, g1, &d1, &err), WV_OK);
      assert_int_equal(wv_render_grad_ex(&s, &p, NULL, &go, &dc, g2, &d2, &cap2, &err), WV_OK);
      assert_int_equal(memcmp(g1, g2, sizeof g1), 0);
      assert_true(d1 == d2);
      assert_int_equal(memcmp(cap1.data, cap2.data, sizeof(float) * 32 * 24 * 3), 0);
      wv_image_free(&cap2);
    }
    wv_image bad;
    assert_int_equal(wv_image_alloc(&bad, 24, 32, 3, &err), WV_OK);
    double g[WV_P_COUNT];
    assert_int_equal(wv_record_grad(rec, &bad, g, NULL, &err), WV_ERR_INVALID);
    wv_image_free(&bad), wv_image_free(&cap1);
    wv_record_free(rec);
  }
  wv_record_free(NULL);
  wv_image_free(&dc);
}

/* The camera blur's checks: a 40 x 32 flat45 window, a random twill, a random adjoint;
 * the double path's window. */
static wv_grad_opts blur_setup(tu_rng *r, wv_scene *s, wv_params *p, wv_image *dc) {
  wv_error err;
  *s = small_scene("flat45", 40, 32, 4);
  random_params("twill", r, p);
  assert_int_equal(wv_image_alloc(dc, 40, 32, 3, &err), WV_OK);
  fill_random(dc, r);
  return (wv_grad_opts){.width = 40, .height = 32, .double_precision = 1};
}

/* The camera blur: its adjoint is the transpose (<K x, y> = <x, K^T y>); the gradient
 * through it matches finite differences; the capture equals wv_render's. */
static void test_camera_blur(void **state) {
  (void)state;
  tu_rng r = {31};
  wv_error err;
  int w = 13, h = 9;
  double x[13 * 9 * 3], y[13 * 9 * 3], kx[13 * 9 * 3], kty[13 * 9 * 3];
  for (int i = 0; i < w * h * 3; i++) x[i] = tu_rnd(&r), y[i] = tu_rnd(&r) - 0.5;
  assert_int_equal(wv_psf_apply(1.3, w, h, 3, x, kx, 0, &err), WV_OK);
  assert_int_equal(wv_psf_apply(1.3, w, h, 3, y, kty, 1, &err), WV_OK);
  double a = 0, b = 0, sx = 0, skx = 0;
  for (int i = 0; i < w * h * 3; i++) a += kx[i] * y[i], b += x[i] * kty[i], sx += x[i], skx += kx[i];
  assert_true(fabs(a - b) < 1e-12 * (fabs(a) + 1));
  assert_true(fabs(skx - sx) < 0.2 * sx); /* a blur, not a gain (edges clamped: close, not equal) */
  assert_int_equal(wv_psf_apply(9.0, w, h, 3, x, kx, 0, &err), WV_ERR_INVALID);
  wv_scene s;
  wv_params p;
  wv_image dc;
  wv_grad_opts g = blur_setup(&r, &s, &p, &dc);
  s.psf_sigma = 0.8;
  wv_grad_check_entry e[WV_P_COUNT];
  assert_int_equal(wv_grad_check(&s, &p, NULL, &g, &dc, 1e-5, e, &err), WV_OK);
  for (int i = 0; i < WV_P_COUNT; i++) {
    if (e[i].rel_err >= 1e-3)
      print_error("blurred %s: analytic %.9e, finite difference %.9e\n", wv_param_name(i), e[i].analytic,
                  e[i].numeric);
    assert_true(e[i].rel_err < 1e-3);
  }
  /* the float path's capture is wv_render's, and the blur changes it */
  wv_image cap, ref, sharp;
  double gr[WV_P_COUNT];
  assert_int_equal(wv_render_grad(&s, &p, NULL, &dc, gr, &cap, &err), WV_OK);
  assert_int_equal(wv_render(&s, &p, NULL, &ref, NULL, &err), WV_OK);
  assert_int_equal(memcmp(cap.data, ref.data, sizeof(float) * 40 * 32 * 3), 0);
  s.psf_sigma = 0;
  assert_int_equal(wv_render(&s, &p, NULL, &sharp, NULL, &err), WV_OK);
  assert_true(memcmp(sharp.data, ref.data, sizeof(float) * 40 * 32 * 3) != 0);
  wv_image_free(&cap), wv_image_free(&ref), wv_image_free(&sharp), wv_image_free(&dc);
}

/* The camera blur's sigma: dL/dsigma from a record (wv_record_grad_psf) against central
 * differences of L = sum(dcapture * capture) in sigma, on the double path. */
static void test_camera_blur_sigma(void **state) {
  (void)state;
  tu_rng r = {37};
  wv_error err;
  wv_scene s;
  wv_params p;
  wv_image dc;
  wv_grad_opts g = blur_setup(&r, &s, &p, &dc);
  const double sigmas[] = {0.45, 0.8, 1.7};
  for (int k = 0; k < 3; k++) {
    double h = 1e-4, gr[WV_P_COUNT], dsig, lp, lm;
    s.psf_sigma = sigmas[k];
    wv_grad_record *rec;
    wv_image cap;
    assert_int_equal(wv_render_record(&s, &p, NULL, &g, &cap, &rec, &err), WV_OK);
    assert_int_equal(wv_record_grad_psf(rec, &dc, &dsig, &err), WV_OK);
    wv_record_free(rec), wv_image_free(&cap);
    s.psf_sigma = sigmas[k] + h;
    assert_int_equal(wv_render_grad_ex(&s, &p, NULL, &g, &dc, gr, &lp, NULL, &err), WV_OK);
    s.psf_sigma = sigmas[k] - h;
    assert_int_equal(wv_render_grad_ex(&s, &p, NULL, &g, &dc, gr, &lm, NULL, &err), WV_OK);
    double fd = (lp - lm) / (2 * h), rel = fabs(dsig - fd) / fmax(fabs(dsig), fabs(fd));
    print_message("blur sigma %.2f: dL/dsigma %.9e, finite difference %.9e, relative error %.1e\n", sigmas[k], dsig,
                  fd, rel);
    assert_true(dsig != 0.0);
    assert_true(rel < 1e-4);
  }
  /* no blur, no derivative */
  s.psf_sigma = 0;
  wv_grad_record *rec;
  wv_image cap;
  double dsig = 1;
  assert_int_equal(wv_render_record(&s, &p, NULL, &g, &cap, &rec, &err), WV_OK);
  assert_int_equal(wv_record_grad_psf(rec, &dc, &dsig, &err), WV_OK);
  assert_true(dsig == 0.0);
  wv_record_free(rec), wv_image_free(&cap), wv_image_free(&dc);
}

/* A record rendered into again (wv_render_record_into) gives what a fresh one gives, bit
 * for bit, whether its memory grows or is reused, in float and double, with and without a
 * camera blur; after a failed render into it, it refuses to differentiate until the next
 * render succeeds. */
static void test_record_reuse(void **state) {
  (void)state;
  tu_rng r = {41};
  wv_scene s = small_scene("flat45", 48, 40, 4);
  wv_params p;
  random_params("twill", &r, &p);
  wv_error err;
  wv_image dc;
  assert_int_equal(wv_image_alloc(&dc, 32, 24, 3, &err), WV_OK);
  fill_random(&dc, &r);
  for (int k = 0; k < 4; k++) {
    int dbl = k & 1;
    s.psf_sigma = k & 2 ? 0.8 : 0;
    wv_grad_opts big = {.x0 = 8, .y0 = 10, .width = 32, .height = 24, .double_precision = dbl};
    wv_grad_opts small = {.x0 = 4, .y0 = 4, .width = 16, .height = 12, .double_precision = dbl};
    wv_grad_record *fresh, *kept = NULL;
    wv_image c1, c2;
    double g1[WV_P_COUNT], g2[WV_P_COUNT], d1, d2, s1, s2;
    assert_int_equal(wv_render_record(&s, &p, NULL, &big, &c1, &fresh, &err), WV_OK);
    assert_int_equal(wv_record_grad(fresh, &dc, g1, &d1, &err), WV_OK);
    assert_int_equal(wv_record_grad_psf(fresh, &dc, &s1, &err), WV_OK);
    wv_record_free(fresh);
    /* small first, so the big render grows the record; then the small one again into the big memory */
    for (int pass = 0; pass < 3; pass++) {
      const wv_grad_opts *g = pass == 1 ? &big : &small;
      assert_int_equal(wv_render_record_into(&s, &p, NULL, g, &c2, &kept, &err), WV_OK);
      assert_non_null(kept);
      if (pass != 1) {
        wv_image_free(&c2);
        continue;
      }
      assert_int_equal(wv_record_grad(kept, &dc, g2, &d2, &err), WV_OK);
      assert_int_equal(wv_record_grad_psf(kept, &dc, &s2, &err), WV_OK);
      assert_int_equal(memcmp(g1, g2, sizeof g1), 0);
      assert_true(d1 == d2 && s1 == s2);
      assert_true((s1 != 0) == (s.psf_sigma > 0));
      assert_int_equal(memcmp(c1.data, c2.data, sizeof(float) * 32 * 24 * 3), 0);
      wv_image_free(&c2);
    }
    /* the small render left in it does not take the big adjoint */
    assert_int_equal(wv_record_grad(kept, &dc, g2, NULL, &err), WV_ERR_INVALID);
    /* a failed render into it: no render kept, refused, then a good render works again */
    wv_grad_opts bad = {.x0 = 40, .width = 32, .height = 24, .double_precision = dbl};
    assert_int_equal(wv_render_record_into(&s, &p, NULL, &bad, &c2, &kept, &err), WV_ERR_INVALID);
    assert_null(c2.data);
    assert_non_null(kept);
    assert_int_equal(wv_record_grad(kept, &dc, g2, NULL, &err), WV_ERR_INVALID);
    assert_non_null(strstr(err.msg, "no render"));
    assert_int_equal(wv_record_grad_psf(kept, &dc, &s2, &err), WV_ERR_INVALID);
    assert_int_equal(wv_render_record_into(&s, &p, NULL, &big, &c2, &kept, &err), WV_OK);
    assert_int_equal(wv_record_grad(kept, &dc, g2, &d2, &err), WV_OK);
    assert_int_equal(memcmp(g1, g2, sizeof g1), 0);
    wv_record_free(kept), wv_image_free(&c1), wv_image_free(&c2);
  }
  assert_int_equal(wv_render_record_into(&s, &p, NULL, NULL, NULL, NULL, &err), WV_ERR_INVALID);
  wv_image_free(&dc);
}

/* Value (x, y, ch) of the camera blur's K, or of dK/dsigma, by the plain double sum over
 * the 2-D taps with clamped edges (the separable passes' definition, term by term). */
static double blur_ref(const double *in, int w, int h, int c, double sigma, int x, int y, int ch, int dsigma) {
  int r = (int)ceil(3 * sigma);
  double wk[32], dwk[32], sum = 0, m2 = 0;
  for (int k = 0; k <= r; k++) sum += (k ? 2 : 1) * (wk[k] = exp(-0.5 * k * k / (sigma * sigma)));
  for (int k = 0; k <= r; k++) wk[k] /= sum, m2 += (k ? 2 : 1) * wk[k] * k * k;
  for (int k = 0; k <= r; k++) dwk[k] = wk[k] * (k * k - m2) / (sigma * sigma * sigma);
  double v = 0;
  for (int ky = -r; ky <= r; ky++)
    for (int kx = -r; kx <= r; kx++) {
      int yy = y + ky < 0 ? 0 : y + ky >= h ? h - 1 : y + ky, xx = x + kx < 0 ? 0 : x + kx >= w ? w - 1 : x + kx;
      int ay = abs(ky), ax = abs(kx);
      double wt = dsigma ? dwk[ay] * wk[ax] + wk[ay] * dwk[ax] : wk[ay] * wk[ax];
      v += wt * in[((size_t)yy * w + xx) * c + ch];
    }
  return v;
}

/* The camera blur's row-streamed passes: K and dK/dsigma equal the plain 2-D sums, K^T
 * is K's transpose, on images narrower than the kernel, single rows, and images of
 * several bands of rows; and none of them depends on the number of threads. */
static void test_camera_blur_passes(void **state) {
  (void)state;
  tu_rng rg = {43};
  wv_error err;
  const int sizes[][2] = {{1, 1}, {3, 70}, {70, 1}, {13, 9}, {29, 75}};
  const double sigmas[] = {0.3, 0.64, 1.7, 3.2};
  for (int a = 0; a < 5; a++)
    for (int b = 0; b < 4; b++) {
      int w = sizes[a][0], h = sizes[a][1], c = 3;
      size_t n = (size_t)w * h * c;
      double *x = malloc(6 * n * sizeof *x), *y = x + n, *kx = y + n, *kty = kx + n, *dk = kty + n, *t = dk + n;
      for (size_t i = 0; i < n; i++) x[i] = tu_rnd(&rg), y[i] = tu_rnd(&rg) - 0.5;
      assert_int_equal(wv_psf_apply(sigmas[b], w, h, c, x, kx, 0, &err), WV_OK);
      assert_int_equal(wv_psf_apply(sigmas[b], w, h, c, y, kty, 1, &err), WV_OK);
      assert_int_equal(wv_psf_apply_dsigma(sigmas[b], w, h, c, x, dk, &err), WV_OK);
      double ab = 0, ba = 0, scale = 0;
      for (int py = 0; py < h; py++)
        for (int px = 0; px < w; px++)
          for (int ch = 0; ch < c; ch++) {
            size_t i = ((size_t)py * w + px) * c + ch;
            double rk = blur_ref(x, w, h, c, sigmas[b], px, py, ch, 0), rd = blur_ref(x, w, h, c, sigmas[b], px, py, ch, 1);
            assert_true(fabs(kx[i] - rk) <= 1e-13);
            assert_true(fabs(dk[i] - rd) <= 1e-12 * (1 + fabs(rd)));
            ab += kx[i] * y[i], ba += x[i] * kty[i], scale += fabs(kx[i] * y[i]);
          }
      assert_true(fabs(ab - ba) <= 1e-13 * scale);
      /* one thread, then three: the same values bit for bit */
      int threads = omp_get_max_threads();
      for (int th = 1; th <= 3; th += 2) {
        omp_set_num_threads(th);
        assert_int_equal(wv_psf_apply(sigmas[b], w, h, c, y, t, 1, &err), WV_OK);
        assert_int_equal(memcmp(t, kty, n * sizeof *t), 0);
        assert_int_equal(wv_psf_apply_dsigma(sigmas[b], w, h, c, x, t, &err), WV_OK);
        assert_int_equal(memcmp(t, dk, n * sizeof *t), 0);
      }
      omp_set_num_threads(threads);
      free(x);
    }
}

/* dL/dsigma from a record (the blur's derivative made a row at a time and summed by
 * rows) against the sum over the whole image of dL/dcapture * slope * (dK/dsigma
 * radiance) with the image-wide wv_psf_apply_dsigma: the radiance is wv_render's, the
 * slope the response's at the blurred radiance. */
static void test_camera_blur_sigma_sum(void **state) {
  (void)state;
  tu_rng r = {47};
  wv_error err;
  wv_scene s;
  wv_params p;
  wv_image dc;
  blur_setup(&r, &s, &p, &dc);
  const double sigmas[] = {0.64, 1.7};
  for (int k = 0; k < 2; k++) {
    s.psf_sigma = sigmas[k];
    wv_image cap, rad;
    wv_grad_record *rec;
    double dsig;
    assert_int_equal(wv_render_record(&s, &p, NULL, NULL, &cap, &rec, &err), WV_OK);
    assert_int_equal(wv_record_grad_psf(rec, &dc, &dsig, &err), WV_OK);
    wv_record_free(rec), wv_image_free(&cap);
    assert_int_equal(wv_render(&s, &p, NULL, &cap, &rad, &err), WV_OK);
    size_t n = (size_t)s.width * s.height * 3;
    double *a = malloc(3 * n * sizeof *a), *blur = a + n, *dk = blur + n;
    for (size_t i = 0; i < n; i++) a[i] = rad.data[i];
    assert_int_equal(wv_psf_apply(s.psf_sigma, s.width, s.height, 3, a, blur, 0, &err), WV_OK);
    assert_int_equal(wv_psf_apply_dsigma(s.psf_sigma, s.width, s.height, 3, a, dk, &err), WV_OK);
    double ref = 0;
    for (size_t i = 0; i < n; i++) {
      int px = (int)(i / 3 % (size_t)s.width), py = (int)(i / 3 / (size_t)s.width);
      double slope;
      float v = wv_respond_f(&s, wv_response_mask(&s, px, py), (float)blur[i], &slope);
      assert_true(v == cap.data[i]); /* the capture is this response */
      ref += (double)dc.data[i] * slope * dk[i];
    }
    print_message("blur sigma %.2f: dL/dsigma %.15e, image-wide sum %.15e\n", sigmas[k], dsig, ref);
    assert_true(ref != 0.0);
    assert_true(fabs(dsig - ref) <= 1e-9 * fabs(ref));
    free(a), wv_image_free(&cap), wv_image_free(&rad);
  }
  wv_image_free(&dc);
}

static void test_errors(void **state) {
  (void)state;
  wv_scene s = small_scene("flat45", 32, 32, 2);
  wv_params p;
  wv_error err;
  assert_int_equal(wv_params_default("plain", &p, &err), WV_OK);
  wv_image dc, cap = {0};
  assert_int_equal(wv_image_alloc(&dc, 16, 16, 3, &err), WV_OK);
  double g[WV_P_COUNT];
  assert_int_equal(wv_render_grad(&s, &p, NULL, &dc, g, &cap, &err), WV_ERR_INVALID); /* wrong size */
  assert_non_null(strstr(err.msg, "32 x 32"));
  assert_null(cap.data);
  wv_grad_opts go = {.x0 = 20, .width = 16, .height = 16};
  assert_int_equal(wv_render_grad_ex(&s, &p, NULL, &go, &dc, g, NULL, NULL, &err), WV_ERR_INVALID);
  go.x0 = 16;
  assert_int_equal(wv_render_grad_ex(&s, &p, NULL, &go, &dc, g, NULL, NULL, &err), WV_OK);
  p.roughness[0] = 0; /* out of range */
  assert_int_equal(wv_render_grad_ex(&s, &p, NULL, &go, &dc, g, NULL, NULL, &err), WV_ERR_INVALID);
  assert_non_null(strstr(err.msg, "roughness"));
  wv_image_free(&dc);
}

/* The back-lit capture as a linear function of the transmission colours (wv_trans_basis):
 * with a camera blur, its capture at other colours is wv_render's within float rounding, its
 * gradient the gradient renderer's; its match brings a capture of other colours close to a
 * photo of the target's; a front-lit scene and a wrongly sized adjoint are refused. */
static void test_trans_basis(void **state) {
  (void)state;
  tu_rng r = {31};
  wv_scene s = small_scene("flat45-back", 48, 40, 4);
  s.psf_sigma = 0.8;
  wv_params p;
  random_params("twill", &r, &p);
  wv_error err;
  wv_render_opts ro = {0};
  wv_trans_basis *b;
  assert_int_equal(wv_trans_basis_create(&s, &p, &ro, &b, &err), WV_OK);
  wv_image dc;
  assert_int_equal(wv_image_alloc(&dc, 48, 40, 3, &err), WV_OK);
  for (int k = 0; k < 3; k++) {
    wv_params q = p;
    for (int i = WV_P_REFLECT_COUNT; i < WV_P_COUNT; i++) wv_param_set(&q, i, 0.6 * tu_rnd(&r));
    wv_image want, got;
    assert_int_equal(wv_render(&s, &q, &ro, &want, NULL, &err), WV_OK);
    assert_int_equal(wv_trans_basis_capture(b, &q, &got, &err), WV_OK);
    double worst = 0;
    for (int i = 0; i < 48 * 40 * 3; i++) worst = fmax(worst, fabs(want.data[i] - got.data[i]));
    fill_random(&dc, &r);
    double g1[WV_P_COUNT] = {0}, g2[WV_P_COUNT];
    assert_int_equal(wv_trans_basis_grad(b, &dc, g1, &err), WV_OK);
    assert_int_equal(wv_render_grad(&s, &q, &ro, &dc, g2, NULL, &err), WV_OK);
    double gerr = 0, gmax = 0;
    for (int i = WV_P_REFLECT_COUNT; i < WV_P_COUNT; i++) gerr = fmax(gerr, fabs(g1[i] - g2[i])), gmax = fmax(gmax, fabs(g2[i]));
    for (int i = 0; i < WV_P_REFLECT_COUNT; i++) assert_true(g1[i] == 0); /* untouched */
    print_message("colours %d: capture off by %.2g at most, gradient by %.2g of %.3g\n", k, worst, gerr, gmax);
    assert_true(worst < 1e-4);
    assert_true(gmax > 0 && gerr < 1e-4 * gmax);
    wv_image_free(&want), wv_image_free(&got);
  }
  /* the match: a photo of the target's colours, the basis made at other colours */
  wv_params tq = p;
  for (int y = 0; y < 2; y++)
    for (int c = 0; c < 3; c++) tq.transmission[y][c] = 0.3 + 0.1 * c, tq.transmission_specular[y][c] = 0.05;
  wv_image photo, before, after;
  assert_int_equal(wv_render(&s, &tq, &ro, &photo, NULL, &err), WV_OK);
  wv_params m = p;
  assert_int_equal(wv_trans_basis_capture(b, &m, &before, &err), WV_OK);
  assert_int_equal(wv_trans_basis_match(b, &photo, 8, 5, WV_TRANS_MATCH_FREE, &m, NULL, &err), WV_OK);
  assert_int_equal(wv_trans_basis_capture(b, &m, &after, &err), WV_OK);
  double d0 = 0, d1 = 0;
  for (int i = 0; i < 48 * 40 * 3; i++) d0 += fabs(before.data[i] - photo.data[i]), d1 += fabs(after.data[i] - photo.data[i]);
  print_message("match: mean difference to the photo %.4f before, %.4f after\n", d0 / (48 * 40 * 3), d1 / (48 * 40 * 3));
  assert_true(d1 < 0.2 * d0);
  for (int i = 0; i < WV_P_REFLECT_COUNT; i++) assert_true(wv_param_get(&m, i) == wv_param_get(&p, i));
  /* the split kept: each channel's k_t of the two yarn types, and their k_st, scaled alike */
  wv_params sp = p;
  wv_image split;
  assert_int_equal(wv_trans_basis_match(b, &photo, 8, 5, WV_TRANS_MATCH_SPLIT, &sp, NULL, &err), WV_OK);
  assert_int_equal(wv_trans_basis_capture(b, &sp, &split, &err), WV_OK);
  double d2 = 0;
  for (int i = 0; i < 48 * 40 * 3; i++) d2 += fabs(split.data[i] - photo.data[i]);
  print_message("match, the split kept: mean difference %.4f\n", d2 / (48 * 40 * 3));
  assert_true(d2 < 0.5 * d0);
  for (int c = 0; c < 3; c++) {
    double f = sp.transmission[0][c] / p.transmission[0][c], g = sp.transmission_specular[0][c] / p.transmission_specular[0][c];
    assert_true(fabs(sp.transmission[1][c] - f * p.transmission[1][c]) < 1e-9);
    assert_true(fabs(sp.transmission_specular[1][c] - g * p.transmission_specular[1][c]) < 1e-9);
  }
  wv_image_free(&split);
  /* k_f alone: a photo of other forward colours; the match moves k_f toward them and nothing
   * else, and what it leaves unexplained falls */
  wv_params tf = p, fm = p;
  for (int y = 0; y < 2; y++)
    for (int c = 0; c < 3; c++) tf.transmission_forward[y][c] = y ? 0.1 + 0.1 * c : 0.4 - 0.1 * c;
  wv_image photo_f;
  assert_int_equal(wv_render(&s, &tf, &ro, &photo_f, NULL, &err), WV_OK);
  double res0, res1, ef0 = 0, ef1 = 0;
  wv_params held = p;
  assert_int_equal(wv_trans_basis_match(b, &photo_f, 8, 5, WV_TRANS_MATCH_FORWARD, &fm, &res1, &err), WV_OK);
  assert_int_equal(wv_trans_basis_match(b, &photo_f, 8, 5, WV_TRANS_MATCH_SPLIT, &held, &res0, &err), WV_OK);
  for (int i = WV_P_REFLECT_COUNT; i < WV_P_KF_WARP_R; i++) assert_true(wv_param_get(&fm, i) == wv_param_get(&p, i));
  for (int i = WV_P_KF_WARP_R; i < WV_P_COUNT; i++) {
    assert_true(wv_param_get(&held, i) == wv_param_get(&p, i)); /* the split holds k_f */
    ef0 += fabs(wv_param_get(&p, i) - wv_param_get(&tf, i)), ef1 += fabs(wv_param_get(&fm, i) - wv_param_get(&tf, i));
  }
  print_message("forward match: k_f error %.4f before, %.4f after; residual %.2g (the split's %.2g)\n", ef0, ef1, res1,
                res0);
  assert_true(ef1 < 0.3 * ef0);
  assert_true(res1 >= 0 && res1 < 0.5 * res0);
  /* the band's images at another width: the capture is wv_render's at that width */
  wv_params wq = tf;
  wq.forward_width = 0.6;
  assert_int_equal(wv_trans_basis_forward_width(b, &wq, &ro, &err), WV_OK);
  wv_image wwant, wgot;
  assert_int_equal(wv_render(&s, &wq, &ro, &wwant, NULL, &err), WV_OK);
  assert_int_equal(wv_trans_basis_capture(b, &wq, &wgot, &err), WV_OK);
  double wworst = 0, wmoved = 0;
  for (int i = 0; i < 48 * 40 * 3; i++)
    wworst = fmax(wworst, fabs(wwant.data[i] - wgot.data[i])), wmoved = fmax(wmoved, fabs(wgot.data[i] - photo_f.data[i]));
  print_message("band width 0.6: capture off by %.2g at most (the width moved it by %.2g)\n", wworst, wmoved);
  assert_true(wworst < 1e-4 && wmoved > 1e-2);
  /* widths made before come back from the basis's copies: the same captures bit for bit, also
   * after more widths than it keeps have pushed the first ones out */
  wv_params w1 = wq;
  w1.forward_width = p.forward_width;
  wv_image again;
  assert_int_equal(wv_trans_basis_forward_width(b, &w1, &ro, &err), WV_OK);
  assert_int_equal(wv_trans_basis_forward_width(b, &wq, &ro, &err), WV_OK);
  assert_int_equal(wv_trans_basis_capture(b, &wq, &again, &err), WV_OK);
  assert_memory_equal(again.data, wgot.data, sizeof(float) * 48 * 40 * 3);
  wv_image_free(&again);
  for (int k = 0; k < 10; k++) {
    w1.forward_width = 0.1 + 0.05 * k;
    assert_int_equal(wv_trans_basis_forward_width(b, &w1, &ro, &err), WV_OK);
  }
  assert_int_equal(wv_trans_basis_forward_width(b, &wq, &ro, &err), WV_OK);
  assert_int_equal(wv_trans_basis_capture(b, &wq, &again, &err), WV_OK);
  assert_memory_equal(again.data, wgot.data, sizeof(float) * 48 * 40 * 3);
  wv_image_free(&again);
  wv_image_free(&wwant), wv_image_free(&wgot), wv_image_free(&photo_f);
  assert_int_equal(wv_trans_basis_match(b, &photo, 100, 5, WV_TRANS_MATCH_FREE, &m, NULL, &err), WV_ERR_INVALID);
  wv_image small;
  assert_int_equal(wv_image_alloc(&small, 40, 48, 3, &err), WV_OK);
  double gs[WV_P_COUNT];
  assert_int_equal(wv_trans_basis_grad(b, &small, gs, &err), WV_ERR_INVALID);
  assert_int_equal(wv_trans_basis_match(b, &small, 8, 5, WV_TRANS_MATCH_SPLIT, &m, NULL, &err), WV_ERR_INVALID);
  wv_image_free(&small), wv_image_free(&photo), wv_image_free(&before), wv_image_free(&after), wv_image_free(&dc);
  wv_trans_basis_free(b);
  wv_trans_basis *none;
  wv_scene front = small_scene("flat45", 48, 40, 4);
  assert_int_equal(wv_trans_basis_create(&front, &p, &ro, &none, &err), WV_ERR_INVALID);
  assert_null(none);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_finite_differences), cmocka_unit_test(test_float_matches_double),
      cmocka_unit_test(test_capture_and_windows), cmocka_unit_test(test_exact_zeros),
      cmocka_unit_test(test_exact_zeros_back),
      cmocka_unit_test(test_range_edges),        cmocka_unit_test(test_deterministic),
      cmocka_unit_test(test_chain_with_downsampling), cmocka_unit_test(test_record),
      cmocka_unit_test(test_camera_blur),        cmocka_unit_test(test_camera_blur_sigma),
      cmocka_unit_test(test_record_reuse),       cmocka_unit_test(test_camera_blur_passes),
      cmocka_unit_test(test_camera_blur_sigma_sum), cmocka_unit_test(test_trans_basis),
      cmocka_unit_test(test_errors)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
