/* FabricNet: backward against finite differences, training on a learnable toy set,
 * parameter mapping, model and checkpoint files (round trip and every corruption),
 * half floats and CRC-32. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"
#include "woven/fabricnet.h"
#include "woven/io.h"
#include "woven/nn.h"

static wv_scene tiny_scene(void) {
  wv_scene s;
  wv_error e;
  assert_int_equal(wv_scene_preset("flat45", &s, &e), WV_OK);
  return s;
}

static double net_loss(wv_fabricnet *n, const float *x, const float *y, int batch) {
  wv_fabricnet_acts a;
  wv_error e;
  assert_int_equal(wv_fabricnet_acts_alloc(&a, batch, &e), WV_OK);
  wv_fabricnet_forward(n, x, batch, &a);
  double s = 0;
  for (int i = 0; i < batch * WV_NET_OUT; i++) s += fabs((double)a.out[i] - y[i]);
  wv_fabricnet_acts_free(&a);
  return s / (batch * WV_NET_OUT);
}

static void test_gradient(void **state) {
  (void)state;
  wv_scene s = tiny_scene();
  wv_fabricnet n;
  wv_error e;
  const int nin = 12, batch = 3;
  assert_int_equal(wv_fabricnet_init(&n, "default", nin, &s, 7, &e), WV_OK);
  /* larger weights than the init so every layer matters */
  float *t[6];
  size_t len[6];
  wv_fabricnet_tensors(&n, t, len);
  wv_rng r;
  wv_rng_seed(&r, 3);
  for (int i = 0; i < 6; i++)
    for (size_t j = 0; j < len[i]; j++) t[i][j] *= 2.0f;
  float x[batch * 12], y[batch * WV_NET_OUT];
  wv_rng_fill_uniform(&r, x, sizeof x / sizeof x[0], -1, 1);
  wv_rng_fill_uniform(&r, y, sizeof y / sizeof y[0], 0, 1);
  size_t P = wv_fabricnet_param_count(&n);
  float *g = calloc(P, sizeof(float)), *gt[6];
  size_t off = 0;
  for (int i = 0; i < 6; i++) gt[i] = g + off, off += len[i];
  wv_fabricnet_acts a;
  assert_int_equal(wv_fabricnet_acts_alloc(&a, batch, &e), WV_OK);
  float loss = wv_fabricnet_backward(&n, x, y, batch, &a, gt);
  assert_true(fabs(loss - net_loss(&n, x, y, batch)) < 1e-6);
  /* spot-check entries of every tensor with central differences */
  double worst = 0;
  for (int i = 0; i < 6; i++) {
    /* relative errors with a floor of a tenth of the tensor's largest gradient: the
     * float loss makes tiny derivatives noisy in absolute terms */
    double gmax = 0;
    for (size_t j = 0; j < len[i]; j++) gmax = fmax(gmax, fabs(gt[i][j]));
    for (size_t j = 0; j < len[i]; j += len[i] / 7 + 1) {
      float save = t[i][j], h = 2e-3f;
      t[i][j] = save + h;
      double fp = net_loss(&n, x, y, batch);
      t[i][j] = save - h;
      double fm = net_loss(&n, x, y, batch);
      t[i][j] = save;
      double num = (fp - fm) / (2 * h), an = gt[i][j];
      double err = fabs(num - an) / (fabs(num) + fabs(an) + 0.1 * gmax + 1e-6);
      if (err > worst) worst = err;
      if (err > 0.05) fprintf(stderr, "tensor %d [%zu]: analytic %g, numeric %g\n", i, j, an, num);
      assert_true(err < 0.05);
    }
  }
  fprintf(stderr, "fabricnet backward: worst relative error %.2e\n", worst);
  wv_fabricnet_acts_free(&a);
  free(g);
  wv_fabricnet_free(&n);
}

