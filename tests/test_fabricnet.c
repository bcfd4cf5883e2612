/* FabricNet: backward (L1 and the pattern head's cross-entropy) against finite
 * differences, training on a learnable toy set, wv_train on a small rendered dataset (the
 * loss falls; a resumed run equals an uninterrupted one), the camera augmentation,
 * parameter mapping, model and checkpoint files (round trip, every corruption, version 1
 * files), half floats and CRC-32. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include "testutil.h"
#include "util/half.h"
#include "woven/dataset.h"
#include "woven/descriptor.h"
#include "woven/fabricnet.h"
#include "woven/io.h"
#include "woven/nn.h"
#include "woven/render.h"
#include "woven/train.h"
#include "woven/weave.h"

static wv_scene tiny_scene(void) {
  wv_scene s;
  wv_error e;
  assert_int_equal(wv_scene_preset("flat45", &s, &e), WV_OK);
  return s;
}

/* L1 + ce_weight CE, in double from the forward pass (labels may be NULL: L1 only). */
static double net_loss_ce(wv_fabricnet *n, const float *x, const float *y, const int *labels, double ce_weight,
                          int batch) {
  wv_fabricnet_acts a;
  wv_error e;
  assert_int_equal(wv_fabricnet_acts_alloc(&a, batch, &e), WV_OK);
  wv_fabricnet_forward(n, x, batch, &a);
  double s = 0, ce = 0;
  for (int i = 0; i < batch * WV_NET_OUT; i++) s += fabs((double)a.out[i] - y[i]);
  if (labels)
    for (int b = 0; b < batch; b++) ce -= log((double)a.prob[(size_t)b * n->n_cls + labels[b]]);
  wv_fabricnet_acts_free(&a);
  return s / (batch * WV_NET_OUT) + ce_weight * ce / batch;
}

static double net_loss(wv_fabricnet *n, const float *x, const float *y, int batch) {
  return net_loss_ce(n, x, y, NULL, 0, batch);
}

