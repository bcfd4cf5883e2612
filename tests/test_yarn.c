/* Bent-cylinder geometry (the shading kernel's): n.t = 0 and unit vectors
 * everywhere, heightfield scaling as SPEC section 3 writes it, noise per segment,
 * the open gaps and the cloth's thickness that light through the cloth meets. */
#include <math.h>

#include "kernel/kernel.h"
#include "testutil.h"
#include "woven/params.h"
#include "woven/yarn.h"

/* The shading kernel's bent-cylinder frame at (u, v), scaled by beta (1: the
 * frame before heightfield scaling), in the yarn's local frame. */
static void frame_at(float u, float v, float sp, float cp, float beta, float n[3], float t[3]) {
  wv_yarn_frame_f f;
  wv_yarn_bend_f(u, 0.0f, v, beta, 0.0f, sp, cp, &f, NULL);
  for (int i = 0; i < 3; i++) n[i] = f.n[i], t[i] = f.t[i];
}

static void assert_frame(const float n[3], const float t[3], double tol) {
  double nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2], tt = t[0] * t[0] + t[1] * t[1] + t[2] * t[2];
  double nt = n[0] * t[0] + n[1] * t[1] + n[2] * t[2];
  assert_true(fabs(nn - 1) < tol);
  assert_true(fabs(tt - 1) < tol);
  assert_true(fabs(nt) < tol);
}

static void test_frame_orthonormal(void **state) {
  (void)state;
  for (double u = -1.22; u <= 1.22; u += 0.061)
    for (double v = -1.5707; v <= 1.5707; v += 0.0785)
      for (double psi = -1.047; psi <= 1.047; psi += 0.26)
        for (double beta = 0; beta <= 2.0; beta += 0.25) {
          float n[3], t[3];
          frame_at((float)u, (float)v, sinf((float)psi), cosf((float)psi), 1.0f, n, t);
          assert_frame(n, t, 2e-6);
          frame_at((float)u, (float)v, sinf((float)psi), cosf((float)psi), (float)beta, n, t);
          assert_frame(n, t, 2e-6);
        }
}

/* SPEC: t' = normalize(k t_x, k t_y, t_z), k = -n'_z t_z / (n'_x t_x + n'_y t_y).
 * Our stable form must give the same direction wherever the SPEC form is defined. */
static void test_scale_matches_spec_formula(void **state) {
  (void)state;
  int compared = 0;
  for (double u = -1.0; u <= 1.0; u += 0.13)
    for (double v = -1.4; v <= 1.4; v += 0.17)
      for (double beta = 0.1; beta <= 2.0; beta += 0.3) {
        float n[3], t[3], sp = sinf(0.4f), cp = cosf(0.4f);
        frame_at((float)u, (float)v, sp, cp, 1.0f, n, t);
        double nx = beta * n[0], ny = beta * n[1], nz = n[2], l = sqrt(nx * nx + ny * ny + nz * nz);
        nx /= l, ny /= l, nz /= l;
        double den = nx * t[0] + ny * t[1];
        if (fabs(den) < 1e-3) continue;
        double k = -nz * t[2] / den;
        double tx = k * t[0], ty = k * t[1], tz = t[2], lt = sqrt(tx * tx + ty * ty + tz * tz);
        tx /= lt, ty /= lt, tz /= lt;
        frame_at((float)u, (float)v, sp, cp, (float)beta, n, t);
        assert_true(fabs(n[0] - nx) < 1e-5 && fabs(n[1] - ny) < 1e-5 && fabs(n[2] - nz) < 1e-5);
        /* same line (fibers have no direction) */
        double dot = tx * t[0] + ty * t[1] + tz * t[2];
        assert_true(fabs(fabs(dot) - 1) < 1e-5);
        compared++;
      }
  assert_true(compared > 500);
}

