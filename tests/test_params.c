/* Parameter and scene files: round trips, and every kind of bad input named. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"
#include "woven/io.h"
#include "woven/params.h"
#include "woven/scene.h"

static const char *GOOD =
    "{\"pattern\": \"twill\", \"density\": {\"warp\": 120, \"weft\": 80},\n"
    " \"heightfield\": {\"warp\": 1.2, \"weft\": 1.0},\n"
    " \"diffuse\": {\"warp\": [0.30, 0.25, 0.10], \"weft\": [0.28, 0.27, 0.12]},\n"
    " \"specular\": {\"warp\": [0.60, 0.55, 0.40], \"weft\": [0.55, 0.55, 0.45]},\n"
    " \"roughness\": {\"warp\": 0.75, \"weft\": 0.70}, \"twist_deg\": -30, \"inclination_deg\": 30,\n"
    " \"diffuse_blend\": 0.5, \"noise_level\": 2, \"thickness\": 2.0, \"yarn_width\": 1.0, \"seed\": 1}";

static void test_parse_and_round_trip(void **state) {
  (void)state;
  wv_params p, q;
  wv_error err = {0};
  assert_int_equal(wv_params_parse(GOOD, "good.json", &p, &err), WV_OK);
  assert_string_equal(p.pattern, "twill");
  assert_true(p.density[WV_WARP] == 120 && p.density[WV_WEFT] == 80);
  assert_true(p.diffuse[WV_WEFT][2] == 0.12);
  assert_true(p.twist_deg == -30);
  assert_int_equal(p.noise_level, 2);
  char *text = wv_params_to_json(&p);
  assert_int_equal(wv_params_parse(text, "rt.json", &q, &err), WV_OK);
  free(text);
  assert_memory_equal(&p, &q, sizeof p); /* the same doubles, bit for bit */
  /* through a file, and a custom pattern */
  const char *dir = tu_tmpdir("params");
  char path[256];
  snprintf(path, sizeof path, "%s/custom.json", dir);
  wv_params c;
  assert_int_equal(wv_params_parse("{\"pattern\": \"custom\", \"weave\": [\"110\", \"011\", \"101\"]}", "c", &c, &err),
                   WV_OK);
  assert_int_equal(wv_params_write(path, &c, &err), WV_OK);
  assert_int_equal(wv_params_read(path, &q, &err), WV_OK);
  assert_memory_equal(&c, &q, sizeof c);
  /* every shipped example reads */
  const char *ex[] = {"twill", "twill90", "satin", "satin90", "plain", "basket"};
  for (int i = 0; i < 6; i++) {
    snprintf(path, sizeof path, "%s/examples/%s.json", WOVEN_SOURCE_DIR, ex[i]);
    if (wv_params_read(path, &q, &err)) fail_msg("%s", err.msg);
  }
}

static void expect_bad(const char *text, wv_status code, const char *needle);

/* Version 1 files (no "version", no "transmission") read with k_t = k_d / 2, versions 1 and
 * 2 (no "transmission_specular") with k_st = k_s, versions 1 to 3 (no "transmission_forward")
 * with k_f = 0 and forward_width 0.2; files are written as version 4 with the transmission
 * colours; a newer version is refused. */