static void test_gradient(void **state) {
  (void)state;
  wv_scene s = tiny_scene();
  wv_fabricnet n;
  wv_error e;
  const int nin = 12, batch = 3;
  assert_int_equal(wv_fabricnet_init(&n, "default", nin, &s, NULL, 7, &e), WV_OK);
  assert_int_equal(n.n_cls, WV_NET_CLASSES);
  /* larger weights than the init so every layer matters */
  float *t[WV_NET_TENSORS];
  size_t len[WV_NET_TENSORS];
  wv_fabricnet_tensors(&n, t, len);
  wv_rng r;
  wv_rng_seed(&r, 3);
  for (int i = 0; i < WV_NET_TENSORS; i++)
    for (size_t j = 0; j < len[i]; j++) t[i][j] *= 2.0f;
  float x[batch * 12], y[batch * WV_NET_OUT];
  const int labels[3] = {3, 0, 15};
  const float cw = 0.5f; /* large enough that the head's share is checked, not drowned */
  wv_rng_fill_uniform(&r, x, sizeof x / sizeof x[0], -1, 1);
  wv_rng_fill_uniform(&r, y, sizeof y / sizeof y[0], 0, 1);
  size_t P = wv_fabricnet_param_count(&n);
  float *g = calloc(P, sizeof(float)), *gt[WV_NET_TENSORS];
  size_t off = 0;
  for (int i = 0; i < WV_NET_TENSORS; i++) gt[i] = g + off, off += len[i];
  wv_fabricnet_acts a;
  assert_int_equal(wv_fabricnet_acts_alloc(&a, batch, &e), WV_OK);
  float l1, ce;
  float loss = wv_fabricnet_backward(&n, x, y, labels, cw, batch, &a, gt, &l1, &ce);
  assert_true(fabs(loss - net_loss_ce(&n, x, y, labels, cw, batch)) < 1e-5);
  assert_true(fabs(l1 - net_loss(&n, x, y, batch)) < 1e-6 && ce > 0);
  /* spot-check entries of every tensor with central differences */
  double worst = 0;
  for (int i = 0; i < WV_NET_TENSORS; i++) {
    /* relative errors with a floor of a tenth of the tensor's largest gradient: the
     * float loss makes tiny derivatives noisy in absolute terms */
    double gmax = 0;
    for (size_t j = 0; j < len[i]; j++) gmax = fmax(gmax, fabs(gt[i][j]));
    for (size_t j = 0; j < len[i]; j += len[i] / 7 + 1) {
      float save = t[i][j], h = 2e-3f;
      t[i][j] = save + h;
      double fp = net_loss_ce(&n, x, y, labels, cw, batch);
      t[i][j] = save - h;
      double fm = net_loss_ce(&n, x, y, labels, cw, batch);
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
  assert_int_equal(wv_fabricnet_init(&n, "default", nin, &s, NULL, 1, &e), WV_OK);
  float *x = malloc(sizeof(float) * N * nin), *y = malloc(sizeof(float) * N * WV_NET_OUT);
  wv_rng r;
  wv_rng_seed(&r, 11);
  wv_rng_fill_uniform(&r, x, (size_t)N * nin, -1, 1);
  for (int i = 0; i < N; i++)
    for (int k = 0; k < WV_NET_OUT; k++) y[i * WV_NET_OUT + k] = 0.5f + 0.4f * sinf(x[i * nin + k] + x[i * nin + k + 1]);
  size_t P = wv_fabricnet_param_count(&n);
  float *g = calloc(P, sizeof(float)), *gt[WV_NET_TENSORS], *t[WV_NET_TENSORS];
  size_t len[WV_NET_TENSORS], off = 0;
  wv_fabricnet_tensors(&n, t, len);
  for (int i = 0; i < WV_NET_TENSORS; i++) gt[i] = g + off, off += len[i];
  wv_nn_adam adam;
  assert_int_equal(wv_nn_adam_init(&adam, P, 1e-3f, &e), WV_OK);
  wv_fabricnet_acts a;
  assert_int_equal(wv_fabricnet_acts_alloc(&a, batch, &e), WV_OK);
  double first = net_loss(&n, x, y, N);
  for (int ep = 0; ep < 60; ep++)
    for (int b = 0; b < N; b += batch) {
      memset(g, 0, P * sizeof(float));
      wv_fabricnet_backward(&n, x + (size_t)b * nin, y + (size_t)b * WV_NET_OUT, NULL, 0, batch, &a, gt, NULL, NULL);
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
  assert_int_equal(wv_fabricnet_init(&n, "default", 4, &s, NULL, 1, &e), WV_OK);
  for (int pat = 0; pat < wv_weave_builtin_count(); pat++) {
    assert_int_equal(wv_params_sample_prior(wv_weave_builtin_name(pat), 99 + pat, &p, &e), WV_OK);
    float y[WV_NET_OUT];
    wv_fabricnet_targets(&p, WV_NET_OUT, y);
    for (int k = 0; k < WV_NET_OUT; k++) assert_true(y[k] >= 0 && y[k] <= 1);
    assert_int_equal(wv_fabricnet_params(&n, y, p.pattern, &q, &e), WV_OK);
    assert_true(fabs(q.density[0] - p.density[0]) < 0.51 && fabs(q.density[1] - p.density[1]) < 0.51);
    for (int k = 0; k < WV_P_REFLECT_COUNT; k++) assert_true(fabs(wv_param_get(&q, k) - wv_param_get(&p, k)) < 1e-4);
    /* the transmission colours are not predicted: their prior mean given the predicted colour */
    for (int y = 0; y < 2; y++)
      for (int c = 0; c < 3; c++) assert_true(q.transmission[y][c] == 0.5 * q.diffuse[y][c]);
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
  assert_int_equal(crc32_z(0, (const unsigned char *)"123456789", 9), 0xcbf43926u); /* the standard check value */
}

static void write_bytes(const char *path, const unsigned char *b, size_t n) {
  FILE *f = fopen(path, "wb");
  assert_non_null(f);
  assert_int_equal(fwrite(b, 1, n, f), n);
  fclose(f);
}

/* Recomputes the payload and header checksums of a patched model file (format 2: a
 * 512-byte header, payload CRC at 504, header CRC at 508 over the bytes before it). */
static void reseal(unsigned char *b, size_t n) {
  uint32_t c = crc32_z(0, b + 512, n - 512);
  for (int i = 0; i < 4; i++) b[504 + i] = (unsigned char)(c >> (8 * i));
  c = crc32_z(0, b, 508);
  for (int i = 0; i < 4; i++) b[508 + i] = (unsigned char)(c >> (8 * i));
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
  assert_int_equal(wv_fabricnet_init(&n, "default", 100, &s, NULL, 5, &e), WV_OK);
  for (int i = 0; i < 100; i++) n.mean[i] = 0.01f * i, n.std[i] = 1 + 0.1f * i;
  assert_int_equal(wv_fabricnet_save(path, &n, &e), WV_OK);
  assert_int_equal(wv_fabricnet_load(path, &m, &e), WV_OK);
  assert_string_equal(m.descriptor, "default");
  assert_string_equal(m.scene, "flat45");
  assert_int_equal(m.n_in, 100);
  for (int i = 0; i < 100; i++) assert_true(m.mean[i] == n.mean[i] && m.std[i] == n.std[i]);
  float *tn[WV_NET_TENSORS], *tm[WV_NET_TENSORS];
  size_t len[WV_NET_TENSORS];
  wv_fabricnet_tensors(&n, tn, len);
  wv_fabricnet_tensors(&m, tm, len);
  assert_int_equal(m.n_cls, WV_NET_CLASSES);
  for (int i = 0; i < WV_NET_TENSORS; i++)
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
  for (int i = 0; i < WV_NET_TENSORS; i++) assert_memory_equal(tn[i], tm[i], len[i] * sizeof(float)); /* f32: exact */
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
  b[512 + 8 * 100] = 0x00, b[512 + 8 * 100 + 1] = 0x7e; /* the first f16 weight: NaN */
  reseal(b, n_bytes);
  write_bytes(bad, b, n_bytes);
  expect_load_fails(bad, "layer 1 weights hold NaN");
  /* a model of another library (the class checksum): refused with a clear message */
  memcpy(b, data, n_bytes);
  b[492] ^= 1;
  uint32_t hc = crc32_z(0, b, 508);
  for (int i = 0; i < 4; i++) b[508 + i] = (unsigned char)(hc >> (8 * i));
  write_bytes(bad, b, n_bytes);
  expect_load_fails(bad, "weave library");
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

/* A version 1 file (no pattern head) still loads, and gives every pattern 1 / count. */
static void test_v1_model(void **state) {
  (void)state;
  const char *dir = tu_tmpdir("fabricnet_v1");
  char path[512], old[512];
  snprintf(path, sizeof path, "%s/v2.bin", dir);
  snprintf(old, sizeof old, "%s/v1.bin", dir);
  wv_scene s = tiny_scene();
  wv_fabricnet n, m;
  wv_error e;
  assert_int_equal(wv_fabricnet_init(&n, "default", 40, &s, NULL, 9, &e), WV_OK);
  n.n_cls = 0; /* the first six tensors only, as version 1 stored them */
  assert_int_equal(wv_fabricnet_save(path, &n, &e), WV_OK);
  char *data;
  size_t len;
  assert_int_equal(wv_read_file(path, &data, &len, &e), WV_OK);
  /* version 2 -> version 1 layout: payload size, payload CRC, header CRC at 488, 496, 500 */
  unsigned char *b = malloc(len);
  memcpy(b, data, 488);
  memcpy(b + 488, data + 496, 8);
  memcpy(b + 496, data + 504, 4);
  b[8] = 1, b[9] = b[10] = b[11] = 0;
  uint32_t hc = crc32_z(0, b, 500);
  for (int i = 0; i < 4; i++) b[500 + i] = (unsigned char)(hc >> (8 * i));
  memcpy(b + 504, data + 512, len - 512);
  write_bytes(old, b, len - 8);
  assert_int_equal(wv_fabricnet_load(old, &m, &e), WV_OK);
  assert_int_equal(m.n_cls, 0);
  assert_true(m.w3[5] == wv_nn_f16_to_f32(wv_f32_to_f16(n.w3[5])) && m.b3[2] == n.b3[2]);
  float feat[40], y[WV_NET_OUT], probs[WV_NET_CLASSES];
  for (int i = 0; i < 40; i++) feat[i] = 0.1f * i;
  assert_int_equal(wv_fabricnet_predict_features(&m, feat, y, probs, &e), WV_OK);
  for (int i = 0; i < WV_NET_CLASSES; i++) assert_true(fabsf(probs[i] - 1.0f / WV_NET_CLASSES) < 1e-7f);
  wv_fabricnet_free(&m);
  /* a model with the head: probabilities indexed like the library, summing to 1 */
  n.n_cls = WV_NET_CLASSES;
  for (int i = 0; i < 40; i++) feat[i] = 0.1f * i;
  assert_int_equal(wv_fabricnet_predict_features(&n, feat, y, probs, &e), WV_OK);
  double sum = 0;
  for (int i = 0; i < WV_NET_CLASSES; i++) assert_true(probs[i] > 0), sum += probs[i];
  assert_true(fabs(sum - 1) < 1e-5);
  free(b), free(data);
  wv_fabricnet_free(&n);
}

/* The camera: deterministic in its seed, different across seeds, 8-bit values. */
static void test_augment(void **state) {
  (void)state;
  wv_scene s;
  tu_centre_window(&s, "flat45", 96, 64, 4);
  wv_params p;
  wv_error e;
  assert_int_equal(wv_params_sample_prior("twill21z", 5, &p, &e), WV_OK);
  wv_render_opts ro = {0};
  wv_image cap = {0}, rad = {0}, a = {0}, b = {0}, c = {0};
  assert_int_equal(wv_render(&s, &p, &ro, &cap, &rad, &e), WV_OK);
  assert_int_equal(wv_camera_augment(&s, &rad, 11, &a, &e), WV_OK);
  assert_int_equal(wv_camera_augment(&s, &rad, 11, &b, &e), WV_OK);
  assert_int_equal(wv_camera_augment(&s, &rad, 12, &c, &e), WV_OK);
  size_t n = (size_t)a.w * a.h * 3;
  assert_int_equal(a.w, s.width);
  assert_memory_equal(a.data, b.data, n * sizeof(float));
  double diff = wv_image_mad(&a, &c), ma = wv_image_mean(&a), mc = wv_image_mean(&cap);
  fprintf(stderr, "augment: mean %.3f (render %.3f), another seed differs by %.4f\n", ma, mc, diff);
  assert_true(diff > 1e-3);
  assert_true(fabs(ma - mc) < 0.25 * mc + 0.02); /* exposure within half a stop, not another picture */
  for (size_t i = 0; i < n; i++) assert_true(fabsf(a.data[i] * 255 - floorf(a.data[i] * 255 + 0.5f)) < 1e-3f);
  wv_image_free(&cap), wv_image_free(&rad), wv_image_free(&a), wv_image_free(&b), wv_image_free(&c);
}

/* A small dataset of every built-in (2 each, 64 x 48 at 2 spp, augmented). */
static void make_dataset(const char *dir) {
  wv_dataset_info info;
  memset(&info, 0, sizeof info);
  wv_error e;
  assert_int_equal(wv_scene_preset("flat45", &info.scene, &e), WV_OK);
  tu_centre_window(&info.scene, "flat45", 64, 48, 2);
  snprintf(info.scene.name, sizeof info.scene.name, "tiny");
  char *sj = wv_scene_to_json(&info.scene);
  snprintf(info.scene_json, sizeof info.scene_json, "%s", sj);
  free(sj);
  wv_descriptor *d;
  assert_int_equal(wv_descriptor_create_default(&d, &e), WV_OK);
  info.version = 2, info.renderer = WV_RENDER_VERSION, info.seed = 4, info.per_pattern = 2;
  info.spp = 2, info.augment = 1, info.n_feat = (int)wv_descriptor_size(d);
  snprintf(info.descriptor, sizeof info.descriptor, "%s", wv_descriptor_name(d));
  assert_int_equal(wv_dataset_info_write(dir, &info, &e), WV_OK);
  char sub[512];
  snprintf(sub, sizeof sub, "%s/samples", dir);
  assert_int_equal(mkdir(sub, 0777), 0);
  float *feat = malloc(sizeof(float) * (size_t)info.n_feat);
  for (int k = 0; k < 2 * wv_weave_builtin_count(); k++) {
    assert_int_equal(wv_dataset_make_sample(dir, &info, k, 0, NULL, NULL, d, feat, &e), WV_OK);
    assert_true(wv_dataset_sample_done(dir, &info, k));
  }
  free(feat);
  wv_descriptor_free(d);
}

/* Stops a build once it has made stop_after samples. */
static int stop_at(void *user, int done, int todo, double seconds) {
  (void)todo, (void)seconds;
  return done >= *(const int *)user;
}

static void assert_same_file(const char *a, const char *b) {
  char *da, *db;
  size_t na, nb;
  wv_error e;
  assert_int_equal(wv_read_file_max(a, 1 << 24, &da, &na, &e), WV_OK);
  assert_int_equal(wv_read_file_max(b, 1 << 24, &db, &nb, &e), WV_OK);
  assert_int_equal(na, nb);
  assert_memory_equal(da, db, na);
  free(da), free(db);
}

/* Writes scene s as a scene file at path. */
static void write_scene(const wv_scene *s, const char *path) {
  char *sj = wv_scene_to_json(s);
  wv_error e;
  assert_non_null(sj);
  assert_int_equal(wv_write_file_atomic(path, sj, strlen(sj), &e), WV_OK);
  free(sj);
}

/* flat45's 64 x 48 centre window at 1 spp ("tiny") as tiny.json in a fresh directory named
 * by tag; its path into path. */
static void write_tiny_scene(const char *tag, char *path, size_t cap) {
  wv_scene s;
  tu_centre_window(&s, "flat45", 64, 48, 1);
  snprintf(s.name, sizeof s.name, "tiny");
  snprintf(path, cap, "%s/tiny.json", tu_tmpdir(tag));
  write_scene(&s, path);
}

/* A build stopped after k samples and run again makes the same files as one run. */
static void test_dataset_build_resumes(void **state) {
  (void)state;
  char scene[512], whole[512], resumed[512];
  write_tiny_scene("ds_scene", scene, sizeof scene);
  snprintf(whole, sizeof whole, "%s", tu_tmpdir("ds_whole"));
  snprintf(resumed, sizeof resumed, "%s", tu_tmpdir("ds_resumed"));
  wv_error e;
  wv_dist one = {0, 1, 0};
  wv_dataset_build_opts o;
  wv_dataset_build_opts_default(&o);
  o.scene = scene, o.dir = whole, o.per_pattern = 1, o.seed = 9, o.jobs = 1;
  wv_dataset_build_result r;
  wv_status st = wv_dataset_build(&one, &o, &r, &e);
  if (st) print_message("%s\n", e.msg);
  assert_int_equal(st, WV_OK);
  int total = r.samples, k = 3;
  assert_true(total > k);
  assert_int_equal(r.rendered, total);
  assert_false(r.stopped);
  /* interrupted after k samples: those are whole, the others not begun */
  o.dir = resumed, o.on_progress = stop_at, o.user = &k;
  assert_int_equal(wv_dataset_build(&one, &o, &r, &e), WV_OK);
  assert_true(r.stopped);
  assert_int_equal(r.rendered, k);
  wv_dataset_info info;
  assert_int_equal(wv_dataset_info_read(resumed, &info, &e), WV_OK);
  int done = 0;
  for (int i = 0; i < total; i++) done += wv_dataset_sample_done(resumed, &info, i);
  assert_int_equal(done, k);
  /* resumed: only the rest is rendered, and every file equals the uninterrupted build's */
  o.on_progress = NULL;
  assert_int_equal(wv_dataset_build(&one, &o, &r, &e), WV_OK);
  assert_int_equal(r.done_before, k);
  assert_int_equal(r.rendered, total - k);
  static const char *const EXT[] = {"json", "png", "feat"};
  for (int i = 0; i < total; i++)
    for (int x = 0; x < 3; x++) {
      char pa[1024], pb[1024];
      wv_dataset_path(whole, &info, i, EXT[x], pa, sizeof pa);
      wv_dataset_path(resumed, &info, i, EXT[x], pb, sizeof pb);
      assert_same_file(pa, pb);
    }
  char ja[600], jb[600];
  snprintf(ja, sizeof ja, "%s/dataset.json", whole);
  snprintf(jb, sizeof jb, "%s/dataset.json", resumed);
  assert_same_file(ja, jb);
}

/* A set drawn as photos show cloths: every sample's yarns 1 to 2.5 pixels apart at the image
 * centre, noise levels over the whole range; the setting is recorded, read back and kept: a
 * build into the same directory with the priors' draws is refused. */
static void test_dataset_photo_draws(void **state) {
  (void)state;
  char scene[512], dir[512];
  write_tiny_scene("dp_scene", scene, sizeof scene);
  snprintf(dir, sizeof dir, "%s", tu_tmpdir("dp_set"));
  wv_error e;
  wv_dist one = {0, 1, 0};
  wv_dataset_build_opts o;
  wv_dataset_build_opts_default(&o);
  o.scene = scene, o.dir = dir, o.per_pattern = 1, o.seed = 9, o.jobs = 1, o.draws = WV_DRAWS_PHOTO;
  wv_dataset_build_result r;
  wv_status st = wv_dataset_build(&one, &o, &r, &e);
  if (st) print_message("%s\n", e.msg);
  assert_int_equal(st, WV_OK);
  wv_dataset_info info;
  assert_int_equal(wv_dataset_info_read(dir, &info, &e), WV_OK);
  assert_int_equal(info.draws, WV_DRAWS_PHOTO);
  double jt[2][2], mmpp;
  assert_true(wv_render_centre_scale(&info.scene, jt, &mmpp));
  /* the priors' draws of the same samples, for comparison */
  wv_dataset_info prior = info;
  prior.draws = WV_DRAWS_PRIOR;
  int n = 400, above6 = 0, dense = 0, prior_dense = 0;
  double lo = 1e9, hi = 0;
  for (int k = 0; k < n; k++) {
    wv_params p, q;
    assert_int_equal(wv_dataset_sample_params(&info, k, &p, &e), WV_OK);
    assert_int_equal(wv_dataset_sample_params(&prior, k, &q, &e), WV_OK);
    assert_string_equal(p.pattern, q.pattern);
    for (int y = 0; y < 2; y++) {
      double px = 25.4 / (p.density[y] * mmpp);
      lo = px < lo ? px : lo, hi = px > hi ? px : hi;
      if (!strcmp(p.pattern, "plain") || !strcmp(p.pattern, "basket")) /* the priors: 140 yarns/inch at most */
        dense += px < 1.4, prior_dense += 25.4 / (q.density[y] * mmpp) < 1.4;
    }
    above6 += p.noise_level > 6;
    assert_memory_equal(p.diffuse, q.diffuse, sizeof p.diffuse); /* the rest as the prior draws it */
  }
  fprintf(stderr, "photo draws: spacing %.3f .. %.3f px, plain and basket yarns under 1.4 px: %d (the priors: %d), noise above 6: %d of %d\n",
          lo, hi, dense, prior_dense, above6, n);
  assert_true(lo >= WV_DATASET_PHOTO_SPACING_LO - 1e-9 && hi <= WV_DATASET_PHOTO_SPACING_HI + 1e-9);
  assert_true(lo < 1.05 && hi > 2.4);
  assert_true(dense > 10 && prior_dense == 0);
  assert_true(above6 > n / 8); /* the priors stop at 5 */
  /* the same directory with the priors' draws: refused, naming the setting */
  o.draws = WV_DRAWS_PRIOR;
  assert_int_equal(wv_dataset_build(&one, &o, &r, &e), WV_ERR_INVALID);
  assert_non_null(strstr(e.msg, "--photo-draws"));
  /* a description with an unknown way of drawing is refused on reading */
  char path[600];
  snprintf(path, sizeof path, "%s/dataset.json", dir);
  char *text = NULL;
  size_t len = 0;
  assert_int_equal(wv_read_file(path, &text, &len, &e), WV_OK);
  char *at = strstr(text, "\"photo\"");
  assert_non_null(at);
  memcpy(at + 1, "fotos", 5);
  assert_int_equal(wv_write_file_atomic(path, text, len, &e), WV_OK);
  free(text);
  assert_int_equal(wv_dataset_info_read(dir, &info, &e), WV_ERR_FORMAT);
  assert_non_null(strstr(e.msg, "draws"));
  /* a scene that does not see the cloth at its image centre (the camera looks along it):
   * refused before anything is written */
  wv_scene side;
  tu_centre_window(&side, "flat45", 64, 48, 1);
  side.cam_look_at[0] = side.cam_pos[0], side.cam_look_at[1] = side.cam_pos[1] + 100;
  side.cam_look_at[2] = side.cam_pos[2], side.cam_up[0] = 0, side.cam_up[1] = 0, side.cam_up[2] = 1;
  char sidefile[512], sidedir[512], sidejson[600];
  snprintf(sidefile, sizeof sidefile, "%s/side.json", tu_tmpdir("dp_side_scene"));
  write_scene(&side, sidefile);
  snprintf(sidedir, sizeof sidedir, "%s/set", tu_tmpdir("dp_side"));
  o.scene = sidefile, o.dir = sidedir, o.draws = WV_DRAWS_PHOTO;
  assert_int_equal(wv_dataset_build(&one, &o, &r, &e), WV_ERR_INVALID);
  print_message("%s\n", e.msg);
  assert_non_null(strstr(e.msg, "image centre"));
  snprintf(sidejson, sizeof sidejson, "%s/dataset.json", sidedir);
  struct stat sb;
  assert_int_not_equal(stat(sidejson, &sb), 0);
}

typedef struct {
  double first, last;
  int n;
} curve;

static void record_epoch(void *user, const wv_train_epoch *ep) {
  curve *c = user;
  if (c->n++ == 0) c->first = ep->train + 0.1 * ep->train_ce;
  c->last = ep->train + 0.1 * ep->train_ce;
}

/* A fresh test directory holding the small rendered set in its ds/ (ds receives that path). */
static const char *train_dir(const char *name, char *ds, size_t n) {
  const char *dir = tu_tmpdir(name);
  snprintf(ds, n, "%s/ds", dir);
  assert_int_equal(mkdir(ds, 0777), 0);
  make_dataset(ds);
  return dir;
}

static void test_train(void **state) {
  (void)state;
  char ds[512], m1[512], m2[512], c1[600], c2[600];
  const char *dir = train_dir("fabricnet_train", ds, sizeof ds);
  snprintf(m1, sizeof m1, "%s/a.bin", dir);
  snprintf(m2, sizeof m2, "%s/b.bin", dir);
  wv_train_opts o;
  wv_train_opts_default(&o);
  o.epochs = 12, o.batch = 8, o.lr = 1e-3, o.val_frac = 0.25, o.checkpoint_every = 3;
  curve cv = {0, 0, 0};
  o.on_epoch = record_epoch, o.user = &cv;
  wv_train_result r;
  wv_error e;
  assert_int_equal(wv_train(ds, m1, &o, &r, &e), WV_OK);
  fprintf(stderr, "wv_train: %d samples (%d train), loss %.4f -> %.4f, validation L1 %.4f, pattern accuracy %.2f\n",
          r.samples, r.train, cv.first, cv.last, r.val_f16, r.val_accuracy);
  assert_int_equal(r.samples, 2 * WV_NET_CLASSES);
  assert_int_equal(cv.n, 12);
  assert_true(cv.last < 0.8 * cv.first);
  /* interrupted after 6 epochs, then resumed to 12: the same weights and Adam state */
  o.epochs = 6, o.on_epoch = NULL;
  assert_int_equal(wv_train(ds, m2, &o, &r, &e), WV_OK);
  o.epochs = 12, o.resume = 1;
  assert_int_equal(wv_train(ds, m2, &o, &r, &e), WV_OK);
  assert_int_equal(r.resumed_epoch, 6);
  snprintf(c1, sizeof c1, "%s.train/checkpoint.bin", m1);
  snprintf(c2, sizeof c2, "%s.train/checkpoint.bin", m2);
  char *a, *b;
  size_t la, lb;
  assert_int_equal(wv_read_file(c1, &a, &la, &e), WV_OK);
  assert_int_equal(wv_read_file(c2, &b, &lb, &e), WV_OK);
  assert_int_equal(la, lb);
  assert_memory_equal(a, b, la);
  free(a), free(b);
  assert_int_equal(wv_read_file(m1, &a, &la, &e), WV_OK);
  assert_int_equal(wv_read_file(m2, &b, &lb, &e), WV_OK);
  assert_int_equal(la, lb);
  assert_memory_equal(a, b, la);
  free(a), free(b);
  /* a second fresh start over an existing checkpoint is refused */
  o.resume = 0;
  assert_int_equal(wv_train(ds, m1, &o, &r, &e), WV_ERR_IO);
  assert_non_null(strstr(e.msg, "--resume"));
}

static void record_ce(void *user, const wv_train_epoch *ep) {
  curve *c = user;
  if (c->n++ == 0) c->first = ep->train_ce;
  c->last = ep->train_ce;
}

/* Fine-tuning the pattern head alone: its cross-entropy falls while every other weight, the
 * feature statistics and so every parameter estimate stay the starting model's, bit for bit. */
static void test_train_pattern_head_only(void **state) {
  (void)state;
  char ds[512], m0[512], m1[512];
  const char *dir = train_dir("fabricnet_head_only", ds, sizeof ds);
  snprintf(m0, sizeof m0, "%s/start.bin", dir);
  snprintf(m1, sizeof m1, "%s/head.bin", dir);
  wv_train_opts o;
  wv_train_opts_default(&o);
  o.epochs = 2, o.batch = 8, o.lr = 1e-3, o.val_frac = 0.25;
  wv_train_result r;
  wv_error e;
  /* without a model to start from there is no head to train alone */
  o.pattern_head_only = 1;
  assert_int_equal(wv_train(ds, m0, &o, &r, &e), WV_ERR_INVALID);
  assert_non_null(strstr(e.msg, "pattern head"));
  o.pattern_head_only = 0;
  assert_int_equal(wv_train(ds, m0, &o, &r, &e), WV_OK);
  curve cv = {0, 0, 0};
  o.epochs = 15, o.lr = 1e-2, o.init = m0, o.pattern_head_only = 1, o.on_epoch = record_ce, o.user = &cv;
  assert_int_equal(wv_train(ds, m1, &o, &r, &e), WV_OK);
  fprintf(stderr, "pattern head alone: training CE %.4f -> %.4f\n", cv.first, cv.last);
  assert_true(cv.last < 0.8 * cv.first);
  wv_fabricnet a, b;
  assert_int_equal(wv_fabricnet_load(m0, &a, &e), WV_OK);
  assert_int_equal(wv_fabricnet_load(m1, &b, &e), WV_OK);
  float *ta[WV_NET_TENSORS], *tb[WV_NET_TENSORS];
  size_t la[WV_NET_TENSORS], lb[WV_NET_TENSORS];
  wv_fabricnet_tensors(&a, ta, la);
  wv_fabricnet_tensors(&b, tb, lb);
  for (int i = 0; i < WV_NET_TENSORS; i++) {
    assert_int_equal(la[i], lb[i]);
    if (i < WV_NET_HEAD_W) assert_memory_equal(ta[i], tb[i], sizeof(float) * la[i]);
  }
  assert_memory_not_equal(ta[WV_NET_HEAD_W], tb[WV_NET_HEAD_W], sizeof(float) * la[WV_NET_HEAD_W]);
  assert_memory_equal(a.mean, b.mean, sizeof(float) * (size_t)a.n_in);
  assert_memory_equal(a.std, b.std, sizeof(float) * (size_t)a.n_in);
  /* The same training with the starting head mixed in at 0.5: the run and its best epoch
   * are the same, so the saved head is the two heads' mean (w4 to f16 rounding, b4 exact
   * to float rounding) and every other weight still the start's. */
  char m2[512];
  snprintf(m2, sizeof m2, "%s/mixed.bin", dir);
  o.on_epoch = NULL, o.head_start_weight = 1.0;
  assert_int_equal(wv_train(ds, m2, &o, &r, &e), WV_ERR_INVALID);
  o.head_start_weight = 0.5, o.pattern_head_only = 0;
  assert_int_equal(wv_train(ds, m2, &o, &r, &e), WV_ERR_INVALID);
  assert_non_null(strstr(e.msg, "mixing"));
  o.pattern_head_only = 1;
  assert_int_equal(wv_train(ds, m2, &o, &r, &e), WV_OK);
  wv_fabricnet c;
  assert_int_equal(wv_fabricnet_load(m2, &c, &e), WV_OK);
  float *tc[WV_NET_TENSORS];
  size_t lc[WV_NET_TENSORS];
  wv_fabricnet_tensors(&c, tc, lc);
  for (int i = 0; i < WV_NET_HEAD_W; i++) assert_memory_equal(ta[i], tc[i], sizeof(float) * la[i]);
  double worst = 0;
  for (int k = WV_NET_HEAD_W; k < WV_NET_TENSORS; k++)
    for (size_t j = 0; j < la[k]; j++) {
      /* f16 (w4): a relative 2^-11 per rounding; f32 (b4): 2^-24 */
      double mean = 0.5 * ((double)ta[k][j] + tb[k][j]), d = fabs(tc[k][j] - mean);
      assert_true(d <= (k == WV_NET_HEAD_W ? 1e-3 : 1e-6) * (fabs(ta[k][j]) + fabs(tb[k][j])) + 1e-9);
      worst = d > worst ? d : worst;
    }
  fprintf(stderr, "pattern head mixed with the start's at 0.5: largest distance from the mean %.2g\n", worst);
  /* not the trained head, nor the start's */
  assert_memory_not_equal(tb[WV_NET_HEAD_W], tc[WV_NET_HEAD_W], sizeof(float) * la[WV_NET_HEAD_W]);
  assert_memory_not_equal(ta[WV_NET_HEAD_W], tc[WV_NET_HEAD_W], sizeof(float) * la[WV_NET_HEAD_W]);
  /* a resumed run has no starting model to mix in */
  o.init = NULL, o.resume = 1;
  assert_int_equal(wv_train(ds, m2, &o, &r, &e), WV_ERR_INVALID);
  wv_fabricnet_free(&a), wv_fabricnet_free(&b), wv_fabricnet_free(&c);
}

/* The features of an 8-bit PNG as a dataset stores them (f16). */
static void png_features(const char *png, wv_descriptor *d, float *feat, uint16_t *out, int n) {
  wv_image img;
  wv_error e;
  assert_int_equal(wv_image_read(png, &img, NULL, &e), WV_OK);
  assert_int_equal(wv_descriptor_forward(d, &img, feat, &e), WV_OK);
  for (int i = 0; i < n; i++) out[i] = wv_f32_to_f16(feat[i]);
  wv_image_free(&img);
}

/* A photo-pair set: each sample rendered lit from the front and from behind, its features
 * the two images' in that order; a model trained on it has the transmission colours among
 * its outputs, is refused where a one-photo model is wanted, and sets k_t. */
static void test_pair_dataset_and_model(void **state) {
  (void)state;
  const char *dir = tu_tmpdir("fabricnet_pair");
  wv_scene s, ts;
  tu_centre_window(&s, "flat45", 64, 48, 1);
  tu_centre_window(&ts, "flat45-back", 64, 48, 1);
  snprintf(s.name, sizeof s.name, "tiny");
  snprintf(ts.name, sizeof ts.name, "tiny-back");
  char scene[600], tscene[600], ds[600], model[600], path[1100], tpath[1100];
  snprintf(scene, sizeof scene, "%s/tiny.json", dir);
  snprintf(tscene, sizeof tscene, "%s/tiny-back.json", dir);
  snprintf(ds, sizeof ds, "%s/ds", dir);
  snprintf(model, sizeof model, "%s/pair.bin", dir);
  write_scene(&s, scene);
  write_scene(&ts, tscene);
  wv_dist solo = {0, 1, 0};
  wv_dataset_build_opts o;
  wv_dataset_build_opts_default(&o);
  o.scene = scene, o.transmission_scene = tscene, o.dir = ds, o.per_pattern = 1, o.seed = 3, o.jobs = 1;
  wv_dataset_build_result r;
  wv_error e;
  wv_status st = wv_dataset_build(&solo, &o, &r, &e);
  if (st) print_message("%s\n", e.msg);
  assert_int_equal(st, WV_OK);
  wv_dataset_info info;
  assert_int_equal(wv_dataset_info_read(ds, &info, &e), WV_OK);
  wv_descriptor *d;
  assert_int_equal(wv_descriptor_create_default(&d, &e), WV_OK);
  int nd = (int)wv_descriptor_size(d);
  assert_int_equal(info.pair, 1);
  assert_int_equal(info.version, 3);
  assert_string_equal(info.tscene.name, "tiny-back");
  assert_int_equal(info.n_feat, 2 * nd);
  /* sample 0's stored features: its front-lit image's, then its back-lit image's */
  float *feat = malloc(sizeof(float) * (size_t)nd);
  uint16_t *stored = malloc(sizeof(uint16_t) * 2 * (size_t)nd), *want = malloc(sizeof(uint16_t) * 2 * (size_t)nd);
  wv_dataset_path(ds, &info, 0, "feat", path, sizeof path);
  assert_int_equal(wv_dataset_read_features(path, 2 * nd, stored, &e), WV_OK);
  wv_dataset_path(ds, &info, 0, "png", path, sizeof path);
  wv_dataset_path(ds, &info, 0, "t.png", tpath, sizeof tpath);
  png_features(path, d, feat, want, nd);
  png_features(tpath, d, feat, want + nd, nd);
  assert_memory_equal(stored, want, 2 * (size_t)nd * sizeof(uint16_t));
  assert_memory_not_equal(stored, stored + nd, (size_t)nd * sizeof(uint16_t));
  /* without its back-lit image a sample is not done */
  assert_true(wv_dataset_sample_done(ds, &info, 0));
  assert_int_equal(unlink(tpath), 0);
  assert_false(wv_dataset_sample_done(ds, &info, 0));
  assert_int_equal(wv_dataset_build(&solo, &o, &r, &e), WV_OK);
  assert_int_equal(r.rendered, 1);
  /* the same directory as a one-photo set is refused */
  o.transmission_scene = NULL;
  assert_int_equal(wv_dataset_build(&solo, &o, &r, &e), WV_ERR_INVALID);
  assert_non_null(strstr(e.msg, "transmission scene"));
  /* training: 27 outputs, the loss falls */
  wv_train_opts to;
  wv_train_opts_default(&to);
  to.epochs = 20, to.batch = 4, to.lr = 1e-3, to.val_frac = 0.25;
  curve cv = {0, 0, 0};
  to.on_epoch = record_epoch, to.user = &cv;
  wv_train_result tr;
  if (wv_train(ds, model, &to, &tr, &e)) fail_msg("%s", e.msg);
  assert_int_equal(tr.outputs, WV_NET_OUT_PAIR);
  assert_true(cv.last < 0.8 * cv.first);
  wv_fabricnet m;
  assert_int_equal(wv_fabricnet_load(model, &m, &e), WV_OK);
  assert_int_equal(m.n_out, WV_NET_OUT_PAIR);
  assert_int_equal(m.n_in, 2 * nd);
  assert_string_equal(m.tscene, "tiny-back");
  assert_int_equal(wv_fabricnet_check_pair(&m, model, &ts, &e), WV_OK);
  assert_int_equal(wv_fabricnet_check_pair(&m, model, NULL, &e), WV_ERR_INVALID);
  assert_non_null(strstr(e.msg, "pair model"));
  wv_scene other = ts;
  snprintf(other.name, sizeof other.name, "other-back");
  assert_int_equal(wv_fabricnet_check_pair(&m, model, &other, &e), WV_ERR_INVALID);
  /* its transmission outputs set k_t (every target of a sample round-trips through them) */
  wv_params p, q;
  assert_int_equal(wv_dataset_sample_params(&info, 5, &p, &e), WV_OK);
  float y[WV_NET_OUT_MAX];
  wv_fabricnet_targets(&p, WV_NET_OUT_PAIR, y);
  q = p;
  for (int t = 0; t < 2; t++)
    for (int c = 0; c < 3; c++) q.transmission[t][c] = 0.5;
  assert_int_equal(wv_fabricnet_transmission(&m, y, &q, &e), WV_OK);
  for (int t = 0; t < 2; t++)
    for (int c = 0; c < 3; c++) assert_true(fabs(q.transmission[t][c] - p.transmission[t][c]) < 1e-5);
  /* a one-photo model predicts no transmission colours and is refused for a pair */
  wv_fabricnet n1;
  assert_int_equal(wv_fabricnet_init(&n1, "default", nd, &s, NULL, 1, &e), WV_OK);
  assert_int_equal(wv_fabricnet_transmission(&n1, y, &q, &e), WV_ERR_INVALID);
  assert_int_equal(wv_fabricnet_check_pair(&n1, "one.bin", &ts, &e), WV_ERR_INVALID);
  wv_fabricnet_free(&n1);
  wv_fabricnet_free(&m);
  wv_descriptor_free(d);
  free(feat), free(stored), free(want);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_gradient),   cmocka_unit_test(test_training_reduces_loss),
      cmocka_unit_test(test_param_mapping), cmocka_unit_test(test_f16_crc),
      cmocka_unit_test(test_files),      cmocka_unit_test(test_features_file),
      cmocka_unit_test(test_v1_model),   cmocka_unit_test(test_augment),
      cmocka_unit_test(test_train),      cmocka_unit_test(test_train_pattern_head_only),
      cmocka_unit_test(test_dataset_build_resumes),
      cmocka_unit_test(test_pair_dataset_and_model), cmocka_unit_test(test_dataset_photo_draws),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
