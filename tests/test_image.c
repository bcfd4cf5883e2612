/* Tests of the image type: allocation limits. */
#include "testutil.h"
#include "woven/image.h"

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

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_alloc_limits)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
