/* Tests of the image type: allocation limits; the blur against its plain definition. */
#include "testutil.h"
#include "woven/image.h"

#include <stdlib.h>

static void test_alloc_limits(void **state) {
  (void)state;
  wv_image img;
  wv_error err = {0};
  assert_int_equal(wv_image_alloc(&img, 4, 3, 3, &err), WV_OK);
  assert_non_null(img.data);
  assert_true(wv_image_mean(&img) == 0.0);
  wv_image_free(&img);
  assert_int_equal(wv_image_alloc(&img, 1 << 16, 1 << 16, 3, &err), WV_ERR_NOMEM);
  assert_null(img.data);
  assert_int_equal(wv_image_alloc(&img, 0, 3, 3, &err), WV_ERR_INVALID);
}

/* The separable blur as defined: per pass, each value the sum over k = -r..r (ascending,
 * in double) of g[k + r] times the clamped neighbour, rounded to float. */
static void blur_plain(const float *in, float *out, int w, int h, int stride, double sigma) {
  int r = wv_gaussian_radius(sigma);
  double g[64];
  wv_gaussian_taps(sigma, g);
  float *tmp = malloc(sizeof(float) * (size_t)w * h * stride);
  for (int pass = 0; pass < 2; pass++) {
    const float *src = pass ? tmp : in;
    float *dst = pass ? out : tmp;
    for (int y = 0; y < h; y++)
      for (int x = 0; x < w; x++) {
        double s = 0;
        for (int k = -r; k <= r; k++) {
          int xx = pass ? x : x + k < 0 ? 0 : x + k >= w ? w - 1 : x + k;
          int yy = !pass ? y : y + k < 0 ? 0 : y + k >= h ? h - 1 : y + k;
          s += g[k + r] * src[((size_t)yy * w + xx) * stride];
        }
        dst[((size_t)y * w + x) * stride] = (float)s;
      }
  }
  free(tmp);
}

/* The blur equals its plain definition bit for bit: narrow images (every value near an
 * edge), wide ones, interleaved channels. */
static void test_blur_exact(void **state) {
  (void)state;
  const int sizes[][2] = {{64, 64}, {5, 7}, {30, 9}, {97, 41}};
  const double sigmas[] = {0.0, 0.7, 2.0, 4.0};
  uint64_t seed = 12345;
  for (size_t i = 0; i < sizeof sizes / sizeof *sizes; i++)
    for (size_t j = 0; j < sizeof sigmas / sizeof *sigmas; j++) {
      int w = sizes[i][0], h = sizes[i][1];
      wv_image a, b;
      assert_int_equal(wv_image_alloc(&a, w, h, 3, NULL), WV_OK);
      for (size_t k = 0; k < (size_t)w * h * 3; k++) {
        seed = seed * 6364136223846793005ULL + 1442695040888963407ULL;
        a.data[k] = (float)((seed >> 40) & 0xffff) / 65536.0f;
      }
      assert_int_equal(wv_image_blur(&a, sigmas[j], &b, NULL), WV_OK);
      float *ref = malloc(sizeof(float) * (size_t)w * h * 3);
      for (int c = 0; c < 3; c++) blur_plain(a.data + c, ref + c, w, h, 3, sigmas[j]);
      assert_memory_equal(b.data, ref, sizeof(float) * (size_t)w * h * 3);
      free(ref);
      wv_image_free(&a), wv_image_free(&b);
    }
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_alloc_limits), cmocka_unit_test(test_blur_exact)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
