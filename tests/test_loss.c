/* The image losses of include/woven/loss.h: the structure loss's gradient against
 * finite differences, and what it is for: a shifted weave costs little, a blurred or an
 * erased one a lot, a change of contrast nothing. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"
#include "woven/imgops.h"
#include "woven/loss.h"
#include "woven/nn.h"
#include "woven/render.h"

static const double PI = 3.14159265358979323846;

/* A woven-looking test image: diagonal ribs of period 6 px, finer threads, noise. */
static void ribs(wv_image *img, int w, int h, double phase, double contrast, uint64_t seed) {
  wv_error e;
  assert_int_equal(wv_image_alloc(img, w, h, 3, &e), WV_OK);
  wv_rng r;
  wv_rng_seed(&r, seed);
  for (int y = 0; y < h; y++)
    for (int x = 0; x < w; x++) {
      double v = 0.4 + contrast * (0.15 * sin(2 * PI * (x + y + phase) / 6.0) + 0.05 * sin(2 * PI * x / 2.5)) +
                 0.02 * (wv_rng_uniform(&r) - 0.5);
      float *c = wv_image_px(img, x, y);
      c[0] = (float)(0.9 * v), c[1] = (float)v, c[2] = (float)(0.7 * v);
    }
}

static void test_spectrum_gradient(void **state) {
  (void)state;
  wv_image photo, img, d;
  wv_error e;
  ribs(&photo, 40, 36, 0, 1, 1);
  ribs(&img, 40, 36, 2.3, 0.6, 2);
  /* something the photo lacks, so the loss and its gradient are far from zero */
  for (int y = 0; y < 36; y++)
    for (int x = 0; x < 40; x++) wv_image_px(&img, x, y)[1] += 0.05f * (float)sin(2 * PI * x / 4.0);
  wv_spectrum_loss *s;
  assert_int_equal(wv_spectrum_loss_create(&photo, &s, &e), WV_OK);
  assert_int_equal(wv_image_alloc(&d, 40, 36, 3, &e), WV_OK);
  memset(d.data, 0, sizeof(float) * 40 * 36 * 3);
  const float wt = 1.5f;
  double l0 = wv_spectrum_loss_eval(s, &img, &d, wt);
  assert_true(l0 > 0.05);
  double gmax = 0;
  for (size_t i = 0; i < 40 * 36 * 3; i++) gmax = fmax(gmax, fabs(d.data[i]));
  double worst = 0;
  int checked = 0;
  for (size_t i = 7; i < 40 * 36 * 3; i += 37) {
    float save = img.data[i], h = 2e-3f;
    img.data[i] = save + h;
    double fp = wv_spectrum_loss_eval(s, &img, NULL, 0);
    img.data[i] = save - h;
    double fm = wv_spectrum_loss_eval(s, &img, NULL, 0);
    img.data[i] = save;
    double num = wt * (fp - fm) / (2 * h), an = d.data[i];
    double err = fabs(num - an) / (fabs(num) + fabs(an) + 0.05 * gmax);
    if (err > 0.05) fprintf(stderr, "pixel value %zu: analytic %g, numeric %g\n", i, an, num);
    worst = fmax(worst, err);
    checked++;
  }
  fprintf(stderr, "structure loss %.4f: %d gradient entries, worst relative error %.2e\n", l0, checked, worst);
  assert_true(worst < 0.05);
  /* d accumulates: a second evaluation adds the same again */
  float first = d.data[100];
  wv_spectrum_loss_eval(s, &img, &d, wt);
  assert_true(fabsf(d.data[100] - 2 * first) <= 1e-5f * fabsf(first) + 1e-12f);
  wv_spectrum_loss_free(s);
  wv_image_free(&photo), wv_image_free(&img), wv_image_free(&d);
}

