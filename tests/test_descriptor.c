/* Descriptors: safetensors loading (a tiny VGG-style network written here, checked
 * against a direct computation; every malformed file rejected with a message naming
 * the file and the problem), the VGG-19 pipeline on random weights, gradients
 * against finite differences, the default descriptor's kernels against each other,
 * determinism, and texture separation. */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "testutil.h"
#include "descriptor/internal.h" /* the default descriptor's filters */
#include "woven/descriptor.h"
#include "woven/nn.h"

/* ---- A safetensors writer independent of the library's ---- */
typedef struct {
  char name[48];
  char dtype[8];
  int ndim;
  long long shape[4];
  long long begin, end; /* -1: computed */
  const float *vals;
} tspec;

static uint16_t to_f16(float v) { /* exact for the values the test uses */
  if (v == 0.0f) return 0;
  uint16_t s = v < 0 ? 0x8000 : 0;
  int e;
  float m = frexpf(fabsf(v), &e); /* v = m 2^e, m in [0.5, 1) */
  int exp16 = e - 1 + 15;
  uint16_t frac = (uint16_t)lrintf((2.0f * m - 1.0f) * 1024.0f);
  return (uint16_t)(s | exp16 << 10 | frac);
}

static uint16_t to_bf16(float v) {
  uint32_t u;
  memcpy(&u, &v, 4);
  return (uint16_t)(u >> 16);
}

static size_t numel(const tspec *t) {
  size_t n = 1;
  for (int d = 0; d < t->ndim; d++) n *= (size_t)t->shape[d];
  return n;
}

static int esize(const char *dt) { return !strcmp(dt, "F16") || !strcmp(dt, "BF16") ? 2 : 4; }

/* Writes the tensors; hlen_override > 0 replaces the header length field; extra_json
 * is inserted verbatim into the header object. */
static void write_st(const char *path, const tspec *t, int n, unsigned long long hlen_override,
                     const char *extra_json) {
  char *hdr = malloc(1 << 16);
  size_t hl = 0;
  long long off = 0;
  hl += (size_t)sprintf(hdr + hl, "{\"__metadata__\":{\"format\":\"pt\"}");
  if (extra_json) hl += (size_t)sprintf(hdr + hl, ",%s", extra_json);
  size_t dsize = 0;
  for (int i = 0; i < n; i++) dsize += numel(&t[i]) * esize(t[i].dtype);
  unsigned char *data = calloc(dsize + 1, 1);
  for (int i = 0; i < n; i++) {
    long long nb = (long long)(numel(&t[i]) * esize(t[i].dtype));
    long long b = t[i].begin >= 0 ? t[i].begin : off, e = t[i].end >= 0 ? t[i].end : off + nb;
    hl += (size_t)sprintf(hdr + hl, ",\"%s\":{\"dtype\":\"%s\",\"shape\":[", t[i].name, t[i].dtype);
    for (int d = 0; d < t[i].ndim; d++) hl += (size_t)sprintf(hdr + hl, d ? ",%lld" : "%lld", t[i].shape[d]);
    hl += (size_t)sprintf(hdr + hl, "],\"data_offsets\":[%lld,%lld]}", b, e);
    for (size_t j = 0; j < numel(&t[i]); j++) {
      unsigned char *p = data + off + j * esize(t[i].dtype);
      float v = t[i].vals[j];
      if (esize(t[i].dtype) == 4) {
        uint32_t u;
        memcpy(&u, &v, 4);
        for (int k = 0; k < 4; k++) p[k] = (unsigned char)(u >> (8 * k));
      } else {
        uint16_t u = !strcmp(t[i].dtype, "F16") ? to_f16(v) : to_bf16(v);
        p[0] = (unsigned char)u, p[1] = (unsigned char)(u >> 8);
      }
    }
    off += nb;
  }
  hl += (size_t)sprintf(hdr + hl, "}");
  while (hl % 8) hdr[hl++] = ' ';
  FILE *f = fopen(path, "wb");
  assert_non_null(f);
  unsigned long long L = hlen_override ? hlen_override : hl;
  for (int k = 0; k < 8; k++) fputc((int)((L >> (8 * k)) & 0xff), f);
  fwrite(hdr, 1, hl, f);
  fwrite(data, 1, dsize, f);
  fclose(f);
  free(hdr), free(data);
}

static void write_bytes(const char *path, const void *b, size_t n) {
  FILE *f = fopen(path, "wb");
  assert_non_null(f);
  fwrite(b, 1, n, f);
  fclose(f);
}

/* ---- The tiny network: conv 3->4, pool, conv 4->6, conv 6->5, pool ---- */
static const int tiny_cfg[] = {4, 0, 6, 5, 0};
#define TINY_N 6

static float *tiny_vals[TINY_N];

