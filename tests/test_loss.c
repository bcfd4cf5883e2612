/* The image losses of include/woven/loss.h: the structure and detail-colour losses'
 * gradients against finite differences, and what they are for: a shifted weave costs
 * little, a blurred or an erased one a lot, a change of contrast nothing; hues on the
 * yarns that the photo's detail lacks cost, and so do two colours merged into one. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"
#include "woven/descriptor.h"
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

/* Worst relative error of d (weight wt times a loss's gradient) against central
 * differences of loss(img) at every step-th value from start; counts them in *checked. */
typedef double (*loss_fn)(void *ctx, const wv_image *img);
static double gradient_error(wv_image *img, const wv_image *d, float wt, size_t start, size_t step, float h,
                             loss_fn loss, void *ctx, int *checked) {
  size_t n = (size_t)img->w * img->h * 3;
  double gmax = 0, worst = 0;
  for (size_t i = 0; i < n; i++) gmax = fmax(gmax, fabs(d->data[i]));
  *checked = 0;
  for (size_t i = start; i < n; i += step) {
    float save = img->data[i];
    img->data[i] = save + h;
    double fp = loss(ctx, img);
    img->data[i] = save - h;
    double fm = loss(ctx, img);
    img->data[i] = save;
    double num = wt * (fp - fm) / (2 * h), an = d->data[i];
    double err = fabs(num - an) / (fabs(num) + fabs(an) + 0.05 * gmax);
    if (err > 0.02) fprintf(stderr, "pixel value %zu: analytic %g, numeric %g\n", i, an, num);
    worst = fmax(worst, err);
    (*checked)++;
  }
  return worst;
}

static double spectrum_loss(void *ctx, const wv_image *img) { return wv_spectrum_loss_eval(ctx, img, NULL, 0); }