/* A learnable toy problem: targets are a fixed smooth function of the features. */
static void test_training_reduces_loss(void **state) {
  (void)state;
  wv_scene s = tiny_scene();
  wv_fabricnet n;
  wv_error e;
  const int nin = 64, N = 64, batch = 16;
  assert_int_equal(wv_fabricnet_init(&n, "default", nin, &s, 1, &e), WV_OK);
  float *x = malloc(sizeof(float) * N * nin), *y = malloc(sizeof(float) * N * WV_NET_OUT);
  wv_rng r;
  wv_rng_seed(&r, 11);
  wv_rng_fill_uniform(&r, x, (size_t)N * nin, -1, 1);
  for (int i = 0; i < N; i++)
    for (int k = 0; k < WV_NET_OUT; k++) y[i * WV_NET_OUT + k] = 0.5f + 0.4f * sinf(x[i * nin + k] + x[i * nin + k + 1]);
  size_t P = wv_fabricnet_param_count(&n);
  float *g = calloc(P, sizeof(float)), *gt[6], *t[6];
  size_t len[6], off = 0;
  wv_fabricnet_tensors(&n, t, len);
  for (int i = 0; i < 6; i++) gt[i] = g + off, off += len[i];
  wv_nn_adam adam;
  assert_int_equal(wv_nn_adam_init(&adam, P, 1e-3f, &e), WV_OK);
  wv_fabricnet_acts a;
  assert_int_equal(wv_fabricnet_acts_alloc(&a, batch, &e), WV_OK);
  double first = net_loss(&n, x, y, N);
  for (int ep = 0; ep < 60; ep++)
    for (int b = 0; b < N; b += batch) {
      memset(g, 0, P * sizeof(float));
      wv_fabricnet_backward(&n, x + (size_t)b * nin, y + (size_t)b * WV_NET_OUT, batch, &a, gt);
      wv_nn_adam_step(&adam, n.w1, g);
    }
  double last = net_loss(&n, x, y, N);
  fprintf(stderr, "toy training: L1 %.4f -> %.4f\n", first, last);
  assert_true(last < 0.3 * first);
  wv_nn_adam_free(&adam);
  wv_fabricnet_acts_free(&a);
  free(g), free(x), free(y);
  wv_fabricnet_free(&n);
}

static void test_param_mapping(void **state) {
  (void)state;
  wv_params p, q;
  wv_error e;
  wv_scene s = tiny_scene();
  wv_fabricnet n;
  assert_int_equal(wv_fabricnet_init(&n, "default", 4, &s, 1, &e), WV_OK);
  for (int pat = 0; pat < WV_NET_PATTERNS; pat++) {
    assert_int_equal(wv_params_sample_prior(wv_net_pattern(pat), 99 + pat, &p, &e), WV_OK);
    float y[WV_NET_OUT];
    wv_fabricnet_targets(&p, y);
    for (int k = 0; k < WV_NET_OUT; k++) assert_true(y[k] >= 0 && y[k] <= 1);
    assert_int_equal(wv_fabricnet_params(&n, y, p.pattern, &q, &e), WV_OK);
    assert_true(fabs(q.density[0] - p.density[0]) < 0.51 && fabs(q.density[1] - p.density[1]) < 0.51);
    for (int k = 0; k < WV_P_COUNT; k++) assert_true(fabs(wv_param_get(&q, k) - wv_param_get(&p, k)) < 1e-4);
  }
  wv_fabricnet_free(&n);
}

static void test_f16_crc(void **state) {
  (void)state;
  const float v[] = {0.0f, 1.0f, -2.5f, 65504.0f, 1e-7f, 6.1035156e-05f, 0.333333f, 1e6f, -1e6f, 3.0e-6f};
  for (size_t i = 0; i < sizeof v / sizeof v[0]; i++) {
    float back = wv_nn_f16_to_f32(wv_f32_to_f16(v[i]));
    float want = fabsf(v[i]) > 65504 ? copysignf(65504, v[i]) : v[i];
    assert_true(fabsf(back - want) <= fmaxf(fabsf(want) * 1e-3f, 6e-8f));
  }
  /* every half value survives a round trip through float */
  for (uint32_t h = 0; h < 0x7c00; h++) assert_int_equal(wv_f32_to_f16(wv_nn_f16_to_f32((uint16_t)h)), h);
  assert_int_equal(wv_crc32(0, "123456789", 9), 0xcbf43926u); /* the standard check value */
}

static void write_bytes(const char *path, const unsigned char *b, size_t n) {
  FILE *f = fopen(path, "wb");
  assert_non_null(f);
  assert_int_equal(fwrite(b, 1, n, f), n);
  fclose(f);
}

/* Recomputes the payload and header checksums of a patched model file. */
static void reseal(unsigned char *b, size_t n) {
  uint32_t c = wv_crc32(0, b + 504, n - 504);
  for (int i = 0; i < 4; i++) b[496 + i] = (unsigned char)(c >> (8 * i));
  c = wv_crc32(0, b, 500);
  for (int i = 0; i < 4; i++) b[500 + i] = (unsigned char)(c >> (8 * i));
}