static void tiny_specs(tspec *t) {
  static const char *names[TINY_N] = {"features.0.weight", "features.0.bias", "features.3.weight",
                                      "features.3.bias",   "features.5.weight", "features.5.bias"};
  static const char *dt[TINY_N] = {"F32", "F32", "F16", "F16", "BF16", "BF16"};
  static const long long shp[TINY_N][4] = {{4, 3, 3, 3}, {4}, {6, 4, 3, 3}, {6}, {5, 6, 3, 3}, {5}};
  wv_rng r;
  wv_rng_seed(&r, 77);
  for (int i = 0; i < TINY_N; i++) {
    memset(&t[i], 0, sizeof t[i]);
    strcpy(t[i].name, names[i]);
    strcpy(t[i].dtype, dt[i]);
    t[i].ndim = i % 2 ? 1 : 4;
    memcpy(t[i].shape, shp[i], sizeof shp[i]);
    t[i].begin = t[i].end = -1;
    if (!tiny_vals[i]) {
      size_t n = numel(&t[i]);
      tiny_vals[i] = malloc(sizeof(float) * n);
      /* Multiples of 1/64 in [-1/2, 1/2]: exact in F32, F16 and BF16. */
      for (size_t j = 0; j < n; j++) tiny_vals[i][j] = (float)((int)(wv_rng_u64(&r) % 65) - 32) / 64.0f;
    }
    t[i].vals = tiny_vals[i];
  }
}

/* Direct computation in double: normalise, conv + ReLU, pools, Grams. */
static void tiny_reference(const wv_image *img, double *gram) {
  static const double mean[3] = {0.485, 0.456, 0.406}, sd[3] = {0.229, 0.224, 0.225};
  int w = img->w, h = img->h, c = 3;
  double *a = malloc(sizeof(double) * 3 * w * h);
  for (int ch = 0; ch < 3; ch++)
    for (int i = 0; i < w * h; i++) a[ch * w * h + i] = (img->data[3 * i + ch] - mean[ch]) / sd[ch];
  int conv = 0;
  size_t goff = 0;
  for (int L = 0; L < 5; L++) {
    if (tiny_cfg[L] > 0) {
      int oc = tiny_cfg[L];
      const float *W = tiny_vals[2 * conv], *B = tiny_vals[2 * conv + 1];
      double *o = malloc(sizeof(double) * oc * w * h);
      for (int k = 0; k < oc; k++)
        for (int y = 0; y < h; y++)
          for (int x = 0; x < w; x++) {
            double s = B[k];
            for (int ci = 0; ci < c; ci++)
              for (int i = 0; i < 3; i++)
                for (int j = 0; j < 3; j++) {
                  int yy = y + i - 1, xx = x + j - 1;
                  if (yy >= 0 && yy < h && xx >= 0 && xx < w)
                    s += W[((k * c + ci) * 3 + i) * 3 + j] * a[(ci * h + yy) * w + xx];
                }
            o[(k * h + y) * w + x] = s > 0 ? s : 0;
          }
      free(a);
      a = o, c = oc, conv++;
    } else {
      int ow = w / 2, oh = h / 2;
      double *o = malloc(sizeof(double) * c * ow * oh);
      for (int k = 0; k < c; k++)
        for (int y = 0; y < oh; y++)
          for (int x = 0; x < ow; x++)
            o[(k * oh + y) * ow + x] =
                0.25 * (a[(k * h + 2 * y) * w + 2 * x] + a[(k * h + 2 * y) * w + 2 * x + 1] +
                        a[(k * h + 2 * y + 1) * w + 2 * x] + a[(k * h + 2 * y + 1) * w + 2 * x + 1]);
      free(a);
      a = o, w = ow, h = oh;
      for (int i = 0; i < c; i++)
        for (int j = 0; j < c; j++) {
          double s = 0;
          for (int p = 0; p < w * h; p++) s += a[i * w * h + p] * a[j * w * h + p];
          gram[goff + i * c + j] = s / (w * h);
        }
      goff += (size_t)c * c;
    }
  }
  free(a);
}

static void random_image(wv_image *img, int w, int h, uint64_t seed) {
  wv_error err;
  assert_int_equal(wv_image_alloc(img, w, h, 3, &err), WV_OK);
  wv_rng r;
  wv_rng_seed(&r, seed);
  wv_rng_fill_uniform(&r, img->data, (size_t)w * h * 3, 0, 1);
}

static void test_tiny_network(void **state) {
  (void)state;
  const char *dir = tu_tmpdir("desc_tiny");
  assert_non_null(dir);
  char path[600];
  snprintf(path, sizeof path, "%s/tiny.safetensors", dir);
  tspec t[TINY_N];
  tiny_specs(t);
  write_st(path, t, TINY_N, 0, NULL);
  wv_descriptor *d;
  wv_error err = {0};
  assert_int_equal(wv_descriptor_create_vgg(path, tiny_cfg, 5, &d, &err), WV_OK);
  assert_int_equal(wv_descriptor_size(d), 4 * 4 + 5 * 5);
  assert_int_equal(wv_descriptor_layer_count(d), 2);
  int ch;
  size_t off;
  assert_int_equal(wv_descriptor_layer_info(d, 1, &ch, &off, &err), WV_OK);
  assert_int_equal(ch, 5);
  assert_int_equal(off, 16);
  assert_int_equal(wv_descriptor_layer_info(d, 2, &ch, &off, &err), WV_ERR_INVALID);
  wv_image img;
  random_image(&img, 21, 18, 5); /* odd width: pooling floors */
  float g[41];
  double ref[41];
  assert_int_equal(wv_descriptor_forward(d, &img, g, &err), WV_OK);
  tiny_reference(&img, ref);
  double worst = 0;
  for (int i = 0; i < 41; i++) {
    double e = fabs(g[i] - ref[i]) / (1e-3 + fabs(ref[i]));
    if (e > worst) worst = e;
  }
  fprintf(stderr, "tiny network vs direct computation: worst relative error %.2e\n", worst);
  assert_true(worst < 1e-4);
  /* Layer weights scale the blocks. */
  float lw[2] = {2.0f, 0.5f}, g2[41];
  assert_int_equal(wv_descriptor_set_layer_weights(d, lw, &err), WV_OK);
  assert_int_equal(wv_descriptor_forward(d, &img, g2, &err), WV_OK);
  for (int i = 0; i < 41; i++) assert_true(fabsf(g2[i] - g[i] * (i < 16 ? 2.0f : 0.5f)) <= 1e-6f * (1 + fabsf(g[i])));
  wv_image_free(&img);
  wv_descriptor_free(d);
}