static void test_versions(void **state) {
  (void)state;
  wv_params p, q;
  wv_error err = {0};
  assert_int_equal(wv_params_parse(GOOD, "v1.json", &p, &err), WV_OK);
  for (int y = 0; y < 2; y++)
    for (int c = 0; c < 3; c++)
      assert_true(p.transmission[y][c] == 0.5 * p.diffuse[y][c] && p.transmission_specular[y][c] == p.specular[y][c] &&
                  p.transmission_forward[y][c] == 0);
  assert_true(p.forward_width == 0.2);
  char *text = wv_params_to_json(&p);
  assert_non_null(strstr(text, "\"version\": 4"));
  assert_non_null(strstr(text, "\"transmission\""));
  assert_non_null(strstr(text, "\"transmission_specular\""));
  assert_non_null(strstr(text, "\"transmission_forward\""));
  assert_non_null(strstr(text, "\"forward_width\""));
  assert_int_equal(wv_params_parse(text, "v2.json", &q, &err), WV_OK);
  free(text);
  assert_memory_equal(&p, &q, sizeof p);
  /* given colours are kept, whatever the diffuse albedo; "version": 1 reads too */
  assert_int_equal(wv_params_parse("{\"version\": 2, \"pattern\": \"plain\", \"diffuse\": {\"warp\": 0.8},"
                                   " \"transmission\": {\"warp\": [0.1, 0.2, 0.3], \"weft\": 0.05}}",
                                   "t.json", &q, &err),
                   WV_OK);
  assert_true(q.transmission[WV_WARP][1] == 0.2 && q.transmission[WV_WEFT][2] == 0.05);
  assert_true(q.transmission_specular[WV_WARP][1] == q.specular[WV_WARP][1]);
  assert_int_equal(wv_params_parse("{\"version\": 3, \"pattern\": \"plain\", \"specular\": {\"warp\": 0.8},"
                                   " \"transmission_specular\": {\"warp\": [0.1, 0.2, 0.3], \"weft\": 0.05}}",
                                   "t.json", &q, &err),
                   WV_OK);
  assert_true(q.transmission_specular[WV_WARP][2] == 0.3 && q.transmission_specular[WV_WEFT][0] == 0.05);
  assert_true(q.transmission[WV_WARP][0] == 0.25); /* k_t's default as before */
  assert_int_equal(wv_params_parse("{\"version\": 1, \"pattern\": \"plain\", \"diffuse\": {\"weft\": 0.8}}", "t.json",
                                   &q, &err),
                   WV_OK);
  assert_true(q.transmission[WV_WEFT][0] == 0.4 && q.transmission[WV_WARP][0] == 0.25);
  wv_params_default("satin", &q, NULL);
  assert_true(q.transmission[WV_WARP][1] == 0.25); /* the prior mean: half of k_d = 0.5 */
  assert_true(q.transmission_specular[WV_WEFT][1] == 0.5); /* k_s */
  assert_int_equal(wv_params_parse("{\"version\": 4, \"pattern\": \"plain\", \"forward_width\": 0.4,"
                                   " \"transmission_forward\": {\"warp\": [0.1, 0.2, 0.3], \"weft\": 0.05}}",
                                   "v4.json", &q, &err),
                   WV_OK);
  assert_true(q.transmission_forward[WV_WARP][2] == 0.3 && q.transmission_forward[WV_WEFT][1] == 0.05);
  assert_true(q.forward_width == 0.4 && q.transmission[WV_WARP][0] == 0.25); /* k_t's default as before */
  assert_true(wv_params_has_forward_band(&q) && !wv_params_has_forward_band(&p));
  expect_bad("{\"version\": 5, \"pattern\": \"twill\"}", WV_ERR_INVALID, "version");
  expect_bad("{\"pattern\": \"twill\", \"forward_width\": 0.01}", WV_ERR_INVALID, "forward_width");
  expect_bad("{\"pattern\": \"twill\", \"transmission_forward\": {\"warp\": [0.1, 1.5, 0]}}", WV_ERR_INVALID,
             "transmission_forward.warp");
  expect_bad("{\"version\": 0, \"pattern\": \"twill\"}", WV_ERR_INVALID, "version");
  expect_bad("{\"version\": 1.5, \"pattern\": \"twill\"}", WV_ERR_INVALID, "version");
  expect_bad("{\"pattern\": \"twill\", \"transmission\": {\"weft\": [0.1, 1.2, 0]}}", WV_ERR_INVALID,
             "transmission.weft");
  expect_bad("{\"pattern\": \"twill\", \"transmission\": {\"warp\": [0.1]}}", WV_ERR_INVALID,
             "transmission.warp");
  expect_bad("{\"pattern\": \"twill\", \"transmission_specular\": {\"weft\": [0.1, -0.2, 0]}}", WV_ERR_INVALID,
             "transmission_specular.weft");
}