static void expect_load_fails(const char *path, const char *needle) {
  wv_fabricnet m;
  wv_error e = {0};
  wv_status st = wv_fabricnet_load(path, &m, &e);
  if (st == WV_OK || !strstr(e.msg, needle) || !strstr(e.msg, path))
    fprintf(stderr, "load %s: status %d, message '%s' (wanted '%s')\n", path, st, e.msg, needle);
  assert_int_not_equal(st, WV_OK);
  assert_non_null(strstr(e.msg, needle));
  assert_non_null(strstr(e.msg, path));
}

static void test_files(void **state) {
  (void)state;
  const char *dir = tu_tmpdir("fabricnet_files");
  char path[512], bad[512];
  snprintf(path, sizeof path, "%s/m.bin", dir);
  snprintf(bad, sizeof bad, "%s/bad.bin", dir);
  wv_scene s = tiny_scene();
  wv_fabricnet n, m;
  wv_error e;
  assert_int_equal(wv_fabricnet_init(&n, "default", 100, &s, 5, &e), WV_OK);
  for (int i = 0; i < 100; i++) n.mean[i] = 0.01f * i, n.std[i] = 1 + 0.1f * i;
  assert_int_equal(wv_fabricnet_save(path, &n, &e), WV_OK);
  assert_int_equal(wv_fabricnet_load(path, &m, &e), WV_OK);
  assert_string_equal(m.descriptor, "default");
  assert_string_equal(m.scene, "flat45");
  assert_int_equal(m.n_in, 100);
  for (int i = 0; i < 100; i++) assert_true(m.mean[i] == n.mean[i] && m.std[i] == n.std[i]);
  float *tn[6], *tm[6];
  size_t len[6];
  wv_fabricnet_tensors(&n, tn, len);
  wv_fabricnet_tensors(&m, tm, len);
  for (int i = 0; i < 6; i++)
    for (size_t j = 0; j < len[i]; j++) assert_true(fabsf(tn[i][j] - tm[i][j]) <= fabsf(tn[i][j]) * 1e-3f + 1e-7f);
  /* the descriptor and scene checks */
  assert_int_equal(wv_fabricnet_check(&m, path, "default", 100, &s, &e), WV_OK);
  assert_int_not_equal(wv_fabricnet_check(&m, path, "vgg19", 100, &s, &e), WV_OK);
  assert_non_null(strstr(e.msg, "descriptor"));
  assert_int_not_equal(wv_fabricnet_check(&m, path, "default", 20480, &s, &e), WV_OK);
  wv_scene cyl;
  assert_int_equal(wv_scene_preset("cylinder", &cyl, &e), WV_OK);
  assert_int_not_equal(wv_fabricnet_check(&m, path, "default", 100, &cyl, &e), WV_OK);
  assert_non_null(strstr(e.msg, "scene"));
  wv_fabricnet_free(&m);

  char *data;
  size_t n_bytes;
  assert_int_equal(wv_read_file(path, &data, &n_bytes, &e), WV_OK);
  unsigned char *b = malloc(n_bytes + 8);
  /* truncated: inside the header and inside the payload */
  memcpy(b, data, n_bytes);
  write_bytes(bad, b, 100);
  expect_load_fails(bad, "truncated");
  write_bytes(bad, b, n_bytes - 10);
  expect_load_fails(bad, "truncated");
  write_bytes(bad, b, 0);
  expect_load_fails(bad, "magic");
  /* trailing garbage */
  memcpy(b + n_bytes, "xxxxxxxx", 8);
  write_bytes(bad, b, n_bytes + 8);
  expect_load_fails(bad, "unexpected bytes");
  /* bad magic */
  b[0] = 'X';
  write_bytes(bad, b, n_bytes);
  expect_load_fails(bad, "magic");
  /* another version (checked before the header checksum, so the message names it) */
  memcpy(b, data, n_bytes);
  b[8] = 9;
  write_bytes(bad, b, n_bytes);
  expect_load_fails(bad, "version");
  /* a flipped header byte (descriptor name): header checksum */
  memcpy(b, data, n_bytes);
  b[20] ^= 1;
  write_bytes(bad, b, n_bytes);
  expect_load_fails(bad, "header checksum");
  /* a flipped payload byte: payload checksum */
  memcpy(b, data, n_bytes);
  b[n_bytes / 2] ^= 0x10;
  write_bytes(bad, b, n_bytes);
  expect_load_fails(bad, "payload checksum");
  /* a checkpoint is not a model */
  float *mm = calloc(wv_fabricnet_param_count(&n), sizeof(float));
  wv_fabricnet_trainstate ts = {.epoch = 3, .best_epoch = 2, .adam_t = 30, .rng = 42, .best_val = 0.25f};
  assert_int_equal(wv_fabricnet_checkpoint_save(bad, &n, mm, mm, &ts, &e), WV_OK);
  expect_load_fails(bad, "not a FabricNet model");
  float *am, *av;
  wv_fabricnet_trainstate ts2;
  assert_int_equal(wv_fabricnet_checkpoint_load(bad, &m, &am, &av, &ts2, &e), WV_OK);
  assert_int_equal(ts2.epoch, 3);
  assert_int_equal(ts2.best_epoch, 2);
  assert_int_equal(ts2.adam_t, 30);
  assert_true(ts2.rng == 42 && ts2.best_val == 0.25f);
  wv_fabricnet_tensors(&m, tm, len);
  for (int i = 0; i < 6; i++) assert_memory_equal(tn[i], tm[i], len[i] * sizeof(float)); /* f32: exact */
  free(am), free(av), free(mm);
  wv_fabricnet_free(&m);
  /* the trainer's counters are checked: a negative epoch would index the loss history */
  mm = calloc(wv_fabricnet_param_count(&n), sizeof(float));
  wv_fabricnet_trainstate bad_ts[3] = {{.epoch = -5, .best_val = 1},
                                       {.epoch = 3, .best_epoch = 7, .best_val = 1},
                                       {.epoch = 200000, .best_epoch = 1, .best_val = 1}};
  const char *bad_key[3] = {"'epoch' = -5", "'best_epoch' = 7", "'epoch' = 200000"};
  for (int i = 0; i < 3; i++) {
    assert_int_equal(wv_fabricnet_checkpoint_save(bad, &n, mm, mm, &bad_ts[i], &e), WV_OK);
    assert_int_equal(wv_fabricnet_checkpoint_load(bad, &m, &am, &av, &ts2, &e), WV_ERR_FORMAT);
    assert_non_null(strstr(e.msg, bad_key[i]));
    assert_non_null(strstr(e.msg, bad));
    assert_null(am);
  }
  free(mm);
  /* an unknown kind, and NaN weights: named as such, with the file (checksums resealed) */
  memcpy(b, data, n_bytes);
  b[12] = 99;
  reseal(b, n_bytes);
  write_bytes(bad, b, n_bytes);
  expect_load_fails(bad, "unknown FabricNet file kind 99");
  memcpy(b, data, n_bytes);
  b[504 + 8 * 100] = 0x00, b[504 + 8 * 100 + 1] = 0x7e; /* the first f16 weight: NaN */
  reseal(b, n_bytes);
  write_bytes(bad, b, n_bytes);
  expect_load_fails(bad, "layer 1 weights hold NaN");
  /* missing file: an I/O error naming it */
  snprintf(bad, sizeof bad, "%s/none.bin", dir);
  assert_int_equal(wv_fabricnet_load(bad, &m, &e), WV_ERR_IO);
  assert_non_null(strstr(e.msg, "none.bin"));
  free(b), free(data);
  wv_fabricnet_free(&n);
}