/* ---- Malformed files ---- */
static void expect_reject(const char *path, wv_status code, const char *what) {
  wv_descriptor *d = NULL;
  wv_error err = {0};
  wv_status rc = wv_descriptor_create_vgg(path, tiny_cfg, 5, &d, &err);
  fprintf(stderr, "  rejected: %s\n", err.msg);
  assert_int_equal(rc, code);
  assert_null(d);
  assert_non_null(strstr(err.msg, path));
  if (!strstr(err.msg, what)) {
    fprintf(stderr, "message lacks '%s'\n", what);
    fail();
  }
}

static void test_malformed(void **state) {
  (void)state;
  const char *dir = tu_tmpdir("desc_bad");
  assert_non_null(dir);
  char path[600];
  tspec t[TINY_N], m[TINY_N];
  tiny_specs(t);
  int k = 0;
#define NEXT() (snprintf(path, sizeof path, "%s/bad%02d.safetensors", dir, k++), memcpy(m, t, sizeof m))

  NEXT();
  expect_reject(path, WV_ERR_IO, "cannot open"); /* no such file */

  NEXT();
  write_bytes(path, "\x10\0\0\0\0", 5);
  expect_reject(path, WV_ERR_FORMAT, "too short");

  NEXT();
  write_st(path, m, TINY_N, 1000000, NULL);
  expect_reject(path, WV_ERR_FORMAT, "exceeds the file");

  NEXT();
  write_bytes(path, "\x0a\0\0\0\0\0\0\0{\"a\": [1,", 18);
  expect_reject(path, WV_ERR_FORMAT, "not valid JSON");

  NEXT();
  write_bytes(path, "\x08\0\0\0\0\0\0\0[1, 2]  ", 16);
  expect_reject(path, WV_ERR_FORMAT, "not a JSON object");

  NEXT();
  write_st(path, m, TINY_N, 0, "\"features.0.bias\":{\"dtype\":\"F32\",\"shape\":[0],\"data_offsets\":[0,0]}");
  expect_reject(path, WV_ERR_FORMAT, "duplicate");

  NEXT();
  strcpy(m[0].dtype, "I32"); /* same size as F32, so only the dtype is wrong */
  write_st(path, m, TINY_N, 0, NULL);
  expect_reject(path, WV_ERR_FORMAT, "dtype I32");

  NEXT();
  strcpy(m[2].dtype, "F33");
  write_st(path, m, TINY_N, 0, NULL);
  expect_reject(path, WV_ERR_FORMAT, "unknown dtype 'F33'");

  NEXT();
  m[2].shape[0] = 4, m[2].shape[1] = 6; /* same size, transposed */
  write_st(path, m, TINY_N, 0, NULL);
  expect_reject(path, WV_ERR_FORMAT, "'features.3.weight' has shape [4, 6, 3, 3], expected [6, 4, 3, 3]");

  NEXT();
  m[4].ndim = 2, m[4].shape[1] = 54; /* same size, wrong rank */
  write_st(path, m, TINY_N, 0, NULL);
  expect_reject(path, WV_ERR_FORMAT, "has shape [5, 54], expected");

  NEXT();
  m[1].begin = 432, m[1].end = 452; /* features.0.bias: 20 bytes for 4 floats */
  write_st(path, m, TINY_N, 0, NULL);
  expect_reject(path, WV_ERR_FORMAT, "[432, 452] hold 20 bytes but shape [4] of F32 needs 16");

  NEXT();
  m[5].begin = 100000, m[5].end = 100010; /* beyond the end of the file */
  write_st(path, m, TINY_N, 0, NULL);
  expect_reject(path, WV_ERR_FORMAT, "outside the file");

  NEXT();
  m[5].begin = 10, m[5].end = 20; /* inside features.0.weight */
  write_st(path, m, TINY_N, 0, NULL);
  expect_reject(path, WV_ERR_FORMAT, "overlap");

  NEXT();
  m[3].begin = -8, m[3].end = 4;
  write_st(path, m, TINY_N, 0, NULL);
  expect_reject(path, WV_ERR_FORMAT, "invalid data_offsets");

  NEXT();
  write_st(path, m, TINY_N - 1, 0, NULL); /* no features.5.bias */
  expect_reject(path, WV_ERR_FORMAT, "'features.5.bias' is missing");

  NEXT();
  float nanv[4] = {0.1f, NAN, 0.2f, 0.3f};
  m[1].vals = nanv;
  write_st(path, m, TINY_N, 0, NULL);
  expect_reject(path, WV_ERR_FORMAT, "NaN");

  NEXT();
  write_st(path, m, TINY_N, 0, "\"features.9.weight\":{\"dtype\":\"F32\",\"shape\":\"big\",\"data_offsets\":[0,0]}");
  expect_reject(path, WV_ERR_FORMAT, "no valid shape");
#undef NEXT
  /* Descriptor-level argument errors. */
  wv_descriptor *d = NULL;
  wv_error err = {0};
  assert_int_equal(wv_descriptor_create("vgg19", NULL, &d, &err), WV_ERR_INVALID);
  assert_non_null(strstr(err.msg, "--vgg19-weights"));
  assert_int_equal(wv_descriptor_create("resnet", NULL, &d, &err), WV_ERR_INVALID);
  assert_non_null(strstr(err.msg, "unknown descriptor 'resnet'"));
  static const int nopool[] = {4, 4};
  assert_int_equal(wv_descriptor_create_vgg("x", nopool, 2, &d, &err), WV_ERR_INVALID);
}

