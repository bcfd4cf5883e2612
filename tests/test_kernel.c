/* The shading kernel (src/kernel/kernel_impl.h): its 8-wide flavour against
 * the scalar one bit for bit (values, open gaps and derivative sums, on yarns,
 * in gaps, with noise and glints, the light in front, behind and both in one
 * vector, and past the 8-wide integer range where lanes fall back to scalar);
 * its derivative sums per sample against central differences of the double
 * flavour, reflected and transmitted; the yarn underneath beside a visible one; the public
 * entry points. */
#include <math.h>
#include <string.h>

#include "kernel/kernel.h"
#include "testutil.h"


/* A random unit vector above the surface (z > 0.05). */
static void above(tu_rng *r, float w[3]) {
  do {
    for (int k = 0; k < 3; k++) w[k] = (float)(2 * tu_rnd(r) - 1);
  } while (w[0] * w[0] + w[1] * w[1] + w[2] * w[2] > 1 || w[2] < 0.05f);
  float l = sqrtf(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
  for (int k = 0; k < 3; k++) w[k] /= l;
}

static void fabric(int k, wv_params *p, wv_fabric *f) {
  static const char *pats[] = {"twill", "satin", "plain", "twill90", "satin90"};
  wv_error err = {0};
  assert_int_equal(wv_params_default(pats[k % 5], p, &err), WV_OK);
  p->noise_level = k % 3 ? 4 : 0;
  p->specular_noise = k % 2;
  p->yarn_width = k % 2 ? 0.8 : 1.0;
  p->twist_deg = -25 + 9 * k;
  p->seed = 11 + k;
  assert_int_equal(wv_fabric_prepare(p, f, &err), WV_OK);
}

static void test_scalar_equals_8wide(void **state) {
  (void)state;
  tu_rng r = {3};
  static wv_fabric f;
  wv_params p;
  int fallbacks = 0, gaps = 0, through = 0, open = 0;
  for (int k = 0; k < 10; k++) {
    fabric(k, &p, &f);
    for (int rep = 0; rep < 200; rep++) {
      wv_dirs_8 d8;
      wv_f8 x, y;
      wv_dirs_f d1[8];
      for (int i = 0; i < 8; i++) {
        float wi[3], wo[3];
        above(&r, wi), above(&r, wo);
        /* the light behind the cloth: in every lane, or in every other lane */
        int below = rep % 3 == 1 || (rep % 3 == 2 && i % 2);
        if (below) wi[2] = -wi[2];
        wv_dirs_make_f(wi, wo, (float)(0.5 + tu_rnd(&r)), &d1[i]);
        for (int c = 0; c < 3; c++) d8.wi[c][i] = d1[i].wi[c], d8.wo[c][i] = d1[i].wo[c], d8.h[c][i] = d1[i].h[c];
        d8.mi[i] = d1[i].mi, d8.mo[i] = d1[i].mo, d8.light[i] = d1[i].light;
        /* mostly near the origin; some far away, past the 8-wide cell range */
        double scale = rep % 17 == 0 && i == 3 ? 3e6 : 40.0;
        x[i] = (float)(scale * (2 * tu_rnd(&r) - 1)), y[i] = (float)(scale * (2 * tu_rnd(&r) - 1));
      }
      wv_f8 rad8[3], open8;
      wv_shade_grad_8 g8;
      wv_shade_ex_8(&f, &f.P, &d8, x, y, rad8, &g8, &open8);
      wv_yarn_cell_8 cell;
      wv_yarn_locate_8(&f.ym, x, y, &cell);
      fallbacks += !wv_all(cell.ok);
      for (int i = 0; i < 8; i++) {
        float rad1[3], open1;
        wv_shade_grad_f g1;
        wv_shade_ex_f(&f, &f.P, &d1[i], x[i], y[i], rad1, &g1, &open1);
        for (int c = 0; c < 3; c++) assert_true(memcmp(&rad1[c], &rad8[c][i], sizeof(float)) == 0);
        assert_true(memcmp(&open1, &open8[i], sizeof(float)) == 0);
        assert_true(open1 == 0.0f || (open1 == 1.0f && d1[i].mi < 0 && rad1[0] == 0.0f));
        through += d1[i].mi < 0 && rad1[0] > 0.0f;
        open += open1 == 1.0f;
        assert_int_equal(g1.warp != 0, g8.warp[i] != 0);
        for (int j = 0; j < WV_J_COUNT; j++) assert_true(memcmp(&g1.J[j], &g8.J[j][i], sizeof(float)) == 0);
        gaps += rad1[0] == 0.0f;
        /* and without the derivatives: the same radiance */
        float rad2[3];
        wv_shade_f(&f, &f.P, &d1[i], x[i], y[i], rad2, NULL);
        assert_true(memcmp(rad1, rad2, sizeof rad1) == 0);
      }
    }
  }
  assert_true(fallbacks > 0 && gaps > 0 && through > 0 && open > 0); /* every path seen */
}

/* Front-lit, beside the visible yarn but over the crossing one, the crossing yarn shows its
 * diffuse lobe with the macro normal, k_d mu_i / pi times the light, and the derivative sums
 * name its yarn type; an open gap reflects nothing. */
static void test_yarn_underneath(void **state) {
  (void)state;
  tu_rng r = {5};
  static wv_fabric f;
  wv_params p;
  wv_error err = {0};
  assert_int_equal(wv_params_default("plain", &p, &err), WV_OK);
  p.yarn_width = 0.7, p.noise_level = 0, p.specular_noise = 0;
  for (int c = 0; c < 3; c++) p.diffuse[WV_WARP][c] = c == 0 ? 0.8 : 0.1, p.diffuse[WV_WEFT][c] = c == 2 ? 0.8 : 0.1;
  assert_int_equal(wv_fabric_prepare(&p, &f, &err), WV_OK);
  int under[2] = {0, 0}, open = 0;
  for (int k = 0; k < 4000; k++) {
    float wi[3], wo[3], rad[3];
    above(&r, wi), above(&r, wo);
    wv_dirs_f d;
    wv_dirs_make_f(wi, wo, 1.0f, &d);
    float x = (float)(4 * tu_rnd(&r)), y = (float)(-4 * tu_rnd(&r));
    wv_yarn_point yp;
    wv_yarn_eval(&f.ym, x, y, &yp);
    if (yp.type >= 0) continue;
    wv_shade_grad_f g;
    wv_shade_f(&f, &f.P, &d, x, y, rad, &g);
    if (yp.open) {
      open++;
      for (int c = 0; c < 3; c++) assert_true(rad[c] == 0.0f);
      continue;
    }
    int t = yp.through;
    under[t]++;
    for (int c = 0; c < 3; c++) {
      double want = d.light * f.P.kd[t][c] * d.mi / 3.14159265358979323846;
      assert_true(fabs(rad[c] - want) <= 1e-5 * want);
    }
    assert_int_equal(g.warp != 0, t == WV_WARP);
    assert_true(fabs(g.J[WV_J_DF] - d.light * d.mi / 3.14159265358979323846) <= 1e-5 * g.J[WV_J_DF]);
    assert_true(g.J[WV_J_S] == 0.0f);
  }
  assert_true(under[WV_WARP] > 50 && under[WV_WEFT] > 50 && open > 20);
}

/* The forward band's normalisation: its mean over a cosine-weighted hemisphere with the light
 * straight behind and the yarn's axis in the plane, against Monte Carlo over that hemisphere
 * (directions as points of the unit disk, s half the axis component). */
static void test_forward_band_mean(void **state) {
  (void)state;
  static const double widths[] = {0.05, 0.1, 0.3, 1.0};
  for (int k = 0; k < 4; k++) {
    tu_rng r = {17};
    double w = widths[k], sum = 0;
    enum { N = 400000 };
    for (int i = 0; i < N; i++) {
      double rad = sqrt(tu_rnd(&r)), phi = 2 * 3.14159265358979323846 * tu_rnd(&r);
      double sh = 0.5 * rad * cos(phi), q = 1 + sh * sh * 0.5 / (w * w);
      sum += 1 / (q * q);
    }
    double mc = sum / N, m = wv_forward_band_mean(w);
    assert_true(fabs(m - mc) < 4e-3 * mc);
    assert_true(m > 0 && m < 1);
  }
  assert_true(wv_forward_band_mean(0.1) < wv_forward_band_mean(0.2)); /* a narrower band covers less */
}

/* Light through the cloth with only k_f: the band, coloured by the yarn the light passes, the
 * cloth's transmittance times |mu_i| g(s) / (pi mean g), s half the component of omega_i +
 * omega_o along that yarn's axis (fabric y for warp, x for weft); 0 in an open gap. */
static void test_forward_band(void **state) {
  (void)state;
  tu_rng r = {9};
  static wv_fabric f;
  wv_params p;
  wv_error err = {0};
  assert_int_equal(wv_params_default("twill", &p, &err), WV_OK);
  p.yarn_width = 0.75, p.noise_level = 0, p.specular_noise = 0, p.forward_width = 0.25;
  memset(p.transmission, 0, sizeof p.transmission);
  memset(p.transmission_specular, 0, sizeof p.transmission_specular);
  for (int c = 0; c < 3; c++)
    p.transmission_forward[WV_WARP][c] = c == 0 ? 0.9 : 0.2, p.transmission_forward[WV_WEFT][c] = c == 1 ? 0.7 : 0.1;
  assert_int_equal(wv_fabric_prepare(&p, &f, &err), WV_OK);
  double norm = 1 / wv_forward_band_mean(p.forward_width), peak[2] = {0, 0};
  int seen[2] = {0, 0}, open = 0;
  for (int k = 0; k < 4000; k++) {
    float wi[3], wo[3], rad[3];
    above(&r, wi), above(&r, wo);
    wi[2] = -wi[2]; /* the light behind */
    wv_dirs_f d;
    wv_dirs_make_f(wi, wo, 1.0f, &d);
    float x = (float)(4 * tu_rnd(&r)), y = (float)(-4 * tu_rnd(&r));
    wv_yarn_point yp;
    wv_yarn_eval(&f.ym, x, y, &yp);
    wv_shade_grad_f g;
    wv_shade_f(&f, &f.P, &d, x, y, rad, &g);
    if (yp.open) {
      open++;
      for (int c = 0; c < 3; c++) assert_true(rad[c] == 0.0f);
      continue;
    }
    int t = yp.through;
    double sh = 0.5 * (t == WV_WARP ? d.wi[1] + d.wo[1] : d.wi[0] + d.wo[0]);
    double q = 1 + sh * sh * 0.5 / (p.forward_width * p.forward_width);
    double band = -d.mi * (1.0 / (1.0 + 0.5 * p.thickness * yp.thickness)) * norm / 3.14159265358979323846 / (q * q);
    for (int c = 0; c < 3; c++) {
      double want = d.light * p.transmission_forward[t][c] * band;
      assert_true(fabs(rad[c] - want) <= 1e-4 * want + 1e-7);
    }
    assert_int_equal(g.warp != 0, t == WV_WARP);
    assert_true(fabs(g.J[WV_J_F] - d.light * band) <= 1e-4 * d.light * band + 1e-7);
    seen[t]++;
    if (band > peak[t]) peak[t] = band;
  }
  assert_true(seen[WV_WARP] > 500 && seen[WV_WEFT] > 500 && open > 20);
}

/* The public entry points agree with each other and with the directions' horizon rule. */
static void test_entry_points(void **state) {
  (void)state;
  tu_rng r = {8};
  static wv_fabric f;
  wv_params p;
  fabric(3, &p, &f);
  float x[8], y[8], wi[3][8], wo[3][8], out8[3][8];
  for (int i = 0; i < 8; i++) {
    float a[3], b[3];
    above(&r, a), above(&r, b);
    if (i == 5) a[2] = -a[2]; /* light below the surface */
    for (int c = 0; c < 3; c++) wi[c][i] = a[c], wo[c][i] = b[c];
    x[i] = (float)(10 * tu_rnd(&r)), y[i] = (float)(-10 * tu_rnd(&r));
  }
  wv_kernel_shade8(&f, x, y, (const float(*)[8])wi, (const float(*)[8])wo, out8);
  int lit = 0;
  for (int i = 0; i < 8; i++) {
    float a[3] = {wi[0][i], wi[1][i], wi[2][i]}, b[3] = {wo[0][i], wo[1][i], wo[2][i]}, out[3];
    wv_kernel_shade(&f, x[i], y[i], a, b, out);
    for (int c = 0; c < 3; c++) assert_true(memcmp(&out[c], &out8[c][i], sizeof(float)) == 0);
    if (i == 5) assert_true(out[0] == 0.0f && out[1] == 0.0f && out[2] == 0.0f);
    lit += out[0] > 0.0f;
  }
  assert_true(lit >= 4);
}

/* d J / d theta of one sample: the double kernel's sums against central
 * differences of its own S and DF, for every non-linear parameter. */
/* The scalar integer floor: exact within the 64-bit range, clamped beyond it and for
 * NaN (a conversion out of range would be undefined; the sanitizer build traps it). */
static void test_floori_range(void **state) {
  (void)state;
  assert_true(wv_floori_f(-2.5f) == -3 && wv_floori_f(2.5f) == 2 && wv_floori_f(-3.0f) == -3);
  assert_true(wv_floori_f(1e18f) == (int64_t)1e18f);
  assert_true(wv_floori_f(1e20f) == (int64_t)4.0e18f && wv_floori_f(-1e20f) == (int64_t)-4.0e18f);
  assert_true(wv_floori_f(INFINITY) == (int64_t)4.0e18f && wv_floori_f(NAN) == (int64_t)-4.0e18f);
}

static void test_sample_derivatives(void **state) {
  (void)state;
  tu_rng r = {21};
  static wv_fabric f;
  wv_params p;
  int checked = 0, through = 0;
  for (int k = 0; k < 6; k++) {
    fabric(k, &p, &f);
    for (int rep = 0; rep < 120; rep++) {
      float wi[3], wo[3];
      above(&r, wi), above(&r, wo);
      if (rep % 2) wi[2] = -wi[2]; /* the light behind the cloth: the transmission */
      wv_dirs_f df;
      wv_dirs_make_f(wi, wo, 1.0f, &df);
      wv_dirs_d d;
      for (int c = 0; c < 3; c++) d.wi[c] = df.wi[c], d.wo[c] = df.wo[c], d.h[c] = df.h[c];
      d.mi = df.mi, d.mo = df.mo, d.light = 1.0;
      float x = (float)(20 * tu_rnd(&r)), y = (float)(-20 * tu_rnd(&r));
      wv_shade_params_d P;
      wv_shade_params_double(&p, &P);
      double rad[3];
      wv_shade_grad_d g;
      wv_shade_d(&f, &P, &d, x, y, rad, &g);
      if (g.J[WV_J_DF] == 0.0) continue; /* a gap */
      through += d.mi < 0;
      int ty = g.warp ? WV_WARP : WV_WEFT;
      /* parameter, slot of S's derivative, slot of DF's derivative (-1: none) */
      struct {
        double *v;
        double scale;
        int js, jd;
      } ps[] = {{&p.heightfield[ty], 1, WV_J_S_BETA, WV_J_DF_BETA},
                {&p.roughness[ty], 1, WV_J_S_ALPHA, -1},
                {&p.inclination_deg, 3.14159265358979323846 / 180, WV_J_S_UMAX, WV_J_DF_UMAX},
                {&p.twist_deg, 3.14159265358979323846 / 180, WV_J_S_PSI, -1},
                {&p.diffuse_blend, 1, -1, WV_J_DF_BLEND}};
      for (size_t q = 0; q < sizeof ps / sizeof ps[0]; q++) {
        double v0 = *ps[q].v, h = 1e-6 * (fabs(v0) + 0.1), J[2][2];
        for (int side = 0; side < 2; side++) {
          *ps[q].v = v0 + (side ? h : -h);
          wv_shade_params_double(&p, &P);
          double rr[3];
          wv_shade_grad_d gg;
          wv_shade_d(&f, &P, &d, x, y, rr, &gg);
          J[side][0] = gg.J[WV_J_S], J[side][1] = gg.J[WV_J_DF];
        }
        *ps[q].v = v0;
        for (int which = 0; which < 2; which++) {
          int slot = which ? ps[q].jd : ps[q].js;
          double fd = (J[1][which] - J[0][which]) / (2 * h) / ps[q].scale;
          double an = slot < 0 ? 0.0 : g.J[slot];
          double tol = 1e-5 * (fabs(fd) + fabs(an)) + 1e-7 * (fabs(g.J[which ? WV_J_DF : WV_J_S]) + 1e-3);
          if (fabs(fd - an) > tol)
            print_error("fabric %d param %zu %s: analytic %.9g finite difference %.9g\n", k, q, which ? "DF" : "S", an,
                        fd);
          assert_true(fabs(fd - an) <= tol);
          checked++;
        }
      }
      wv_shade_params_double(&p, &P);
    }
  }
  assert_true(checked > 2000 && through > 200);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_scalar_equals_8wide), cmocka_unit_test(test_yarn_underneath),
                                     cmocka_unit_test(test_forward_band_mean), cmocka_unit_test(test_forward_band),
                                     cmocka_unit_test(test_entry_points),
                                     cmocka_unit_test(test_sample_derivatives), cmocka_unit_test(test_floori_range)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