static void test_features_file(void **state) {
  (void)state;
  const char *dir = tu_tmpdir("fabricnet_feat");
  char path[512];
  snprintf(path, sizeof path, "%s/f.feat", dir);
  float x[50];
  for (int i = 0; i < 50; i++) x[i] = 0.1f * i * i;
  wv_error e;
  assert_int_equal(wv_dataset_write_features(path, x, 50, &e), WV_OK);
  uint16_t h[50];
  assert_int_equal(wv_dataset_read_features(path, 50, h, &e), WV_OK);
  for (int i = 0; i < 50; i++) assert_true(fabsf(wv_nn_f16_to_f32(h[i]) - x[i]) <= x[i] * 1e-3f);
  assert_int_equal(wv_dataset_read_features(path, 51, h, &e), WV_ERR_FORMAT);
  char *d;
  size_t n;
  assert_int_equal(wv_read_file(path, &d, &n, &e), WV_OK);
  write_bytes(path, (unsigned char *)d, n - 1);
  assert_int_equal(wv_dataset_read_features(path, 50, h, &e), WV_ERR_FORMAT);
  assert_non_null(strstr(e.msg, "truncated"));
  d[40] ^= 1;
  write_bytes(path, (unsigned char *)d, n);
  assert_int_equal(wv_dataset_read_features(path, 50, h, &e), WV_ERR_FORMAT);
  assert_non_null(strstr(e.msg, "checksum"));
  free(d);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_gradient),   cmocka_unit_test(test_training_reduces_loss),
      cmocka_unit_test(test_param_mapping), cmocka_unit_test(test_f16_crc),
      cmocka_unit_test(test_files),      cmocka_unit_test(test_features_file),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
