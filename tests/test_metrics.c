/* SSIM against reference values from scikit-image.
 * The values below were computed once with scikit-image 0.19.3 (Debian package
 * python3-skimage) by tests/reference/ssim_reference.py:
 * structural_similarity(a, b, gaussian_weights=True, sigma=1.5,
 * use_sample_covariance=False, data_range=1.0) on the same synthetic images,
 * on luminance (Rec. 709 weights) and per channel (channel_axis=2). */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>

#include "testutil.h"
#include "util/hash.h"
#include "util/select.h"
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

/* Rows of the SSIM's filter go to threads: one thread and two give the same bits. */
static void test_ssim_threads(void **state) {
  (void)state;
  wv_image a, b;
  int W = 97, H = 83;
  wv_image_alloc(&a, W, H, 3, NULL), wv_image_alloc(&b, W, H, 3, NULL);
  for (size_t i = 0; i < (size_t)W * H * 3; i++) {
    a.data[i] = (float)(wv_mix64(i) >> 40) / (float)(1 << 24);
    b.data[i] = 0.5f * a.data[i] + 0.5f * (float)(wv_mix64(i + 7777) >> 40) / (float)(1 << 24);
  }
  double s1, s2;
  int nt = omp_get_max_threads();
  omp_set_num_threads(1);
  assert_int_equal(wv_ssim(&a, &b, WV_SSIM_RGB, &s1, NULL), WV_OK);
  omp_set_num_threads(2);
  assert_int_equal(wv_ssim(&a, &b, WV_SSIM_RGB, &s2, NULL), WV_OK);
  omp_set_num_threads(nt);
  assert_true(s1 == s2);
  assert_true(s1 > 0.1 && s1 < 0.99);
  wv_image_free(&a), wv_image_free(&b);
}

static int cmp_f(const void *a, const void *b) {
  float x = *(const float *)a, y = *(const float *)b;
  return (x > y) - (x < y);
}

/* The k-th smallest is what a sorted copy holds at k: on random values, on many equal
 * values, on sorted and reversed input, at every k of small arrays. */
static void test_select_matches_sort(void **state) {
  (void)state;
  enum { N = 301 };
  float a[N], b[N], sorted[N];
  for (int kind = 0; kind < 4; kind++)
    for (int n = 1; n <= N; n += (n < 20 ? 1 : 37)) {
      for (int i = 0; i < n; i++) {
        uint64_t h = wv_mix64((uint64_t)(kind * 1000 + n) * 4096 + (uint64_t)i);
        a[i] = kind == 0 ? (float)(h >> 40) : kind == 1 ? (float)(h % 3) : kind == 2 ? (float)i : (float)(n - i);
      }
      for (int i = 0; i < n; i++) sorted[i] = a[i];
      qsort(sorted, (size_t)n, sizeof(float), cmp_f);
      for (int k = 0; k < n; k++) {
        for (int i = 0; i < n; i++) b[i] = a[i];
        float v = wv_select_float(b, (size_t)n, (size_t)k);
        assert_true(v == sorted[k]);
        assert_true(b[k] == v);
        for (int i = 0; i < k; i++) assert_true(b[i] <= v);
        for (int i = k + 1; i < n; i++) assert_true(b[i] >= v);
      }
    }
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_ssim_reference), cmocka_unit_test(test_ssim_exact),
                                     cmocka_unit_test(test_ssim_threads), cmocka_unit_test(test_select_matches_sort)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