static void test_param_vector(void **state) {
  (void)state;
  wv_params p;
  wv_params_default("satin", &p, NULL);
  for (int i = 0; i < WV_P_COUNT; i++) {
    double lo, hi;
    wv_param_range(i, &lo, &hi);
    assert_true(lo < hi);
    wv_param_set(&p, i, 0.5 * (lo + hi));
    assert_true(wv_param_get(&p, i) == 0.5 * (lo + hi));
    assert_true(strlen(wv_param_name(i)) > 3);
  }
  assert_int_equal(wv_params_validate(&p, NULL), WV_OK);
  assert_true(p.diffuse[WV_WEFT][1] == 0.5);
  assert_true(p.roughness[WV_WEFT] == 0.505);
  /* the transmission colours come after the reflection model's parameters */
  assert_int_equal(WV_P_REFLECT_COUNT, 19);
  assert_int_equal(WV_P_COUNT, 37);
  assert_string_equal(wv_param_name(WV_P_KF_WEFT_B), "transmission_forward.weft[2]");
  assert_string_equal(wv_param_name(WV_P_KT_WEFT_B), "transmission.weft[2]");
  assert_string_equal(wv_param_name(WV_P_KST_WARP_G), "transmission_specular.warp[1]");
  assert_true(p.transmission[WV_WEFT][2] == 0.5 && p.transmission_specular[WV_WARP][0] == 0.5);
}

/* Each bad text must fail with the given code and a message containing 'needle'. */
static void expect_bad(const char *text, wv_status code, const char *needle) {
  wv_params p;
  wv_error err = {0};
  wv_status st = wv_params_parse(text, "bad.json", &p, &err);
  if (st != code || !strstr(err.msg, needle) || !strstr(err.msg, "bad.json"))
    fail_msg("for %s: got %d '%s', wanted %d with '%s'", text, st, err.msg, code, needle);
}

static void test_bad_params(void **state) {
  (void)state;
  expect_bad("{\"pattern\": \"twill\",\n \"density\": {\"warp\": 120,, }}", WV_ERR_FORMAT, "bad.json:2:");
  expect_bad("{\"pattern\": \"twill\", \"colour\": 1}", WV_ERR_INVALID, "'colour'");
  expect_bad("{\"pattern\": \"twill\", \"density\": {\"warp\": 120, \"wefts\": 3}}", WV_ERR_INVALID, "density.wefts");
  expect_bad("{\"pattern\": \"herringbone\"}", WV_ERR_INVALID, "herringbone");
  expect_bad("{\"pattern\": \"twill\", \"density\": {\"warp\": 400}}", WV_ERR_INVALID, "density.warp");
  expect_bad("{\"pattern\": \"twill\", \"roughness\": {\"weft\": 0}}", WV_ERR_INVALID, "roughness.weft");
  expect_bad("{\"pattern\": \"twill\", \"diffuse\": {\"warp\": [0.1, 1.5, 0.2]}}", WV_ERR_INVALID, "diffuse.warp");
  expect_bad("{\"pattern\": \"twill\", \"diffuse\": {\"warp\": [0.1, 0.2]}}", WV_ERR_INVALID, "diffuse.warp");
  expect_bad("{\"pattern\": \"twill\", \"twist_deg\": \"a lot\"}", WV_ERR_INVALID, "twist_deg");
  expect_bad("{\"pattern\": \"twill\", \"inclination_deg\": 1e999}", WV_ERR_FORMAT, "bad.json:1:");
  expect_bad("{\"pattern\": \"twill\", \"inclination_deg\": NaN}", WV_ERR_FORMAT, "bad.json:1:");
  expect_bad("{\"pattern\": \"twill\", \"noise_level\": 11}", WV_ERR_INVALID, "noise_level");
  expect_bad("{\"pattern\": \"twill\", \"noise_level\": 2.5}", WV_ERR_INVALID, "noise_level");
  expect_bad("{\"pattern\": \"twill\", \"twist_deg\": 5, \"twist_deg\": 6}", WV_ERR_FORMAT, "duplicate");
  expect_bad("{\"pattern\": \"custom\", \"weave\": [\"10\", \"1\"]}", WV_ERR_INVALID, "weave");
  expect_bad("{\"pattern\": \"custom\"}", WV_ERR_INVALID, "weave");
  expect_bad("[1, 2]", WV_ERR_INVALID, "object");
  expect_bad("", WV_ERR_FORMAT, "bad.json:");
  /* NaN can also arrive through the API */
  wv_params p;
  wv_error err = {0};
  wv_params_default("plain", &p, NULL);
  p.diffuse_blend = NAN;
  assert_int_equal(wv_params_validate(&p, &err), WV_ERR_INVALID);
  assert_non_null(strstr(err.msg, "diffuse_blend"));
  /* missing and unreadable files */
  assert_int_equal(wv_params_read("no/such/file.json", &p, &err), WV_ERR_IO);
  assert_non_null(strstr(err.msg, "no/such/file.json"));
}

