/* SSIM against reference values from scikit-image.
 * The values below were computed once with scikit-image 0.19.3 (Debian package
 * python3-skimage) by tests/reference/ssim_reference.py:
 * structural_similarity(a, b, gaussian_weights=True, sigma=1.5,
 * use_sample_covariance=False, data_range=1.0) on the same synthetic images,
 * on luminance (Rec. 709 weights) and per channel (channel_axis=2). */
#include <math.h>
#include <stdio.h>

#include "testutil.h"
#include "woven/metrics.h"

static void make(wv_image *a, wv_image *b, wv_image *d) {
  int W = 40, H = 30;
  wv_image_alloc(a, W, H, 3, NULL);
  wv_image_alloc(b, W, H, 3, NULL);
  wv_image_alloc(d, W, H, 3, NULL);
  for (int y = 0; y < H; y++)
    for (int x = 0; x < W; x++)
      for (int c = 0; c < 3; c++) {
        size_t i = ((size_t)y * W + x) * 3 + c;
        float av = (float)(0.5 + 0.35 * sin(0.21 * x + 0.9 * c) * cos(0.17 * y));
        double bv = (double)av + 0.15 * sin(0.05 * x * y + c);
        a->data[i] = av;
        b->data[i] = (float)(bv < 0 ? 0 : bv > 1 ? 1 : bv);
        d->data[i] = (float)(1.0 - (double)av);
      }
}

static void test_ssim_reference(void **state) {
  (void)state;
  wv_image a, b, d;
  make(&a, &b, &d);
  double s;
  assert_int_equal(wv_ssim(&a, &b, WV_SSIM_LUMA, &s, NULL), WV_OK);
  assert_true(fabs(s - 0.4903210782) < 1e-6);
  assert_int_equal(wv_ssim(&a, &b, WV_SSIM_RGB, &s, NULL), WV_OK);
  assert_true(fabs(s - 0.4701536556) < 1e-6);
  assert_int_equal(wv_ssim(&a, &d, WV_SSIM_LUMA, &s, NULL), WV_OK);
  assert_true(fabs(s - (-0.6393561451)) < 1e-6);
  assert_int_equal(wv_ssim(&a, &d, WV_SSIM_RGB, &s, NULL), WV_OK);
  assert_true(fabs(s - (-0.6552155303)) < 1e-6);
  assert_int_equal(wv_ssim(&a, &a, WV_SSIM_RGB, &s, NULL), WV_OK);
  assert_true(fabs(s - 1.0) < 1e-12);
  double m;
  assert_int_equal(wv_mae(&a, &d, &m, NULL), WV_OK);
  assert_true(m > 0.05);
  wv_image small;
  wv_image_alloc(&small, 8, 8, 3, NULL);
  wv_error err = {0};
  assert_int_equal(wv_ssim(&small, &small, WV_SSIM_LUMA, &s, &err), WV_ERR_INVALID);
  assert_int_equal(wv_ssim(&a, &small, WV_SSIM_LUMA, &s, &err), WV_ERR_INVALID);
  wv_image_free(&a), wv_image_free(&b), wv_image_free(&d), wv_image_free(&small);
}

/* The values of the implementation before its filter summed a row at a time, bit for bit
 * (each value sums the same terms in the same order). */
static void test_ssim_exact(void **state) {
  (void)state;
  wv_image a, b, d;
  make(&a, &b, &d);
  double s[4];
  assert_int_equal(wv_ssim(&a, &b, WV_SSIM_LUMA, &s[0], NULL), WV_OK);
  assert_int_equal(wv_ssim(&a, &b, WV_SSIM_RGB, &s[1], NULL), WV_OK);
  assert_int_equal(wv_ssim(&a, &d, WV_SSIM_LUMA, &s[2], NULL), WV_OK);
  assert_int_equal(wv_ssim(&a, &d, WV_SSIM_RGB, &s[3], NULL), WV_OK);
  fprintf(stderr, "SSIM exact: %a %a %a %a\n", s[0], s[1], s[2], s[3]);
  const double want[4] = {0x1.f616ba8e179e6p-2, 0x1.e16ff5bc4d6bbp-2, -0x1.4759b04b5a74ep-1, -0x1.4f7868f50d401p-1};
  for (int i = 0; i < 4; i++) assert_true(s[i] == want[i]);
  wv_image_free(&a), wv_image_free(&b), wv_image_free(&d);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_ssim_reference), cmocka_unit_test(test_ssim_exact)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
