/* What a capture says about itself (src/capture/report.c): the photo's blurred-copy SSIM,
 * the flag of a fit that scores below it, the report's warning, and the pattern choice's
 * runner-up families in the report. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"
#include "woven/io.h"
#include "woven/metrics.h"
#include "woven/report.h"

/* A photo with pixel-scale detail (a two-pixel check over a smooth ramp, a little noise). */
static void photo_of_checks(wv_image *img) {
  wv_error e = {0};
  tu_rng r = {7};
  assert_int_equal(wv_image_alloc(img, 96, 96, 3, &e), WV_OK);
  for (int y = 0; y < img->h; y++)
    for (int x = 0; x < img->w; x++) {
      float *p = wv_image_px(img, x, y);
      double v = 0.3 + 0.3 * x / img->w + (((x / 2) + (y / 2)) % 2 ? 0.2 : 0.0) + 0.05 * tu_rnd(&r);
      p[0] = (float)v, p[1] = (float)(0.8 * v), p[2] = (float)(0.6 * v);
    }
}

static wv_status write_views(const char *dir, const wv_image *photo, const wv_image *fit, wv_weave_views *v) {
  wv_error e = {0};
  return wv_weave_views_write(dir, photo, fit, fit, v, &e);
}

/* The blurred copy is measured once (wv_blurred_copy_ssim), and a fit that loses the weave
 * (a flat mean colour) scores below it; the photo itself does not. The photo's periodic share
 * is measured with it. */
static void test_below_blurred_copy(void **state) {
  (void)state;
  const char *dir = tu_tmpdir("capture_views");
  wv_error e = {0};
  wv_image photo, flat;
  photo_of_checks(&photo);
  assert_int_equal(wv_image_alloc(&flat, photo.w, photo.h, 3, &e), WV_OK);
  double mean[3] = {0, 0, 0};
  size_t np = (size_t)photo.w * photo.h;
  for (size_t i = 0; i < np; i++)
    for (int c = 0; c < 3; c++) mean[c] += photo.data[3 * i + c] / (double)np;
  for (size_t i = 0; i < np; i++)
    for (int c = 0; c < 3; c++) flat.data[3 * i + c] = (float)mean[c];
  double base;
  assert_int_equal(wv_blurred_copy_ssim(&photo, WV_BLURRED_COPY_SIGMA, &base, &e), WV_OK);
  assert_true(base > 0 && base < 1);
  wv_weave_views v;
  assert_int_equal(write_views(dir, &photo, &flat, &v), WV_OK);
  assert_true(fabs(v.ssim_rgb_blurred - base) < 1e-12);
  assert_true(v.ssim_rgb[1] < base);
  assert_true(v.below_blurred_copy);
  /* the checks' detail is all periodic */
  fprintf(stderr, "periodic share of the checks: %.3f\n", v.periodic_share);
  assert_true(v.periodic_share > 0.9 && v.periodic_share <= 1);
  assert_int_equal(write_views(dir, &photo, &photo, &v), WV_OK);
  assert_true(fabs(v.ssim_rgb[1] - 1) < 1e-9);
  assert_false(v.below_blurred_copy);
  wv_image_free(&photo), wv_image_free(&flat);
}

static int contains(const char *path, const char *text) {
  char *data;
  size_t len;
  wv_error e = {0};
  assert_int_equal(wv_read_file(path, &data, &len, &e), WV_OK);
  int found = strstr(data, text) != NULL;
  free(data);
  return found;
}

/* A report's files in a fresh folder NAME: the photo (a check pattern) written to png, the
 * report's path in html, and satin5's default parameters for start and fit. */
static void report_files(const char *name, char png[4096], char html[4096], wv_params *p) {
  const char *dir = tu_tmpdir(name);
  wv_error e = {0};
  wv_image photo;
  photo_of_checks(&photo);
  snprintf(png, 4096, "%s/photo.png", dir);
  snprintf(html, 4096, "%s/report.html", dir);
  assert_int_equal(wv_image_write_png(png, &photo, 8, &e), WV_OK);
  wv_image_free(&photo);
  assert_int_equal(wv_params_default("satin5", p, &e), WV_OK);
}

/* The report warns of a fit below the blurred copy, shows the baseline and the photo's
 * periodic share, and lists the families of the pattern choice with their candidates and
 * scores. */