/* ---- Gradient checks ----
 * 1. Against an independent double-precision reference of the same network (where the
 *    test has one): per-pixel central differences with a tiny step, exact up to
 *    rounding. 2. Against the descriptor itself in float: directional derivatives
 *    along the gradient and along the gradient with every component scaled at random
 *    (large, coherent derivatives, so float rounding stays small). */
typedef double (*ref_loss_fn)(const wv_image *img, const float *dg, void *ctx);

static double loss_at(wv_descriptor *d, const wv_image *img, const float *dg, float *g) {
  wv_error err;
  assert_int_equal(wv_descriptor_forward(d, img, g, &err), WV_OK);
  double s = 0;
  for (size_t i = 0; i < wv_descriptor_size(d); i++) s += (double)dg[i] * g[i];
  return s;
}

static void check_descriptor_gradient(wv_descriptor *d, int w, int h, double tol, ref_loss_fn ref,
                                      void *ctx) {
  wv_image img, dimg, probe;
  wv_error err;
  random_image(&img, w, h, 21);
  assert_int_equal(wv_image_alloc(&dimg, w, h, 3, &err), WV_OK);
  assert_int_equal(wv_image_alloc(&probe, w, h, 3, &err), WV_OK);
  size_t n = wv_descriptor_size(d), np = (size_t)w * h * 3;
  float *dg = malloc(sizeof(float) * n), *g = malloc(sizeof(float) * n),
        *g2 = malloc(sizeof(float) * n);
  wv_rng r;
  wv_rng_seed(&r, 22);
  wv_rng_fill_uniform(&r, dg, n, -1, 1);
  assert_int_equal(wv_descriptor_backward(d, &img, dg, g, &dimg, &err), WV_OK);
  /* The Gram from backward equals forward's. */
  double f0 = loss_at(d, &img, dg, g2);
  for (size_t i = 0; i < n; i++) assert_true(g[i] == g2[i]);
  double gmax = 0;
  for (size_t i = 0; i < np; i++) gmax = fmax(gmax, fabs(dimg.data[i]));
  if (ref) {
    double fr = ref(&img, dg, ctx);
    fprintf(stderr, "%s %dx%d: sum(dgram .* gram) %.8g, double-precision reference %.8g\n",
            wv_descriptor_name(d), w, h, f0, fr);
    assert_true(fabs(f0 - fr) <= 1e-5 * fabs(fr) + 1e-6);
    double worst = 0;
    memcpy(probe.data, img.data, sizeof(float) * np);
    for (int k = 0; k < 24; k++) {
      /* Corners, edges and random interior pixels, every channel. */
      int x = k < 4 ? (k % 2) * (w - 1) : (int)(wv_rng_u64(&r) % (uint64_t)w);
      int y = k < 4 ? (k / 2) * (h - 1) : (int)(wv_rng_u64(&r) % (uint64_t)h);
      size_t i = ((size_t)y * w + x) * 3 + (size_t)k % 3;
      float save = img.data[i], up = save + 1e-4f, dn = save - 1e-4f;
      probe.data[i] = up;
      double fp = ref(&probe, dg, ctx);
      probe.data[i] = dn;
      double fm = ref(&probe, dg, ctx);
      probe.data[i] = save;
      double num = (fp - fm) / ((double)up - (double)dn);
      double e = fabs(num - dimg.data[i]) / (fabs(num) + fabs(dimg.data[i]) + 1e-2 * gmax);
      if (e > worst) worst = e;
      if (e > 1e-3) {
        fprintf(stderr, "pixel (%d, %d) channel %d: gradient %.6g, reference finite difference %.6g\n",
                x, y, k % 3, dimg.data[i], num);
        fail();
      }
    }
    fprintf(stderr, "%s %dx%d: 24 pixel derivatives vs the reference, worst relative error %.1e\n",
            wv_descriptor_name(d), w, h, worst);
  }
  float *v = malloc(sizeof(float) * np);
  for (int dir = 0; dir < 2; dir++) {
    double vmax = 0, ana = 0;
    for (size_t i = 0; i < np; i++) {
      v[i] = dir == 0 ? dimg.data[i] : dimg.data[i] * wv_rng_uniform(&r);
      vmax = fmax(vmax, fabs(v[i]));
    }
    for (size_t i = 0; i < np; i++) {
      v[i] = (float)(v[i] / vmax);
      ana += (double)v[i] * dimg.data[i];
    }
    /* Piecewise quadratic (ReLU kinks): the error from kinks shrinks with the step while
     * float rounding grows; take the best of three small steps. */
    double num = 0, rel = 1e30;
    for (float eps = 2.5e-4f; eps > 5e-5f; eps /= 2) {
      for (size_t i = 0; i < np; i++) probe.data[i] = img.data[i] + eps * v[i];
      double fp = loss_at(d, &probe, dg, g);
      for (size_t i = 0; i < np; i++) probe.data[i] = img.data[i] - eps * v[i];
      double fm = loss_at(d, &probe, dg, g);
      double nd = (fp - fm) / (2 * (double)eps), e = fabs(nd - ana) / fabs(ana);
      if (e < rel) rel = e, num = nd;
    }
    fprintf(stderr, "%s %dx%d gradient along %s: analytic %.6g, finite difference %.6g (rel. error %.1e)\n",
            wv_descriptor_name(d), w, h, dir ? "the randomly scaled gradient" : "the gradient", ana,
            num, rel);
    assert_true(rel < tol);
  }
  free(v), free(dg), free(g), free(g2);
  wv_image_free(&img), wv_image_free(&dimg), wv_image_free(&probe);
}