static void test_scenes(void **state) {
  (void)state;
  const char *names[] = {"cylinder", "flat45", "flat45-back"};
  for (int i = 0; i < 3; i++) {
    wv_scene a, b;
    wv_error err = {0};
    char path[512];
    snprintf(path, sizeof path, "%s/scenes/%s.json", WOVEN_SOURCE_DIR, names[i]);
    assert_int_equal(wv_scene_preset(names[i], &a, &err), WV_OK);
    if (wv_scene_read(path, &b, &err)) fail_msg("%s", err.msg);
    assert_memory_equal(&a, &b, sizeof a); /* scenes/ files and built-in presets agree */
    char *text = wv_scene_to_json(&a);
    assert_int_equal(wv_scene_parse(text, "rt", &b, &err), WV_OK);
    free(text);
    assert_memory_equal(&a, &b, sizeof a);
  }
  /* a skewed plane survives the round trip; square cloth writes no skew */
  wv_scene k, r;
  wv_error err = {0};
  wv_scene_preset("flat45", &k, NULL);
  char *square = wv_scene_to_json(&k);
  assert_null(strstr(square, "skew_deg"));
  free(square);
  k.rotation_deg = -0.75, k.skew_deg = -4.05;
  char *text = wv_scene_to_json(&k);
  assert_int_equal(wv_scene_parse(text, "rt", &r, &err), WV_OK);
  free(text);
  assert_memory_equal(&k, &r, sizeof k);
  /* and a distorted one; an undistorted plane writes no distortion */
  assert_null(strstr(text = wv_scene_to_json(&k), "distortion"));
  free(text);
  k.distort_extent_mm = 31.9, k.distort[0][4] = 0.25, k.distort[0][2] = 7, k.distort[1][8] = -0.125;
  text = wv_scene_to_json(&k);
  assert_int_equal(wv_scene_parse(text, "rt", &r, &err), WV_OK);
  free(text);
  assert_memory_equal(&k, &r, sizeof k);
  double d[2]; /* 0.25 b^2 + 7 a^2 and -0.125 b^3 at a = 0, b = 1: the point (0, 3.9875) units */
  wv_scene_distortion_at(&k, 0, 31.9 / 8, d);
  assert_true(fabs(d[0] - 0.25) < 1e-12 && fabs(d[1] + 0.125) < 1e-12);
  wv_scene s;
  wv_scene_preset("flat45", &s, NULL);
  assert_int_equal(s.width, 512);
  assert_int_equal(s.encoding, WV_ENC_GAMMA);
  assert_true(s.falloff && s.falloff_sigma == 450);
  assert_true(s.glow_radiance == 0 && !wv_scene_transmits(&s));
  /* the back-lit rig: flat45 with the light behind the cloth and the gap glow */
  wv_scene b;
  assert_int_equal(wv_scene_load("flat45-back", &b, &err), WV_OK);
  assert_true(wv_scene_transmits(&b));
  assert_true(b.light_pos[2] == -9 && b.light_pos[0] == 0 && b.light_intensity == 300);
  assert_true(b.glow_radiance == 8 && b.glow_sigma == 20);
  b.light_pos[2] = s.light_pos[2], b.light_pos[1] = s.light_pos[1], b.glow_radiance = b.glow_sigma = 0;
  memcpy(b.name, s.name, sizeof b.name);
  assert_memory_equal(&b, &s, sizeof b); /* otherwise flat45 */
  wv_scene_preset("cylinder", &b, NULL);
  b.light_pos[2] = -100;
  assert_false(wv_scene_transmits(&b)); /* a cylinder never transmits */
}

