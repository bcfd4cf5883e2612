/* SGGX and SpongeCake identities (SPEC section 4), by numerical quadrature. */
#include <math.h>

#include "testutil.h"
#include "woven/brdf.h"

#define PI 3.14159265358979323846

static void unit(float v[3]) {
  float l = sqrtf(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  v[0] /= l, v[1] /= l, v[2] /= l;
}

/* Quadrature over the sphere in (cos theta, phi) about axis t: flakes concentrate
 * around the plane normal to t, so cos theta = m.t gets fine, warped steps. */
typedef double (*sphere_fn)(const float m[3], void *ctx);
static double sphere_integral(const float t[3], sphere_fn f, void *ctx, double alpha, double c0) {
  float a[3] = {1, 0, 0};
  if (fabsf(t[0]) > 0.9f) a[0] = 0, a[1] = 1;
  float e1[3] = {t[1] * a[2] - t[2] * a[1], t[2] * a[0] - t[0] * a[2], t[0] * a[1] - t[1] * a[0]};
  unit(e1);
  float e2[3] = {t[1] * e1[2] - t[2] * e1[1], t[2] * e1[0] - t[0] * e1[2], t[0] * e1[1] - t[1] * e1[0]};
  /* substitution c = c0 + alpha tan(s) puts nodes densely where the integrand
   * peaks (m.t near c0) and covers c in [-1, 1] exactly */
  int ns = 1600, np = 720;
  double sum = 0;
  double smin = atan((-1.0 - c0) / alpha), smax = atan((1.0 - c0) / alpha);
  for (int i = 0; i < ns; i++) {
    double s = smin + (i + 0.5) * (smax - smin) / ns;
    double c = c0 + alpha * tan(s), dc = alpha / (cos(s) * cos(s)) * (smax - smin) / ns;
    double r = sqrt(fmax(0.0, 1 - c * c));
    for (int j = 0; j < np; j++) {
      double phi = (j + 0.5) * 2 * PI / np;
      float m[3];
      for (int k = 0; k < 3; k++) m[k] = (float)(r * cos(phi) * e1[k] + r * sin(phi) * e2[k] + c * t[k]);
      sum += f(m, ctx) * dc * (2 * PI / np);
    }
  }
  return sum;
}

typedef struct {
  const float *t, *w, *wi;
  float alpha;
} ctx_t;

static double projected_area_integrand(const float m[3], void *vc) {
  ctx_t *c = vc;
  double d = wv_dot3(m, c->w);
  return d > 0 ? d * wv_sggx_D(c->t, c->alpha, m) : 0.0;
}

static double phase_integrand(const float wo[3], void *vc) {
  ctx_t *c = vc;
  float h[3] = {c->wi[0] + wo[0], c->wi[1] + wo[1], c->wi[2] + wo[2]};
  float l = sqrtf(wv_dot3(h, h));
  if (l < 1e-9f) return 0;
  h[0] /= l, h[1] /= l, h[2] /= l;
  return wv_sggx_D(c->t, c->alpha, h) / (4 * wv_sggx_sigma(c->t, c->alpha, c->wi));
}

static void test_sggx_projected_area(void **state) {
  (void)state;
  float alphas[] = {0.05f, 0.2f, 0.5f, 1.0f};
  float t[3] = {0.3f, 0.8f, 0.2f};
  unit(t);
  float dirs[][3] = {{0, 0, 1}, {0.7f, 0.1f, 0.7f}, {0.3f, 0.8f, 0.2f}, {-0.5f, 0.2f, 0.84f}};
  for (int a = 0; a < 4; a++)
    for (int d = 0; d < 4; d++) {
      unit(dirs[d]);
      ctx_t c = {t, dirs[d], NULL, alphas[a]};
      double integral = sphere_integral(t, projected_area_integrand, &c, alphas[a], 0.0);
      double sigma = wv_sggx_sigma(t, alphas[a], dirs[d]);
      assert_true(fabs(integral - sigma) < 2e-3 * sigma + 1e-5);
    }
}

static void test_phase_normalised(void **state) {
  (void)state;
  float alphas[] = {0.1f, 0.3f, 0.7f, 1.0f};
  float t[3] = {0.1f, 0.9f, -0.3f};
  unit(t);
  float dirs[][3] = {{0, 0, 1}, {0.6f, -0.2f, 0.77f}, {0.1f, 0.9f, -0.3f}};
  for (int a = 0; a < 4; a++)
    for (int d = 0; d < 3; d++) {
      unit(dirs[d]);
      ctx_t c = {t, NULL, dirs[d], alphas[a]};
      /* over outgoing directions D(h) peaks where h.t = 0, i.e. wo.t = -wi.t */
      double integral = sphere_integral(t, phase_integrand, &c, alphas[a], -wv_dot3(dirs[d], t));
      if (fabs(integral - 1.0) >= 5e-3) print_message("alpha %g dir %d: %g\n", alphas[a], d, integral);
      assert_true(fabs(integral - 1.0) < 5e-3);
    }
}

static void test_specular_symmetric_and_bounded(void **state) {
  (void)state;
  float wm[3] = {0, 0, 1};
  float ts[][3] = {{0, 1, 0}, {0.6f, 0.6f, 0.5f}, {1, 0, 0.2f}};
  float alphas[] = {0.01f, 0.1f, 0.5f, 1.0f};
  float ws[][3] = {{0.2f, 0.1f, 0.97f}, {-0.6f, 0.3f, 0.74f}, {0.1f, -0.95f, 0.3f}, {0.9f, 0.0f, 0.1f}};
  for (int i = 0; i < 3; i++) {
    unit(ts[i]);
    for (int a = 0; a < 4; a++) {
      for (int j = 0; j < 4; j++)
        for (int k = 0; k < 4; k++) {
          unit(ws[j]), unit(ws[k]);
          float f1 = wv_brdf_specular(ts[i], alphas[a], 2.0f, ws[j], ws[k], wm);
          float f2 = wv_brdf_specular(ts[i], alphas[a], 2.0f, ws[k], ws[j], wm);
          assert_true(fabsf(f1 - f2) <= 1e-5f * fabsf(f1) + 1e-12f);
        }
      for (int j = 0; j < 4; j++) {
        double albedo = wv_brdf_specular_albedo(ts[i], alphas[a], 2.0f, ws[j], wm, 400);
        assert_true(albedo >= 0.0);
        assert_true(albedo <= 1.0); /* k_s = 1: energy never created */
      }
    }
  }
}

static void test_specular_below_horizon(void **state) {
  (void)state;
  float wm[3] = {0, 0, 1}, t[3] = {0, 1, 0};
  float up[3] = {0, 0.6f, 0.8f}, down[3] = {0, 0.6f, -0.8f};
  assert_true(wv_brdf_specular(t, 0.3f, 2.0f, up, down, wm) == 0.0f);
  assert_true(wv_brdf_specular(t, 0.3f, 2.0f, down, up, wm) == 0.0f);
  assert_true(wv_brdf_diffuse_cos(t, 0.5f, down, wm) == 0.0f);
  /* diffuse blend: w = 0 is plain Lambert mu_i / pi */
  assert_true(fabsf(wv_brdf_diffuse_cos(t, 0.0f, up, wm) - 0.8f / (float)PI) < 1e-6f);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_sggx_projected_area), cmocka_unit_test(test_phase_normalised),
      cmocka_unit_test(test_specular_symmetric_and_bounded), cmocka_unit_test(test_specular_below_horizon)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
