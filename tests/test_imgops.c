/* Image operations and their adjoints: area downsampling, the L1 loss. (The
 * sensor response: test_sensor.c.) */
#include <math.h>
#include <string.h>

#include "testutil.h"
#include "woven/imgops.h"


static void fill(wv_image *im, tu_rng *s, double lo, double hi) {
  for (size_t i = 0; i < (size_t)im->w * im->h * im->c; i++) im->data[i] = (float)(lo + (hi - lo) * tu_rnd(s));
}

static double dot(const wv_image *a, const wv_image *b) {
  double d = 0;
  for (size_t i = 0; i < (size_t)a->w * a->h * a->c; i++) d += (double)a->data[i] * b->data[i];
  return d;
}

/* Integer factors average blocks; non-integer factors weight partial pixels by area. */
static void test_downsample_values(void **state) {
  (void)state;
  wv_error err;
  wv_image in, out;
  assert_int_equal(wv_image_alloc(&in, 4, 2, 1, &err), WV_OK);
  for (int i = 0; i < 8; i++) in.data[i] = (float)i; /* rows 0 1 2 3 / 4 5 6 7 */
  assert_int_equal(wv_image_downsample(&in, 2, 1, &out, &err), WV_OK);
  assert_float_equal(out.data[0], (0 + 1 + 4 + 5) / 4.0, 1e-6);
  assert_float_equal(out.data[1], (2 + 3 + 6 + 7) / 4.0, 1e-6);
  wv_image_free(&out);
  /* 4 -> 3 columns: each output covers 4/3 input pixels. */
  assert_int_equal(wv_image_downsample(&in, 3, 1, &out, &err), WV_OK);
  double row[4] = {2, 3, 4, 5}; /* column means */
  assert_float_equal(out.data[0], (row[0] + row[1] / 3) * 0.75, 1e-6);
  assert_float_equal(out.data[1], (row[1] * 2 / 3 + row[2] * 2 / 3) * 0.75, 1e-6);
  assert_float_equal(out.data[2], (row[2] / 3 + row[3]) * 0.75, 1e-6);
  wv_image_free(&out), wv_image_free(&in);
  /* The fit's 16 x 8 of an 800 x 300 render (300 / 8 = 37.5): a constant stays
   * constant and the mean is kept. */
  tu_rng s = {1};
  assert_int_equal(wv_image_alloc(&in, 800, 300, 3, &err), WV_OK);
  for (size_t i = 0; i < 800 * 300 * 3; i++) in.data[i] = 0.25f;
  assert_int_equal(wv_image_downsample(&in, 16, 8, &out, &err), WV_OK);
  for (int i = 0; i < 16 * 8 * 3; i++) assert_float_equal(out.data[i], 0.25, 1e-6);
  wv_image_free(&out);
  fill(&in, &s, 0, 1);
  assert_int_equal(wv_image_downsample(&in, 16, 8, &out, &err), WV_OK);
  assert_float_equal(wv_image_mean(&out), wv_image_mean(&in), 1e-6);
  wv_image_free(&out);
  /* Upsampling is allowed too (each output a part of one input pixel). */
  assert_int_equal(wv_image_downsample(&in, 1600, 301, &out, &err), WV_OK);
  assert_float_equal(wv_image_mean(&out), wv_image_mean(&in), 1e-5);
  wv_image_free(&out), wv_image_free(&in);
  assert_int_equal(wv_image_downsample(&in, 0, 8, &out, &err), WV_ERR_INVALID);
}

/* <dout, D x> = <D^T dout, x> for several shapes (the exact adjoint). */
static void test_downsample_adjoint(void **state) {
  (void)state;
  static const int shapes[][4] = {{800, 300, 16, 8}, {97, 61, 16, 8}, {64, 64, 64, 64}, {10, 7, 3, 2}, {5, 4, 12, 9}};
  tu_rng s = {9};
  for (size_t k = 0; k < sizeof shapes / sizeof shapes[0]; k++) {
    wv_error err;
    wv_image x, y, dy, dx;
    assert_int_equal(wv_image_alloc(&x, shapes[k][0], shapes[k][1], 3, &err), WV_OK);
    assert_int_equal(wv_image_alloc(&dy, shapes[k][2], shapes[k][3], 3, &err), WV_OK);
    fill(&x, &s, -1, 1), fill(&dy, &s, -1, 1);
    assert_int_equal(wv_image_downsample(&x, dy.w, dy.h, &y, &err), WV_OK);
    assert_int_equal(wv_image_downsample_backward(x.w, x.h, &dy, &dx, &err), WV_OK);
    assert_int_equal(dx.w, x.w);
    assert_int_equal(dx.h, x.h);
    double a = dot(&dy, &y), b = dot(&dx, &x);
    assert_true(fabs(a - b) <= 1e-5 * (fabs(a) + 1.0));
    wv_image_free(&x), wv_image_free(&y), wv_image_free(&dy), wv_image_free(&dx);
  }
}

static void test_l1(void **state) {
  (void)state;
  wv_error err;
  wv_image a, b, g;
  assert_int_equal(wv_image_alloc(&a, 2, 1, 3, &err), WV_OK);
  assert_int_equal(wv_image_alloc(&b, 2, 1, 3, &err), WV_OK);
  assert_int_equal(wv_image_alloc(&g, 2, 1, 3, &err), WV_OK);
  float av[6] = {0.5f, 1.5f, -1, 2, 0.25f, 1}, bv[6] = {0.5f, 1, 0, 1, 0.5f, 1};
  memcpy(a.data, av, sizeof av), memcpy(b.data, bv, sizeof bv);
  assert_float_equal(wv_image_l1(&a, &b, &g), (0 + 0.5 + 1 + 1 + 0.25 + 0) / 6, 1e-9);
  float gv[6] = {0, 1.0f / 6, -1.0f / 6, 1.0f / 6, -1.0f / 6, 0};
  for (int i = 0; i < 6; i++) assert_float_equal(g.data[i], gv[i], 1e-7);
  wv_image_free(&a), wv_image_free(&b), wv_image_free(&g);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_downsample_values), cmocka_unit_test(test_downsample_adjoint),
      cmocka_unit_test(test_l1)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