static double tiny_ref_loss(const wv_image *img, const float *dg, void *ctx) {
  (void)ctx;
  double g[41], s = 0;
  tiny_reference(img, g);
  for (int i = 0; i < 41; i++) s += dg[i] * g[i];
  return s;
}

/* The default descriptor in double precision, from its own filters. */
typedef struct {
  wv_descriptor *d;
  float lw[5];
} default_ref;

static double default_ref_loss(const wv_image *img, const float *dg, void *ctx) {
  static const double mean[3] = {0.485, 0.456, 0.406}, sd[3] = {0.229, 0.224, 0.225};
  default_ref *R = ctx;
  int w = img->w, h = img->h, k, c;
  const float *W;
  double *a = malloc(sizeof(double) * 3 * w * h), loss = 0;
  for (int ch = 0; ch < 3; ch++)
    for (int i = 0; i < w * h; i++) a[ch * w * h + i] = (img->data[3 * i + ch] - mean[ch]) / sd[ch];
  size_t off = 0;
  int levels = wv_descriptor_default_filters(R->d, 0, &k, &c, &W);
  assert_true(levels > 0);
  for (int s = 0; s < levels; s++) {
    if (s) { /* 2x2 average pooling */
      int pw = w / 2, ph = h / 2;
      double *b = malloc(sizeof(double) * 3 * pw * ph);
      for (int ch = 0; ch < 3; ch++)
        for (int y = 0; y < ph; y++)
          for (int x = 0; x < pw; x++) {
            const double *q = a + ((size_t)ch * h + 2 * y) * w + 2 * x;
            b[((size_t)ch * ph + y) * pw + x] = 0.25 * (q[0] + q[1] + q[w] + q[w + 1]);
          }
      free(a);
      a = b, w = pw, h = ph;
    }
    wv_descriptor_default_filters(R->d, s, &k, &c, &W);
    int oh = h - k + 1, ow = w - k + 1, np = oh * ow;
    double *F = malloc(sizeof(double) * c * np);
    for (int o = 0; o < c; o++)
      for (int y = 0; y < oh; y++)
        for (int x = 0; x < ow; x++) {
          double v = 0;
          for (int ch = 0; ch < 3; ch++)
            for (int i = 0; i < k; i++)
              for (int j = 0; j < k; j++)
                v += (double)W[((o * 3 + ch) * k + i) * k + j] * a[((size_t)ch * h + y + i) * w + x + j];
          F[(size_t)o * np + y * ow + x] = v > 0 ? v : 0;
        }
    for (int i = 0; i < c; i++)
      for (int j = i; j < c; j++) {
        double g = 0;
        for (int p = 0; p < np; p++) g += F[(size_t)i * np + p] * F[(size_t)j * np + p];
        g *= R->lw[s] / np;
        loss += g * (i == j ? dg[off + i * c + i] : (double)dg[off + i * c + j] + dg[off + j * c + i]);
      }
    off += (size_t)c * c;
    free(F);
  }
  free(a);
  return loss;
}

static void test_tiny_gradient(void **state) {
  (void)state;
  const char *dir = tu_tmpdir("desc_tinygrad");
  char path[600];
  snprintf(path, sizeof path, "%s/tiny.safetensors", dir);
  tspec t[TINY_N];
  tiny_specs(t);
  write_st(path, t, TINY_N, 0, NULL);
  wv_descriptor *d;
  wv_error err;
  assert_int_equal(wv_descriptor_create_vgg(path, tiny_cfg, 5, &d, &err), WV_OK);
  check_descriptor_gradient(d, 33, 20, 5e-3, tiny_ref_loss, NULL);
  wv_descriptor_free(d);
}

static void test_default_gradient(void **state) {
  (void)state;
  wv_descriptor *d;
  wv_error err;
  assert_int_equal(wv_descriptor_create_default(&d, &err), WV_OK);
  default_ref R = {d, {1, 1, 1, 1, 1}};
  check_descriptor_gradient(d, 61, 50, 5e-3, default_ref_loss, &R);
  /* With layer weights the gradient follows. */
  default_ref R2 = {d, {1.0f, 0.5f, 2.0f, 0.0f, 1.5f}};
  assert_int_equal(wv_descriptor_set_layer_weights(d, R2.lw, &err), WV_OK);
  check_descriptor_gradient(d, 83, 66, 5e-3, default_ref_loss, &R2);
  wv_descriptor_free(d);
}