static double colour_loss(void *ctx, const wv_image *img) {
  double v = -1;
  wv_error e;
  assert_int_equal(wv_colour_loss_eval(ctx, img, NULL, 0, &v, &e), WV_OK);
  return v;
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
  int checked;
  double worst = gradient_error(&img, &d, wt, 7, 37, 2e-3f, spectrum_loss, s, &checked);
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
  wv_render_opts ro = {0};
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

/* Threads of two colours ca and cb alternating every 2 px along x over ribs of period 6:
 * the detail moves along ca - cb (and along the light, by the ribs). */
static void two_colour(wv_image *img, int w, int h, const double ca[3], const double cb[3], double phase,
                       uint64_t seed) {
  wv_error e;
  assert_int_equal(wv_image_alloc(img, w, h, 3, &e), WV_OK);
  wv_rng r;
  wv_rng_seed(&r, seed);
  for (int y = 0; y < h; y++)
    for (int x = 0; x < w; x++) {
      const double *c = ((x + (int)phase) / 2) % 2 ? ca : cb;
      double v = 1 + 0.2 * sin(2 * PI * (x + y + phase) / 6.0);
      float *p = wv_image_px(img, x, y);
      for (int k = 0; k < 3; k++) p[k] = (float)(c[k] * v + 0.01 * (wv_rng_uniform(&r) - 0.5));
    }
}

static void test_colour_gradient(void **state) {
  (void)state;
  wv_image photo, img, d;
  wv_error e;
  ribs(&photo, 40, 36, 0, 1, 1);
  const double ca[3] = {0.6, 0.3, 0.2}, cb[3] = {0.3, 0.5, 0.6};
  two_colour(&img, 40, 36, ca, cb, 1, 2);
  wv_colour_loss *c;
  assert_int_equal(wv_colour_loss_create(&photo, &c, &e), WV_OK);
  assert_int_equal(wv_image_alloc(&d, 40, 36, 3, &e), WV_OK);
  memset(d.data, 0, sizeof(float) * 40 * 36 * 3);
  const float wt = 0.7f;
  double l0;
  assert_int_equal(wv_colour_loss_eval(c, &img, &d, wt, &l0, &e), WV_OK);
  assert_true(l0 > 0.05);
  int checked;
  double worst = gradient_error(&img, &d, wt, 5, 29, 1e-3f, colour_loss, c, &checked);
  fprintf(stderr, "detail-colour loss %.4f: %d gradient entries, worst relative error %.2e\n", l0, checked, worst);
  assert_true(worst < 0.02);
  /* the crop's edge pixels (outside the blur's reach of the interior) get no gradient */
  assert_true(d.data[0] == 0.0f && d.data[3 * (40 * 36 - 1)] == 0.0f);
  wv_colour_loss_free(c);
  wv_image_free(&photo), wv_image_free(&img), wv_image_free(&d);
}

static void test_colour_what_it_sees(void **state) {
  (void)state;
  wv_image grey, grey2, split, denim, denim2, merged;
  wv_error e;
  const double olive[3] = {0.45, 0.5, 0.3}, pink[3] = {0.6, 0.4, 0.35}, green[3] = {0.3, 0.6, 0.25};
  const double blue[3] = {0.05, 0.1, 0.35}, white[3] = {0.8, 0.78, 0.72};
  two_colour(&grey, 64, 64, olive, olive, 0, 1);       /* one colour: light and shade */
  two_colour(&grey2, 64, 64, olive, olive, 3, 2);      /* another phase and noise draw */
  for (size_t i = 0; i < (size_t)64 * 64 * 3; i++) grey2.data[i] = 0.5f * grey2.data[i] + 0.1f; /* other contrast */
  two_colour(&split, 64, 64, pink, green, 0, 3);      /* its mean colour, but hues on the yarns */
  two_colour(&denim, 64, 64, blue, white, 0, 4);
  two_colour(&denim2, 64, 64, white, blue, 3, 5);     /* the colours on the other yarns */
  double mid[3];
  for (int k = 0; k < 3; k++) mid[k] = 0.5 * (blue[k] + white[k]);
  two_colour(&merged, 64, 64, mid, mid, 0, 6);        /* denim's mean colour on both */
  wv_colour_loss *cg, *cd;
  assert_int_equal(wv_colour_loss_create(&grey, &cg, &e), WV_OK);
  assert_int_equal(wv_colour_loss_create(&denim, &cd, &e), WV_OK);
  double same, hues, other, m;
  assert_int_equal(wv_colour_loss_eval(cg, &grey2, NULL, 0, &same, &e), WV_OK);
  assert_int_equal(wv_colour_loss_eval(cg, &split, NULL, 0, &hues, &e), WV_OK);
  assert_int_equal(wv_colour_loss_eval(cd, &denim2, NULL, 0, &other, &e), WV_OK);
  assert_int_equal(wv_colour_loss_eval(cd, &merged, NULL, 0, &m, &e), WV_OK);
  fprintf(stderr, "detail-colour loss: one colour vs itself rescaled %.5f, vs hues on the yarns %.4f; "
                  "denim vs its colours swapped %.5f, vs merged %.4f\n", same, hues, other, m);
  assert_true(same < 0.01 && other < 0.01);
  assert_true(hues > 20 * same + 0.05 && m > 20 * other + 0.05);
  /* a flat card has no detail colour to match: no cost, no gradient */
  wv_image card, dc;
  assert_int_equal(wv_image_alloc(&card, 64, 64, 3, &e), WV_OK);
  assert_int_equal(wv_image_alloc(&dc, 64, 64, 3, &e), WV_OK);
  for (size_t i = 0; i < (size_t)64 * 64 * 3; i++) card.data[i] = 0.5f, dc.data[i] = 0;
  wv_colour_loss *cc;
  assert_int_equal(wv_colour_loss_create(&card, &cc, &e), WV_OK);
  double lc = -1;
  assert_int_equal(wv_colour_loss_eval(cc, &split, &dc, 1.0f, &lc, &e), WV_OK);
  assert_true(lc == 0.0);
  for (size_t i = 0; i < (size_t)64 * 64 * 3; i++) assert_true(dc.data[i] == 0.0f);
  wv_colour_loss_free(cc);
  wv_image_free(&card), wv_image_free(&dc);
  wv_colour_loss_free(cg), wv_colour_loss_free(cd);
  wv_image_free(&grey), wv_image_free(&grey2), wv_image_free(&split), wv_image_free(&denim), wv_image_free(&denim2),
      wv_image_free(&merged);
}

static void test_gram_loss(void **state) {
  (void)state;
  const float a[4] = {1, 2, 3, 4}, b[4] = {1, 3, 2, 5};
  float d[4];
  assert_true(fabs(wv_loss_gram(a, b, 4, d) - 0.75) < 1e-12);
  assert_true(d[0] == 0 && d[1] == -0.25f && d[2] == 0.25f && d[3] == -0.25f);
}

/* The gradient after a value taken without it (wv_image_loss_grad) is the one the evaluation
 * with it gives, bit for bit; for a render other than the one last evaluated it fails. */
static void test_image_loss_grad_later(void **state) {
  (void)state;
  wv_image photo, img, other, d1, d2;
  wv_error e;
  ribs(&photo, 64, 48, 0, 1, 1);
  ribs(&img, 64, 48, 2, 0.6, 2);
  ribs(&other, 64, 48, 1, 0.8, 3);
  wv_descriptor *desc;
  assert_int_equal(wv_descriptor_create_default(&desc, &e), WV_OK);
  wv_loss_weights w = {.w_pixel = 0.2, .w_struct = 0.05, .w_colour = 0.1, .down_w = 8, .down_h = 4};
  wv_image_loss *l;
  assert_int_equal(wv_image_loss_create(&photo, desc, NULL, &w, &l, &e), WV_OK);
  assert_int_equal(wv_image_alloc(&d1, 64, 48, 3, &e), WV_OK);
  assert_int_equal(wv_image_alloc(&d2, 64, 48, 3, &e), WV_OK);
  wv_loss_terms t1, t2;
  assert_int_equal(wv_image_loss_eval(l, &img, &t1, &d1, &e), WV_OK);
  /* another render's value in between, then this one's without and its gradient after */
  assert_int_equal(wv_image_loss_eval(l, &other, &t2, NULL, &e), WV_OK);
  assert_int_equal(wv_image_loss_grad(l, &img, &d2, &e), WV_ERR_INVALID);
  assert_int_equal(wv_image_loss_eval(l, &img, &t2, NULL, &e), WV_OK);
  assert_true(t1.total == t2.total && t1.total > 0);
  assert_int_equal(wv_image_loss_grad(l, &img, &d2, &e), WV_OK);
  size_t n = (size_t)64 * 48 * 3, nonzero = 0;
  for (size_t i = 0; i < n; i++) {
    assert_true(d1.data[i] == d2.data[i]);
    nonzero += d1.data[i] != 0.0f;
  }
  assert_true(nonzero > n / 2);
  wv_image_loss_free(l);
  wv_descriptor_free(desc);
  wv_image_free(&photo), wv_image_free(&img), wv_image_free(&other), wv_image_free(&d1), wv_image_free(&d2);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_spectrum_gradient),
      cmocka_unit_test(test_spectrum_erasing_costs),
      cmocka_unit_test(test_gram_loss),
      cmocka_unit_test(test_image_loss_grad_later),
      cmocka_unit_test(test_colour_gradient),
      cmocka_unit_test(test_colour_what_it_sees),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