static void test_eval_everywhere(void **state) {
  (void)state;
  const char *pats[] = {"plain", "twill", "satin", "twill90", "satin90"};
  for (int k = 0; k < 5; k++) {
    wv_params p;
    wv_params_default(pats[k], &p, NULL);
    p.noise_level = 10;
    p.yarn_width = 0.9;
    wv_yarn_model m;
    assert_int_equal(wv_params_yarn_model(&p, &m, NULL), WV_OK);
    int types[3] = {0, 0, 0};
    for (int i = 0; i < 20000; i++) {
      float x = (float)(i % 141) * 0.0137f - 1.0f, y = (float)(i / 141) * 0.0119f - 0.8f;
      wv_yarn_point yp;
      wv_yarn_eval(&m, x, y, &yp);
      assert_frame(yp.n, yp.t, 3e-6);
      assert_true(yp.n[2] >= 0.0f);
      assert_true(fabsf(yp.u) <= m.umax + 1e-5f);
      assert_true(fabsf(yp.v) <= 1.5708f);
      assert_true(yp.beta >= 0.0f && yp.beta <= 2.0f * p.heightfield[yp.type < 0 ? 0 : yp.type] + 1e-6);
      types[yp.type + 1]++;
    }
    assert_true(types[0] > 0); /* gaps exist with yarn_width < 1 */
    assert_true(types[1] > 0 && types[2] > 0);
  }
}

static void test_noise_per_segment(void **state) {
  (void)state;
  wv_params p;
  wv_params_default("satin", &p, NULL);
  p.noise_level = 5;
  wv_yarn_model m;
  wv_params_yarn_model(&p, &m, NULL);
  /* points on one float share beta; different floats differ */
  wv_yarn_point a, b, c;
  float dx = m.spacing[WV_WARP], dy = m.spacing[WV_WEFT];
  /* cell row 0, column 0 of satin is warp with a float of 4 rows (rows 3,4? wrap) */
  wv_yarn_eval(&m, 0.5f * dx, -0.2f * dy, &a);
  wv_yarn_eval(&m, 0.5f * dx, -1.5f * dy, &b); /* row 1: same float (rows 3,4,0,1) */
  assert_int_equal(a.type, WV_WARP);
  assert_int_equal(a.segment, b.segment);
  assert_true(a.beta == b.beta);
  double lo = 1e9, hi = -1e9;
  for (int j = 0; j < 200; j++) {
    wv_yarn_eval(&m, (0.5f + 5.0f * j) * dx, -0.2f * dy, &c);
    if (c.beta < lo) lo = c.beta;
    if (c.beta > hi) hi = c.beta;
  }
  /* beta_seg = beta (1 + 0.1 Q (2 xi - 1)): spread up to +-50% at Q = 5 */
  assert_true(lo >= 0.5 * p.heightfield[0] - 1e-6 && hi <= 1.5 * p.heightfield[0] + 1e-6);
  assert_true(hi - lo > 0.5 * p.heightfield[0]);
}

/* Light through the cloth: open where neither kind of yarn covers the point, (1 - w)^2 of
 * the fabric; elsewhere it passes the visible yarn, or beside it the crossing one; the
 * thickness is one or two chords of circular cross-sections. */
static void test_open_area(void **state) {
  (void)state;
  const char *pats[] = {"plain", "twill", "satin90"};
  const double widths[] = {1.0, 0.9, 0.6};
  for (int k = 0; k < 3; k++) {
    wv_params p;
    wv_params_default(pats[k], &p, NULL);
    p.yarn_width = widths[k];
    p.density[WV_WARP] = 97, p.density[WV_WEFT] = 61;
    wv_yarn_model m;
    assert_int_equal(wv_params_yarn_model(&p, &m, NULL), WV_OK);
    int n = 0, open = 0, beside = 0;
    for (int i = 0; i < 300; i++)
      for (int j = 0; j < 300; j++) {
        wv_yarn_point yp;
        wv_yarn_eval(&m, (float)(0.01 * i + 0.0013), (float)(-0.01 * j - 0.0007), &yp);
        n++;
        assert_true(yp.open == (yp.through < 0));
        assert_true(yp.thickness >= 0.0f && yp.thickness <= 2.0f);
        if (yp.type >= 0) { /* on a yarn: the light passes it */
          assert_int_equal(yp.through, yp.type);
          assert_true(yp.thickness > 0.0f);
        } else if (!yp.open) { /* beside it: the crossing yarn, one chord */
          assert_true(yp.through >= 0 && yp.thickness > 0.0f && yp.thickness <= 1.0f);
          beside++;
        } else {
          assert_true(yp.thickness == 0.0f);
        }
        open += yp.open;
      }
    double w = widths[k], want = (1 - w) * (1 - w);
    assert_true(fabs((double)open / n - want) < 0.01);
    assert_true(w == 1.0 ? beside == 0 && open == 0 : beside > 0 && open > 0);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_frame_orthonormal),
                                     cmocka_unit_test(test_scale_matches_spec_formula),
                                     cmocka_unit_test(test_eval_everywhere), cmocka_unit_test(test_noise_per_segment),
                                     cmocka_unit_test(test_open_area)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