/* Every kernel the CPU runs (AVX-512, AVX2, baseline) gives the widest one's Gram and
 * gradient up to float rounding (the widest one passes the finite-difference checks
 * above). The gradient without a Gram output, and everything on one thread, are bit
 * for bit the same. */
static double max_rel(const float *a, const float *b, size_t n) { /* max |a - b| / max |b| */
  double d = 0, m = 0;
  for (size_t i = 0; i < n; i++) d = fmax(d, fabs((double)a[i] - b[i])), m = fmax(m, fabs(b[i]));
  return d / m;
}

static void test_default_kernels(void **state) {
  (void)state;
  wv_descriptor *d;
  wv_error err;
  assert_int_equal(wv_descriptor_create_default(&d, &err), WV_OK);
  int widest = wv_descriptor_default_kernel(d, -1);
  assert_true(widest >= WV_DESC_KERNEL_BASE && widest <= WV_DESC_KERNEL_AVX512);
  /* 211 x 90: every level's last vector is partial at every vector width. */
  int w = 211, h = 90;
  wv_image img, dimg, dimg2;
  random_image(&img, w, h, 31);
  assert_int_equal(wv_image_alloc(&dimg, w, h, 3, &err), WV_OK);
  assert_int_equal(wv_image_alloc(&dimg2, w, h, 3, &err), WV_OK);
  size_t n = wv_descriptor_size(d), np = (size_t)w * h * 3;
  float *dg = malloc(sizeof(float) * n), *g0 = malloc(sizeof(float) * n),
        *g = malloc(sizeof(float) * n);
  wv_rng r;
  wv_rng_seed(&r, 32);
  wv_rng_fill_uniform(&r, dg, n, -1, 1);
  assert_int_equal(wv_descriptor_backward(d, &img, dg, g0, &dimg, &err), WV_OK);
  assert_int_equal(wv_descriptor_backward(d, &img, dg, NULL, &dimg2, &err), WV_OK);
  assert_memory_equal(dimg.data, dimg2.data, sizeof(float) * np);
  int nt = omp_get_max_threads();
  omp_set_num_threads(1);
  assert_int_equal(wv_descriptor_backward(d, &img, dg, g, &dimg2, &err), WV_OK);
  omp_set_num_threads(nt);
  assert_memory_equal(g0, g, sizeof(float) * n);
  assert_memory_equal(dimg.data, dimg2.data, sizeof(float) * np);
  for (int k = widest - 1; k >= WV_DESC_KERNEL_BASE; k--) {
    assert_int_equal(wv_descriptor_default_kernel(d, k), k);
    assert_int_equal(wv_descriptor_backward(d, &img, dg, g, &dimg2, &err), WV_OK);
    double eg = max_rel(g, g0, n), ed = max_rel(dimg2.data, dimg.data, np);
    fprintf(stderr, "default kernel %d vs %d at %dx%d: Gram %.1e, gradient %.1e (max |diff| / max)\n", k,
            widest, w, h, eg, ed);
    assert_true(eg < 1e-5 && ed < 1e-5);
  }
  free(dg), free(g0), free(g);
  wv_image_free(&img), wv_image_free(&dimg), wv_image_free(&dimg2);
  wv_descriptor_free(d);
}

/* ---- VGG-19 on random weights ---- */
static const int vgg_cfg[] = {64,  64,  0,   128, 128, 0,   256, 256, 256, 256, 0,
                              512, 512, 512, 512, 0,   512, 512, 512, 512, 0};

static void test_vgg19_random(void **state) {
  (void)state;
  const char *dir = tu_tmpdir("desc_vgg19");
  char path[600];
  snprintf(path, sizeof path, "%s/vgg19_random.safetensors", dir);
  tspec t[32];
  float *vals[32];
  int n = 0, idx = 0, c = 3;
  wv_rng r;
  wv_rng_seed(&r, 19);
  for (int i = 0; i < 21; i++) {
    if (!vgg_cfg[i]) {
      idx++;
      continue;
    }
    for (int wb = 0; wb < 2; wb++) {
      memset(&t[n], 0, sizeof t[n]);
      snprintf(t[n].name, sizeof t[n].name, "features.%d.%s", idx, wb ? "bias" : "weight");
      strcpy(t[n].dtype, "BF16"); /* half the file of F32 */
      t[n].ndim = wb ? 1 : 4;
      t[n].shape[0] = vgg_cfg[i], t[n].shape[1] = c, t[n].shape[2] = t[n].shape[3] = 3;
      t[n].begin = t[n].end = -1;
      size_t cnt = numel(&t[n]);
      vals[n] = malloc(sizeof(float) * cnt);
      float lim = wb ? 0.01f : sqrtf(6.0f / (9.0f * c)); /* He-uniform */
      wv_rng_fill_uniform(&r, vals[n], cnt, -lim, lim);
      t[n].vals = vals[n];
      n++;
    }
    c = vgg_cfg[i];
    idx += 2;
  }
  write_st(path, t, n, 0, NULL);
  for (int i = 0; i < n; i++) free(vals[i]);
  wv_descriptor *d;
  wv_error err = {0};
  assert_int_equal(wv_descriptor_create("vgg19", path, &d, &err), WV_OK);
  remove(path);
  assert_string_equal(wv_descriptor_name(d), "vgg19");
  assert_int_equal(wv_descriptor_size(d), 610304);
  assert_int_equal(wv_descriptor_layer_count(d), 5);
  static const int chans[5] = {64, 128, 256, 512, 512};
  size_t off = 0;
  for (int l = 0; l < 5; l++) {
    int ch;
    size_t o;
    assert_int_equal(wv_descriptor_layer_info(d, l, &ch, &o, &err), WV_OK);
    assert_int_equal(ch, chans[l]);
    assert_int_equal(o, off);
    off += (size_t)ch * ch;
  }
  assert_int_equal(wv_descriptor_min_side(d), 32);
  wv_image small;
  random_image(&small, 31, 64, 1);
  float *g = malloc(sizeof(float) * 610304);
  assert_int_equal(wv_descriptor_forward(d, &small, g, &err), WV_ERR_INVALID);
  assert_non_null(strstr(err.msg, "at least 32 x 32"));
  wv_image_free(&small);
  wv_image img;
  random_image(&img, 64, 64, 2);
  assert_int_equal(wv_descriptor_forward(d, &img, g, &err), WV_OK);
  int nonzero = 0;
  for (size_t i = 0; i < 610304; i++) {
    assert_true(isfinite(g[i]));
    nonzero += g[i] != 0.0f;
  }
  assert_true(nonzero > 300000);
  /* Gram blocks are symmetric with a non-negative diagonal. */
  for (int l = 0; l < 5; l++) {
    int ch;
    size_t o;
    wv_descriptor_layer_info(d, l, &ch, &o, &err);
    for (int i = 0; i < ch; i += 7) {
      assert_true(g[o + (size_t)i * ch + i] >= 0.0f);
      for (int j = 0; j < ch; j += 5) assert_true(g[o + (size_t)i * ch + j] == g[o + (size_t)j * ch + i]);
    }
  }
  free(g);
  wv_image_free(&img);
  check_descriptor_gradient(d, 64, 48, 5e-3, NULL, NULL);
  wv_descriptor_free(d);
}

