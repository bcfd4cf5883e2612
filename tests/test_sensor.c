/* The sensor response, written once for float and double with its adjoint
 * (src/sensor/response_impl.h): the encodings' slopes and the adjoint against
 * central differences, float against double, the image response against the
 * per-value one, the falloff mask, clipping; the powers taken many at once
 * (src/util/vmath.h) against libm's and a row's response against its values alone. */
#include <float.h>
#include <math.h>
#include <string.h>

#include "sensor/sensor.h"
#include "util/vmath.h"
#include "testutil.h"

static wv_scene scene(const char *name) {
  wv_scene s;
  wv_error err;
  assert_int_equal(wv_scene_preset(name, &s, &err), WV_OK);
  return s;
}

/* Encoding slopes against central differences of the double encoding, and the
 * double encoding against the float one. */
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
      assert_true(wv_encode(&s, (float)x) == wv_encode_f(&s, (float)x));
    }
    assert_true(wv_encode_slope(&s, 0.0) == 0.0 && wv_encode_slope(&s, -1.0) == 0.0);
    assert_true(wv_encode_f(&s, -1.0f) == 0.0f && wv_encode_d(&s, 0.0) == 0.0);
  }
}

/* The adjoint against central differences of the double response, on both
 * presets with a mask that varies and values that clip; the image response
 * equals the per-value one; float against double. */
static void test_respond(void **state) {
  (void)state;
  static const char *names[] = {"cylinder", "flat45"};
  uint64_t seed = 5;
  for (int k = 0; k < 2; k++) {
    wv_scene s = scene(names[k]);
    s.width = 40, s.height = 30, s.falloff = 1, s.falloff_sigma = 20;
    s.exposure = 1.3;
    wv_error err;
    wv_image rad, cap;
    assert_int_equal(wv_image_alloc(&rad, 40, 30, 3, &err), WV_OK);
    assert_int_equal(wv_image_alloc(&cap, 40, 30, 3, &err), WV_OK);
    for (int i = 0; i < 40 * 30 * 3; i++) {
      seed = seed * 6364136223846793005ULL + 1442695040888963407ULL;
      rad.data[i] = (float)((seed >> 11) * (1.2 / 9007199254740992.0)); /* some clip: 1.3 x > 1 */
    }
    wv_scene_response(&s, &rad, &cap);
    int clipped = 0;
    for (int y = 0; y < 30; y++)
      for (int x = 0; x < 40; x++)
        for (int c = 0; c < 3; c++) {
          size_t i = ((size_t)y * 40 + x) * 3 + c;
          double m = wv_response_mask(&s, x, y), slope, slope_d;
          assert_true(wv_respond_f(&s, m, rad.data[i], &slope) == cap.data[i]);
          double capd = wv_respond_d(&s, m, rad.data[i], &slope_d);
          assert_true(fabs(capd - cap.data[i]) <= 1e-6 * capd + 1e-9);
          double v = rad.data[i] * s.exposure;
          if (v > s.clip) {
            assert_true(slope == 0.0 && slope_d == 0.0);
            clipped++;
            continue;
          }
          if (v > s.clip * 0.999) continue; /* too near the kink for a difference */
          double h = 1e-7;
          double fd = (wv_respond_d(&s, m, rad.data[i] + h, NULL) - wv_respond_d(&s, m, rad.data[i] - h, NULL)) / (2 * h);
          assert_true(fabs(fd - slope_d) <= 1e-4 * fabs(fd) + 1e-9);
          assert_true(fabs(slope - slope_d) <= 1e-6 * fabs(slope_d));
        }
    assert_true(clipped > 0);
    /* at exactly the clip value: the left derivative */
    double sl;
    wv_respond_f(&s, 1.0, (float)(s.clip / s.exposure), &sl);
    assert_true(sl > 0.0);
    wv_image_free(&rad), wv_image_free(&cap);
  }
}