static void expect_bad_scene(const char *text, wv_status code, const char *needle) {
  wv_scene s;
  wv_error err = {0};
  wv_status st = wv_scene_parse(text, "scene.json", &s, &err);
  if (st != code || !strstr(err.msg, needle) || !strstr(err.msg, "scene.json"))
    fail_msg("for %s: got %d '%s', wanted %d with '%s'", text, st, err.msg, code, needle);
}

#define CAM "\"camera\": {\"position_mm\": [0,0,8], \"look_at_mm\": [0,0,0], \"vfov_deg\": 50}"
#define LIGHT "\"light\": {\"position_mm\": [0,8,8], \"intensity\": 300}"
#define PLANE "\"sample\": {\"shape\": \"plane\"}"

static void test_bad_scenes(void **state) {
  (void)state;
  expect_bad_scene("{\"image\": {\"width\": 100, \"height\": 100}, " CAM ", " PLANE ", " LIGHT ", }", WV_ERR_FORMAT,
                   "scene.json:1:");
  expect_bad_scene("{\"image\": {\"width\": 100000, \"height\": 100}, " CAM ", " PLANE ", " LIGHT "}",
                   WV_ERR_INVALID, "image");
  expect_bad_scene("{\"image\": {\"width\": 16000, \"height\": 16000, \"spp\": 4000}, " CAM ", " PLANE ", " LIGHT "}",
                   WV_ERR_NOMEM, "too many samples");
  expect_bad_scene("{\"image\": {\"width\": 10, \"height\": 10, \"spp\": 0}, " CAM ", " PLANE ", " LIGHT "}",
                   WV_ERR_INVALID, "image.spp");
  expect_bad_scene("{\"image\": {\"width\": 10, \"height\": 10}, " CAM ", \"sample\": {\"shape\": \"sphere\"}, " LIGHT "}",
                   WV_ERR_INVALID, "sample.shape");
  expect_bad_scene("{\"image\": {\"width\": 10, \"height\": 10}, " CAM ", " PLANE ", " LIGHT ", \"lens\": 1}",
                   WV_ERR_INVALID, "'lens'");
  expect_bad_scene("{\"image\": {\"width\": 10, \"height\": 10}, " CAM ", " PLANE "}", WV_ERR_INVALID, "light");
  expect_bad_scene("{\"image\": {\"width\": 10, \"height\": 10}, " CAM
                   ", \"sample\": {\"shape\": \"plane\", \"skew_deg\": 20}, " LIGHT "}",
                   WV_ERR_INVALID, "sample.skew_deg");
  expect_bad_scene("{\"image\": {\"width\": 10, \"height\": 10}, " CAM
                   ", \"sample\": {\"shape\": \"cylinder\", \"radius_mm\": 5, \"skew_deg\": 2}, " LIGHT "}",
                   WV_ERR_INVALID, "skew_deg");
  expect_bad_scene("{\"image\": {\"width\": 10, \"height\": 10}, " CAM
                   ", \"sample\": {\"shape\": \"cylinder\", \"radius_mm\": 5, \"distortion\": {}}, " LIGHT "}",
                   WV_ERR_INVALID, "sample.distortion");
  expect_bad_scene("{\"image\": {\"width\": 10, \"height\": 10}, " CAM
                   ", \"sample\": {\"shape\": \"plane\", \"distortion\": {\"extent_mm\": 30, \"x\": [1], "
                   "\"y\": [0,0,0,0,0,0,0,0,0]}}, " LIGHT "}",
                   WV_ERR_INVALID, "sample.distortion.x");
  expect_bad_scene("{\"image\": {\"width\": 10, \"height\": 10}, " CAM
                   ", \"sample\": {\"shape\": \"plane\", \"distortion\": {\"extent_mm\": 0, \"x\": [1,0,0,0,0,0,0,0,0], "
                   "\"y\": [0,0,0,0,0,0,0,0,0]}}, " LIGHT "}",
                   WV_ERR_INVALID, "extent_mm");
  expect_bad_scene("{\"image\": {\"width\": 10, \"height\": 10}, " CAM
                   ", \"sample\": {\"shape\": \"plane\", \"distortion\": {\"extent_mm\": 30, \"x\": [1e9,0,0,0,0,0,0,0,0], "
                   "\"y\": [0,0,0,0,0,0,0,0,0], \"z\": 1}}, " LIGHT "}",
                   WV_ERR_INVALID, "sample.distortion.z");
  expect_bad_scene("{\"image\": {\"width\": 10, \"height\": 10}, " CAM ", " PLANE ", " LIGHT
                   ", \"response\": {\"encoding\": \"log\"}}",
                   WV_ERR_INVALID, "response.encoding");
  expect_bad_scene("{\"image\": {\"width\": 10, \"height\": 10}, " CAM ", " PLANE ", " LIGHT
                   ", \"response\": {\"gap_glow\": {\"radiance\": -1, \"sigma_px\": 20}}}",
                   WV_ERR_INVALID, "response.gap_glow.radiance");
  expect_bad_scene("{\"image\": {\"width\": 10, \"height\": 10}, " CAM ", " PLANE ", " LIGHT
                   ", \"response\": {\"gap_glow\": {\"radiance\": 8, \"sigma_px\": 0}}}",
                   WV_ERR_INVALID, "response.gap_glow.sigma_px");
  expect_bad_scene("{\"image\": {\"width\": 10, \"height\": 10}, " CAM ", " PLANE ", " LIGHT
                   ", \"response\": {\"gap_glow\": {\"radiance\": 8}}}",
                   WV_ERR_INVALID, "response.gap_glow.sigma_px");
  expect_bad_scene("{\"image\": {\"width\": 10, \"height\": 10}, " CAM ", " PLANE ", " LIGHT
                   ", \"response\": {\"gap_glow\": {\"radiance\": 8, \"sigma_px\": 20, \"colour\": 1}}}",
                   WV_ERR_INVALID, "colour");
  expect_bad_scene("{\"image\": {\"width\": 10, \"height\": 10}, \"camera\": {\"position_mm\": [0,0,8], "
                   "\"look_at_mm\": [0,0,0], \"vfov_deg\": 200}, " PLANE ", " LIGHT "}",
                   WV_ERR_INVALID, "vfov_deg");
  wv_scene s;
  wv_error err = {0};
  assert_int_equal(wv_scene_load("nowhere.json", &s, &err), WV_ERR_IO);
  assert_non_null(strstr(err.msg, "nowhere.json"));
}