/* ---- Default descriptor: determinism, input checks ---- */
static void test_default_determinism(void **state) {
  (void)state;
  wv_descriptor *a, *b;
  wv_error err = {0};
  assert_int_equal(wv_descriptor_create("default", NULL, &a, &err), WV_OK);
  assert_int_equal(wv_descriptor_create_default(&b, &err), WV_OK);
  assert_string_equal(wv_descriptor_name(a), "default");
  size_t n = wv_descriptor_size(a);
  assert_true(n >= 10000 && n <= 40000);
  wv_image img, img2;
  random_image(&img, 130, 100, 3);
  random_image(&img2, 96, 80, 4);
  float *g1 = malloc(sizeof(float) * n), *g2 = malloc(sizeof(float) * n),
        *g3 = malloc(sizeof(float) * n);
  assert_int_equal(wv_descriptor_forward(a, &img, g1, &err), WV_OK);
  assert_int_equal(wv_descriptor_forward(b, &img, g2, &err), WV_OK);
  assert_memory_equal(g1, g2, sizeof(float) * n);
  /* A different size in between re-sizes the buffers; the result is unchanged. */
  assert_int_equal(wv_descriptor_forward(a, &img2, g3, &err), WV_OK);
  assert_int_equal(wv_descriptor_forward(a, &img, g3, &err), WV_OK);
  assert_memory_equal(g1, g3, sizeof(float) * n);
  /* Input checks. */
  wv_image small;
  assert_int_equal(wv_descriptor_min_side(a), 48);
  random_image(&small, 47, 200, 5);
  assert_int_equal(wv_descriptor_forward(a, &small, g1, &err), WV_ERR_INVALID);
  assert_non_null(strstr(err.msg, "at least 48 x 48"));
  wv_image_free(&small);
  img.data[7] = NAN;
  assert_int_equal(wv_descriptor_forward(a, &img, g1, &err), WV_ERR_INVALID);
  assert_non_null(strstr(err.msg, "NaN"));
  free(g1), free(g2), free(g3);
  wv_image_free(&img), wv_image_free(&img2);
  wv_descriptor_free(a), wv_descriptor_free(b);
}

/* ---- Separation on synthetic woven textures ---- */
typedef struct {
  int pattern;    /* 0 plain, 1 twill 3/1, 2 satin 5 */
  float period;   /* yarn spacing in pixels */
  float warp[3], weft[3];
} weave;

static int warp_on_top(int pattern, int i, int j) {
  switch (pattern) {
  case 0: return (i + j) % 2 == 0;
  case 1: return ((i - j) % 4 + 4) % 4 != 0; /* 3 up 1 down, shifting by one each row */
  default: return ((2 * i - j) % 5 + 5) % 5 == 0 ? 0 : 1;
  }
}

static float hashf(uint64_t a, uint64_t b) { /* uniform in [0,1) from two integers */
  wv_rng r;
  wv_rng_seed(&r, a * 0x9e3779b97f4a7c15ULL ^ (b + 0x632be59bd9b4e019ULL));
  return wv_rng_uniform(&r);
}

/* Yarns with a rounded cross-section profile, per-yarn brightness and position
 * jitter and pixel noise, all drawn from seed; supersampled 3x3. */