static void test_mask_and_clip(void **state) {
  (void)state;
  wv_scene s = scene("flat45");
  /* The mask is 1 at the centre and exp(-d^2/sigma^2) away from it. */
  double dx = 0.5 - 256, dy = 0.5 - 256;
  assert_float_equal(wv_response_mask(&s, 0, 0), exp(-(dx * dx + dy * dy) / (450.0 * 450.0)), 1e-12);
  s.falloff = 0;
  assert_true(wv_response_mask(&s, 0, 0) == 1.0);
  s.encoding = WV_ENC_LINEAR, s.exposure = 1;
  assert_true(wv_respond_f(&s, 1.0, 1.5f, NULL) == 1.0f); /* clip 1 */
  s.clip = 0;                                             /* clip <= 0: none */
  assert_true(wv_respond_f(&s, 1.0, 1.5f, NULL) == 1.5f);
  assert_true(wv_respond_f(&s, 0.5, 1.5f, NULL) == 0.75f);
}

/* The vector powers against libm's, for every count up to 40 (whole
 * vectors and masked rests): within a few units in the last place, nothing written past
 * the count, and a value's result the same alone as among others. */
static void test_vmath(void **state) {
  (void)state;
  enum { N = 40 };
  float xf[N], yf[N], zf;
  double xd[N], yd[N], zd;
  for (int i = 0; i < N; i++) xf[i] = 0.001f + 0.037f * (float)i, xd[i] = xf[i];
  for (int n = 0; n <= N; n++) {
    for (int i = 0; i < N; i++) yf[i] = -1.0f, yd[i] = -1.0;
    wv_powf_n(xf, 1.0f / 2.4f, yf, n);
    wv_pow_n(xd, 1.0 / 2.4 - 1.0, yd, n);
    for (int i = n; i < N; i++) assert_true(yf[i] == -1.0f && yd[i] == -1.0);
    for (int i = 0; i < n; i++) {
      assert_true(fabs((double)yf[i] - pow(xf[i], 1.0 / 2.4)) <= 4 * FLT_EPSILON * yf[i]);
      assert_true(fabs(yd[i] - pow(xd[i], 1.0 / 2.4 - 1.0)) <= 8 * DBL_EPSILON * yd[i]);
      wv_powf_n(xf + i, 1.0f / 2.4f, &zf, 1);
      wv_pow_n(xd + i, 1.0 / 2.4 - 1.0, &zd, 1);
      assert_true(zf == yf[i] && zd == yd[i]);
    }
  }
}

/* A row's response (wv_respond_n) is each value's alone (wv_respond_f), slopes included,
 * with and without a mask, in place and not, for every encoding. */
static void test_respond_row(void **state) {
  (void)state;
  wv_scene s = scene("flat45");
  s.exposure = 1.3;
  enum { N = 37 };
  float rad[3 * N], cap[3 * N], inplace[3 * N];
  double slope[3 * N], mask[N];
  for (int i = 0; i < 3 * N; i++) rad[i] = (float)i / (3 * N) - 0.05f; /* some <= 0, some clip */
  for (int k = 0; k < N; k++) mask[k] = 0.5 + 0.01 * k;
  wv_encoding encs[] = {WV_ENC_SRGB, WV_ENC_GAMMA, WV_ENC_LINEAR};
  for (int e = 0; e < 3; e++) {
    s.encoding = encs[e], s.gamma = 2.2;
    for (int m = 0; m < 2; m++) {
      wv_respond_n(&s, m ? mask : NULL, N, 3, rad, cap, slope);
      memcpy(inplace, rad, sizeof rad);
      wv_respond_n(&s, m ? mask : NULL, N, 3, inplace, inplace, NULL);
      int clipped = 0;
      for (int i = 0; i < 3 * N; i++) {
        double sl;
        float v = wv_respond_f(&s, m ? mask[i / 3] : 1.0, rad[i], &sl);
        assert_true(v == cap[i] && v == inplace[i] && sl == slope[i]);
        clipped += rad[i] * s.exposure > s.clip;
      }
      assert_true(clipped > 0);
    }
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_encode), cmocka_unit_test(test_respond),
                                     cmocka_unit_test(test_mask_and_clip), cmocka_unit_test(test_vmath),
                                     cmocka_unit_test(test_respond_row)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