/* Rendered twill: the photo; the same fabric shifted, blurred, flattened, rescaled. */
static void test_spectrum_erasing_costs(void **state) {
  (void)state;
  wv_scene sc;
  tu_centre_window(&sc, "flat45", 128, 128, 16);
  wv_params p;
  wv_error e;
  assert_int_equal(wv_params_sample_prior("twill21z", 3, &p, &e), WV_OK);
  p.density[0] = 140, p.density[1] = 90;
  wv_render_opts ro = {0, 0, NULL, NULL, NULL};
  wv_image photo, shifted, blurred, flat, dim;
  assert_int_equal(wv_render(&sc, &p, &ro, &photo, NULL, &e), WV_OK);
  sc.fabric_offset[0] += 0.37, sc.fabric_offset[1] -= 0.21; /* another phase of the weave */
  p.seed += 1;                                             /* and another noise draw */
  assert_int_equal(wv_render(&sc, &p, &ro, &shifted, NULL, &e), WV_OK);
  assert_int_equal(wv_image_blur(&shifted, 1.5, &blurred, &e), WV_OK);
  assert_int_equal(wv_image_blur(&shifted, 0, &flat, &e), WV_OK);
  assert_int_equal(wv_image_blur(&shifted, 0, &dim, &e), WV_OK);
  double mean = wv_image_mean(&shifted);
  for (size_t i = 0; i < (size_t)128 * 128 * 3; i++) {
    flat.data[i] = (float)(mean + 0.05 * (flat.data[i] - mean)); /* the weave almost erased */
    dim.data[i] = (float)(0.2 + 0.5 * dim.data[i]);               /* other contrast and level */
  }
  wv_spectrum_loss *s;
  assert_int_equal(wv_spectrum_loss_create(&photo, &s, &e), WV_OK);
  double ls = wv_spectrum_loss_eval(s, &shifted, NULL, 0), lb = wv_spectrum_loss_eval(s, &blurred, NULL, 0);
  double lf = wv_spectrum_loss_eval(s, &flat, NULL, 0), ld = wv_spectrum_loss_eval(s, &dim, NULL, 0);
  double lp = wv_spectrum_loss_eval(s, &photo, NULL, 0);
  fprintf(stderr, "structure loss: itself %.4f, shifted %.4f, rescaled %.4f, blurred %.4f, nearly flat %.4f\n", lp,
          ls, ld, lb, lf);
  assert_true(lp < 1e-9);
  assert_true(fabs(ld - ls) < 0.05 * ls + 1e-3); /* contrast and level do not matter */
  assert_true(lb > 3 * ls);                      /* blur erases the weave's fine frequencies */
  /* A nearly flat copy keeps the spectrum's shape (P / E is blind to contrast), but a
   * render always carries sampling noise: against it the erased weave's peaks vanish. */
  wv_rng r;
  wv_rng_seed(&r, 5);
  for (size_t i = 0; i < (size_t)128 * 128 * 3; i++) flat.data[i] += 0.01f * (wv_rng_uniform(&r) - 0.5f);
  double lq = wv_spectrum_loss_eval(s, &flat, NULL, 0);
  fprintf(stderr, "structure loss: nearly flat with render noise %.4f\n", lq);
  assert_true(lq > 3 * ls);
  wv_spectrum_loss_free(s);
  wv_image_free(&photo), wv_image_free(&shifted), wv_image_free(&blurred), wv_image_free(&flat), wv_image_free(&dim);
}

static void test_gram_loss(void **state) {
  (void)state;
  const float a[4] = {1, 2, 3, 4}, b[4] = {1, 3, 2, 5};
  float d[4];
  assert_true(fabs(wv_loss_gram(a, b, 4, d) - 0.75) < 1e-12);
  assert_true(d[0] == 0 && d[1] == -0.25f && d[2] == 0.25f && d[3] == -0.25f);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_spectrum_gradient),
      cmocka_unit_test(test_spectrum_erasing_costs),
      cmocka_unit_test(test_gram_loss),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