static void render_weave(wv_image *img, int w, int h, const weave *p, uint64_t seed) {
  wv_error err;
  assert_int_equal(wv_image_alloc(img, w, h, 3, &err), WV_OK);
  wv_rng r;
  wv_rng_seed(&r, seed);
  for (int y = 0; y < h; y++)
    for (int x = 0; x < w; x++) {
      float acc[3] = {0, 0, 0};
      for (int s = 0; s < 9; s++) {
        float u = (x + (s % 3 + 0.5f) / 3) / p->period, v = (y + (s / 3 + 0.5f) / 3) / p->period;
        int i = (int)floorf(u), j = (int)floorf(v);
        float fu = u - i + 0.15f * (hashf(seed, (uint64_t)i) - 0.5f);
        float fv = v - j + 0.15f * (hashf(seed + 1, (uint64_t)j) - 0.5f);
        int top = warp_on_top(p->pattern, i, j);
        /* The float this cell belongs to: the run of cells where the same yarn stays on top. */
        int a = 0, b = 0;
        if (top) {
          while (a < 5 && warp_on_top(p->pattern, i, j - a - 1)) a++;
          while (b < 5 && warp_on_top(p->pattern, i, j + b + 1)) b++;
        } else {
          while (a < 5 && !warp_on_top(p->pattern, i - a - 1, j)) a++;
          while (b < 5 && !warp_on_top(p->pattern, i + b + 1, j)) b++;
        }
        float across = top ? fu : fv;
        float along = ((top ? fv : fu) + a) / (float)(a + b + 1);
        float jit = 0.85f + 0.3f * hashf(seed + 2 + top, (uint64_t)(top ? i : j));
        float shade = jit * (0.35f + 0.65f * sinf(3.14159265f * fminf(fmaxf(across, 0), 1))) *
                      (0.6f + 0.4f * sinf(3.14159265f * fminf(fmaxf(along, 0), 1)));
        const float *col = top ? p->warp : p->weft;
        for (int c = 0; c < 3; c++) acc[c] += col[c] * shade;
      }
      for (int c = 0; c < 3; c++)
        wv_image_px(img, x, y)[c] = acc[c] / 9 + 0.03f * (wv_rng_uniform(&r) - 0.5f);
    }
}

static double gram_dist(const float *a, const float *b, size_t n) { /* L_g: mean |dG| */
  double s = 0;
  for (size_t i = 0; i < n; i++) s += fabs((double)a[i] - b[i]);
  return s / n;
}

static void test_default_separation(void **state) {
  (void)state;
  wv_descriptor *d;
  wv_error err;
  assert_int_equal(wv_descriptor_create_default(&d, &err), WV_OK);
  size_t n = wv_descriptor_size(d);
  const int W = 400, H = 150;
  const weave base[3] = {
      {0, 5.0f, {0.55f, 0.25f, 0.15f}, {0.50f, 0.30f, 0.20f}},
      {1, 4.0f, {0.20f, 0.25f, 0.45f}, {0.60f, 0.60f, 0.55f}},
      {2, 4.5f, {0.70f, 0.65f, 0.30f}, {0.40f, 0.35f, 0.20f}},
  };
  /* For each base fabric: two noise seeds; another pattern with the same colours and
   * spacing; other colours with the same pattern; a 1.4x yarn spacing. The ratio is
   * the distance to the nearest different fabric over the distance between seeds. */
  double worst = 1e30, rsum = 0;
  for (int b = 0; b < 3; b++) {
    weave pat = base[b], col = base[b], dens = base[b];
    pat.pattern = (base[b].pattern + 1) % 3;
    for (int c = 0; c < 3; c++) col.warp[c] = base[(b + 1) % 3].warp[c], col.weft[c] = base[(b + 1) % 3].weft[c];
    dens.period = base[b].period * 1.4f;
    const weave *fab[5] = {&base[b], &base[b], &pat, &col, &dens};
    float *g[5];
    for (int q = 0; q < 5; q++) {
      wv_image im;
      render_weave(&im, W, H, fab[q], 100 * (q + 1) + b);
      g[q] = malloc(sizeof(float) * n);
      assert_int_equal(wv_descriptor_forward(d, &im, g[q], &err), WV_OK);
      wv_image_free(&im);
    }
    double ds = gram_dist(g[0], g[1], n), dp = gram_dist(g[0], g[2], n),
           dc = gram_dist(g[0], g[3], n), dd = gram_dist(g[0], g[4], n);
    double ratio = fmin(dp, fmin(dc, dd)) / ds;
    fprintf(stderr, "fabric %d: L_g between seeds %.3g; other pattern %.3g (x%.1f), other colours "
            "%.3g (x%.1f), other spacing %.3g (x%.1f)\n",
            b, ds, dp, dp / ds, dc, dc / ds, dd, dd / ds);
    if (ratio < worst) worst = ratio;
    rsum += ratio;
    for (int q = 0; q < 5; q++) free(g[q]);
  }
  fprintf(stderr, "separation (nearest different fabric / other seed): worst %.1f, mean %.1f\n",
          worst, rsum / 3);
  assert_true(worst > 5.0);
  wv_descriptor_free(d);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_tiny_network),       cmocka_unit_test(test_malformed),
      cmocka_unit_test(test_tiny_gradient),      cmocka_unit_test(test_default_gradient),
      cmocka_unit_test(test_default_determinism), cmocka_unit_test(test_default_separation),
      cmocka_unit_test(test_default_kernels),    cmocka_unit_test(test_vgg19_random),
  };
  int rc = cmocka_run_group_tests(tests, NULL, NULL);
  for (int i = 0; i < TINY_N; i++) free(tiny_vals[i]);
  return rc;
}