static void test_report_says_unsure(void **state) {
  (void)state;
  wv_error e = {0};
  char png[4096], html[4096];
  wv_params p;
  report_files("capture_report", png, html, &p);
  static wv_pattern_choice c; /* no lattice, the network decided: satin first, twill the runner-up */
  memset(&c, 0, sizeof c);
  c.method = "network", c.has_prob = 1;
  int satin5 = -1, twill21s = -1;
  for (int i = 0; i < wv_weave_builtin_count(); i++) {
    c.prob[i] = 0.01;
    if (!strcmp(wv_weave_builtin_name(i), "satin5")) satin5 = i;
    if (!strcmp(wv_weave_builtin_name(i), "twill21s")) twill21s = i;
  }
  c.prob[satin5] = 0.52, c.prob[twill21s] = 0.31, c.best = satin5;
  snprintf(c.lattice.reason, sizeof c.lattice.reason, "no weave lattice (test)");
  wv_weave_views v = {.ssim_rgb = {0.30, 0.35}, .wsc = {-2, -2}, .wsc_whitened = {-2, -2},
                      .ssim_rgb_blurred = 0.61, .below_blurred_copy = 1, .periodic_share = 0.075};
  wv_report r = {.title = "test", .photo_png = png, .start_png = png, .fit_png = png, .start_label = "network",
                 .start = &p, .fit = &p, .descriptor = "default", .pattern_choice = &c, .weave = &v};
  assert_int_equal(wv_report_write_html(html, &r, &e), WV_OK);
  assert_true(contains(html, "Warning: an unsure capture."));
  assert_true(contains(html, "(0.6100)"));
  assert_true(contains(html, "the fit scores below it"));
  /* how much of the photo is weave, and what the rest is */
  assert_true(contains(html, "8% lies in the peaks of its spectrum"));
  assert_true(contains(html, "<td colspan=\"2\">7.5%</td>"));
  /* the runner-up family, its candidate and its score, and how far behind it is */
  assert_true(contains(html, "<tr><td><b>satin</b></td><td><b>satin5</b></td><td>0.5200</td><td>0.0000</td></tr>"));
  assert_true(contains(html, "<tr><td>twill</td><td>twill21s</td><td>0.3100</td><td>0.2100</td></tr>"));
  /* above the blurred copy: no warning, the baseline still shown */
  v.ssim_rgb[1] = 0.7, v.below_blurred_copy = 0;
  assert_int_equal(wv_report_write_html(html, &r, &e), WV_OK);
  assert_false(contains(html, "Warning: an unsure capture."));
  assert_false(contains(html, "lies in the peaks of its spectrum"));
  assert_true(contains(html, "copy blurred by 4 px, the baseline"));
}

/* A pair's back-lit re-render below its photo's blurred copy: the report warns in the
 * transmission section and gives the back-lit photo's periodic share; above it, no warning. */
static void test_report_says_unsure_t(void **state) {
  (void)state;
  wv_error e = {0};
  char png[4096], html[4096];
  wv_params p;
  report_files("capture_report_t", png, html, &p);
  wv_report r = {.title = "test", .photo_png = png, .start_png = png, .fit_png = png, .start_label = "network",
                 .start = &p, .fit = &p, .descriptor = "default", .photo_t_png = png, .fit_t_png = png,
                 .ssim_rgb_t = 0.7845, .wsc_t = 0.27, .ssim_rgb_blurred_t = 0.8237, .periodic_share_t = 0.015,
                 .below_blurred_copy_t = 1};
  assert_int_equal(wv_report_write_html(html, &r, &e), WV_OK);
  assert_true(contains(html, "Warning: the back-lit re-render is unsure."));
  assert_true(contains(html, "(0.8237). Of the back-lit photo's detail, 2% lies in the peaks"));
  assert_true(contains(html, "<td>0.8237 <b style=\"color:#c00\">(the fit scores below it)</b></td>"));
  assert_true(contains(html, "<td>1.5%</td>"));
  assert_false(contains(html, "Warning: an unsure")); /* the reflection side has no figures here */
  r.ssim_rgb_t = 0.85, r.below_blurred_copy_t = 0, r.periodic_share_t = -2;
  assert_int_equal(wv_report_write_html(html, &r, &e), WV_OK);
  assert_false(contains(html, "the back-lit re-render is unsure"));
  assert_false(contains(html, "(the fit scores below it)"));
  assert_false(contains(html, "<td>1.5%</td>"));
  assert_true(contains(html, "<td>0.8237</td>"));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_below_blurred_copy),
      cmocka_unit_test(test_report_says_unsure),
      cmocka_unit_test(test_report_says_unsure_t),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