static void test_prior_samples(void **state) {
  (void)state;
  const char *pats[] = {"plain", "twill", "satin", "twill90", "satin90"};
  for (int k = 0; k < 5; k++) {
    double dmin[2] = {1e9, 1e9}, dmax[2] = {0, 0}, amin[2] = {9, 9}, amax[2] = {0, 0};
    int grey_like = 0, same_colour = 0;
    for (uint64_t seed = 0; seed < 400; seed++) {
      wv_params p, q;
      wv_error err = {0};
      if (wv_params_sample_prior(pats[k], seed, &p, &err)) fail_msg("%s", err.msg);
      wv_params_sample_prior(pats[k], seed, &q, NULL);
      assert_memory_equal(&p, &q, sizeof p); /* deterministic */
      for (int y = 0; y < 2; y++) {
        dmin[y] = fmin(dmin[y], p.density[y]), dmax[y] = fmax(dmax[y], p.density[y]);
        amin[y] = fmin(amin[y], p.roughness[y]), amax[y] = fmax(amax[y], p.roughness[y]);
        for (int c = 0; c < 3; c++) /* k_s = k_d^gamma, gamma in (0,1): never darker */
          assert_true(p.specular[y][c] >= p.diffuse[y][c] - 1e-12);
      }
      grey_like += p.diffuse[0][0] == p.diffuse[0][1] && p.diffuse[0][1] == p.diffuse[0][2];
      for (int y = 0; y < 2; y++) { /* transmission: the diffuse colour times one factor in 0.1..0.9 */
        double f = p.diffuse[y][0] > 0 ? p.transmission[y][0] / p.diffuse[y][0] : 0.5;
        assert_true(f >= 0.1 && f <= 0.9);
        for (int c = 0; c < 3; c++) assert_true(fabs(p.transmission[y][c] - f * p.diffuse[y][c]) < 1e-12);
        /* specular transmission: the specular colour times one factor in 0.1..1 */
        double fs = p.specular[y][0] > 0 ? p.transmission_specular[y][0] / p.specular[y][0] : 0.5;
        assert_true(fs >= 0.1 && fs <= 1.0);
        for (int c = 0; c < 3; c++)
          assert_true(fabs(p.transmission_specular[y][c] - fs * p.specular[y][c]) < 1e-12);
        /* the forward band: the transmission colour times one factor in 0..1 */
        double ff = p.transmission[y][0] > 0 ? p.transmission_forward[y][0] / p.transmission[y][0] : 0.5;
        assert_true(ff >= 0 && ff <= 1);
        for (int c = 0; c < 3; c++)
          assert_true(fabs(p.transmission_forward[y][c] - ff * p.transmission[y][c]) < 1e-12);
      }
      assert_true(p.forward_width >= 0.1 && p.forward_width <= 0.8);
      same_colour += !memcmp(p.diffuse[0], p.diffuse[1], sizeof p.diffuse[0]);
      assert_true(p.noise_level >= 0 && p.noise_level <= 5);
    }
    int rot = k >= 3, base = k % 3 == 0 ? 0 : k % 3; /* 0 plain, 1 twill, 2 satin (and 90s) */
    if (k == 3) base = 1;
    if (k == 4) base = 2;
    double want_lo = base == 0 ? 60 : base == 1 ? 80 : 120, want_hi = base == 0 ? 140 : base == 1 ? 200 : 250;
    int y = rot ? WV_WEFT : WV_WARP; /* the base pattern's warp */
    assert_true(dmin[y] >= want_lo && dmax[y] <= want_hi && dmax[y] - dmin[y] > 0.8 * (want_hi - want_lo));
    if (base == 2) { /* satin: glossy weft, rough warp */
      assert_true(amin[1 - y] >= 0.04 && amax[1 - y] <= 0.49);
      assert_true(amin[y] >= 0.49);
    }
    assert_true(grey_like > 15 && grey_like < 90);     /* about 10% of 400 */
    assert_true(same_colour > 80 && same_colour < 170); /* about 30% */
  }
  /* the transmission colours were added without changing any earlier draw */
  wv_params p;
  wv_params_sample_prior("twill", 7, &p, NULL);
  assert_true(p.heightfield[0] == 1.7358562399228419 && p.diffuse[1][2] == 0.44830148950692383);
  assert_true(p.roughness[1] == 0.79454175580912723 && p.inclination_deg == 24.30283196905037);
  assert_true(p.seed == 1054995969 && p.density[0] == 98);
  wv_params_sample_prior("satin90", 123, &p, NULL);
  assert_true(p.heightfield[0] == 0.51354726608763324 && p.diffuse[1][2] == 0.31611276570360347);
  assert_true(p.seed == 2058691208 && p.density[0] == 60);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_parse_and_round_trip), cmocka_unit_test(test_param_vector),
                                     cmocka_unit_test(test_bad_params), cmocka_unit_test(test_versions),
                                     cmocka_unit_test(test_scenes),
                                     cmocka_unit_test(test_bad_scenes), cmocka_unit_test(test_prior_samples)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
