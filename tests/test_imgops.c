/* Image operations and their adjoints: area downsampling, encoding, clipping,
 * falloff mask, the scene response's backward, the L1 loss. */
#include <math.h>
#include <string.h>

#include "testutil.h"
#include "woven/imgops.h"

static uint64_t next(uint64_t *s) {
  *s = *s * 6364136223846793005ULL + 1442695040888963407ULL;
  return *s;
}
static double rnd(uint64_t *s) { return (double)(next(s) >> 11) * (1.0 / 9007199254740992.0); }

static void fill(wv_image *im, uint64_t *s, double lo, double hi) {
  for (size_t i = 0; i < (size_t)im->w * im->h * im->c; i++) im->data[i] = (float)(lo + (hi - lo) * rnd(s));
}

static double dot(const wv_image *a, const wv_image *b) {
  double d = 0;
  for (size_t i = 0; i < (size_t)a->w * a->h * a->c; i++) d += (double)a->data[i] * b->data[i];
  return d;
}

static wv_scene scene(const char *name) {
  wv_scene s;
  wv_error err;
  assert_int_equal(wv_scene_preset(name, &s, &err), WV_OK);
  return s;
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
  uint64_t s = 1;
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
  uint64_t s = 9;
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

/* Encoding slopes against central differences of the double encoding, and the
 * double encoding against wv_encode. */
static void test_encode(void **state) {
  (void)state;
  wv_scene s = scene("cylinder");
  wv_encoding encs[] = {WV_ENC_SRGB, WV_ENC_GAMMA, WV_ENC_LINEAR};
  double xs[] = {1e-4, 0.002, 0.01, 0.1, 0.5, 0.9, 1.7};
  for (int e = 0; e < 3; e++) {
    s.encoding = encs[e], s.gamma = 2.2;
    for (size_t i = 0; i < sizeof xs / sizeof xs[0]; i++) {
      double x = xs[i], h = 1e-6 * x;
      double fd = (wv_encode_d(&s, x + h) - wv_encode_d(&s, x - h)) / (2 * h);
      assert_true(fabs(fd - wv_encode_slope(&s, x)) <= 1e-6 * fabs(fd));
      assert_true(fabs(wv_encode_d(&s, x) - wv_encode(&s, (float)x)) <= 1e-6 * wv_encode_d(&s, x));
    }
    assert_true(wv_encode_slope(&s, 0.0) == 0.0 && wv_encode_slope(&s, -1.0) == 0.0);
  }
}

/* wv_scene_response_backward equals the composition of the pieces' adjoints and
 * central differences of the response computed in double, on both presets. */
static void test_response_backward(void **state) {
  (void)state;
  static const char *names[] = {"cylinder", "flat45"};
  uint64_t seed = 5;
  for (int k = 0; k < 2; k++) {
    wv_scene s = scene(names[k]);
    s.width = 40, s.height = 30, s.falloff_sigma = 20; /* a mask that varies across the image */
    s.exposure = 1.3;
    wv_error err;
    wv_image rad, dcap, drad, t1, t2, t3;
    assert_int_equal(wv_image_alloc(&rad, 40, 30, 3, &err), WV_OK);
    assert_int_equal(wv_image_alloc(&dcap, 40, 30, 3, &err), WV_OK);
    assert_int_equal(wv_image_alloc(&drad, 40, 30, 3, &err), WV_OK);
    assert_int_equal(wv_image_alloc(&t1, 40, 30, 3, &err), WV_OK);
    assert_int_equal(wv_image_alloc(&t2, 40, 30, 3, &err), WV_OK);
    assert_int_equal(wv_image_alloc(&t3, 40, 30, 3, &err), WV_OK);
    fill(&rad, &seed, 0.0, 1.2); /* some values clip (1.3 x > 1) */
    fill(&dcap, &seed, -1, 1);
    wv_scene_response_backward(&s, &rad, &dcap, &drad);
    /* Composition: mask(encode(clip(exposure x))). */
    wv_image_scale(&rad, (float)s.exposure, &t1);
    wv_image_clip(&t1, (float)s.clip, &t2);
    wv_image_mask_backward(&s, &dcap, &t3);
    wv_image_encode_backward(&s, &t2, &t3, &t3);
    wv_image_clip_backward(&t1, (float)s.clip, &t3, &t3);
    wv_image_scale(&t3, (float)s.exposure, &t3);
    /* Forward composition equals wv_scene_response. */
    wv_image cap, cap2;
    assert_int_equal(wv_image_alloc(&cap, 40, 30, 3, &err), WV_OK);
    assert_int_equal(wv_image_alloc(&cap2, 40, 30, 3, &err), WV_OK);
    wv_scene_response(&s, &rad, &cap);
    wv_image_encode(&s, &t2, &cap2);
    wv_image_mask(&s, &cap2, &cap2);
    assert_int_equal(memcmp(cap.data, cap2.data, sizeof(float) * 40 * 30 * 3), 0);
    int clipped = 0;
    for (int y = 0; y < 30; y++)
      for (int x = 0; x < 40; x++)
        for (int c = 0; c < 3; c++) {
          size_t i = ((size_t)y * 40 + x) * 3 + c;
          assert_float_equal(drad.data[i], t3.data[i], 1e-5 * fabs(drad.data[i]) + 1e-7);
          double v = rad.data[i] * s.exposure;
          if (v > s.clip) {
            assert_true(drad.data[i] == 0.0f);
            clipped++;
            continue;
          }
          if (v > s.clip * 0.999) continue; /* too near the kink for a difference */
          double h = 1e-7, m = wv_falloff_mask(&s, x, y);
          double fp = m * wv_encode_d(&s, (rad.data[i] + h) * s.exposure);
          double fm = m * wv_encode_d(&s, (rad.data[i] - h) * s.exposure);
          double fd = dcap.data[i] * (fp - fm) / (2 * h);
          assert_true(fabs(fd - drad.data[i]) <= 1e-4 * fabs(fd) + 1e-9);
        }
    assert_true(clipped > 0);
    wv_image_free(&rad), wv_image_free(&dcap), wv_image_free(&drad), wv_image_free(&t1), wv_image_free(&t2);
    wv_image_free(&t3), wv_image_free(&cap), wv_image_free(&cap2);
  }
}

static void test_mask_clip_l1(void **state) {
  (void)state;
  wv_scene s = scene("flat45");
  /* The mask is 1 at the centre and exp(-d^2/sigma^2) away from it. */
  double dx = 0.5 - 256, dy = 0.5 - 256;
  assert_float_equal(wv_falloff_mask(&s, 0, 0), exp(-(dx * dx + dy * dy) / (450.0 * 450.0)), 1e-12);
  s.falloff = 0;
  assert_true(wv_falloff_mask(&s, 0, 0) == 1.0);
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
  wv_image_clip(&a, 1.0f, &b);
  assert_true(b.data[1] == 1.0f && b.data[3] == 1.0f && b.data[0] == 0.5f && b.data[5] == 1.0f);
  for (int i = 0; i < 6; i++) g.data[i] = 1;
  wv_image_clip_backward(&a, 1.0f, &g, &g);
  float cv[6] = {1, 0, 1, 0, 1, 1}; /* at exactly the clip value: the left derivative */
  for (int i = 0; i < 6; i++) assert_true(g.data[i] == cv[i]);
  wv_image_clip(&a, 0.0f, &b); /* clip <= 0: none */
  assert_int_equal(memcmp(a.data, b.data, sizeof av), 0);
  wv_image_free(&a), wv_image_free(&b), wv_image_free(&g);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_downsample_values), cmocka_unit_test(test_downsample_adjoint),
      cmocka_unit_test(test_encode),            cmocka_unit_test(test_response_backward),
      cmocka_unit_test(test_mask_clip_l1)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
