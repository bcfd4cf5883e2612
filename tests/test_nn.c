/* nn ops: every backward against central finite differences of
 * loss = sum(dy .* forward(...)) (accumulated in double), plus forward references,
 * the threaded sgemm, Adam, the RNG and half-float conversion. */
#include <cblas.h>
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "testutil.h"
#include "woven/fit.h"
#include "woven/nn.h"

static float *rnd(wv_rng *r, size_t n, float lo, float hi) {
  float *x = malloc(sizeof(float) * (n ? n : 1));
  wv_rng_fill_uniform(r, x, n, lo, hi);
  return x;
}

/* Values away from 0 so that ReLU-like kinks are not crossed by the finite difference. */
static float *rnd_nokink(wv_rng *r, size_t n, float margin) {
  float *x = rnd(r, n, -1, 1);
  for (size_t i = 0; i < n; i++)
    if (fabsf(x[i]) < margin) x[i] = x[i] < 0 ? -margin - 0.1f : margin + 0.1f;
  return x;
}

static double dot(const float *a, const float *b, size_t n) {
  double s = 0;
  for (size_t i = 0; i < n; i++) s += (double)a[i] * b[i];
  return s;
}

typedef double (*loss_fn)(void *ctx);

/* Compares the analytic gradient g of f with respect to p[0..n) with central differences.
 * Errors are relative, with a floor of a tenth of the largest gradient entry: the float
 * rounding of the loss makes tiny derivatives noisy in absolute terms. */
static void check_grad(const char *what, float *p, size_t n, const float *g, loss_fn f, void *ctx,
                       float eps, double tol) {
  double worst = 0, gmax = 0;
  for (size_t i = 0; i < n; i++) gmax = fmax(gmax, fabs(g[i]));
  for (size_t i = 0; i < n; i++) {
    float save = p[i];
    p[i] = save + eps;
    double fp = f(ctx);
    p[i] = save - eps;
    double fm = f(ctx);
    p[i] = save;
    /* Divide by the step actually taken in float. */
    double num = (fp - fm) / ((double)(save + eps) - (double)(save - eps));
    double err = fabs(num - g[i]) / (fabs(num) + fabs(g[i]) + 0.1 * gmax + 1e-6);
    if (err > worst) worst = err;
    if (err > tol) {
      fprintf(stderr, "%s: d/dp[%zu] analytic %.6g, finite difference %.6g\n", what, i, g[i], num);
      fail();
    }
  }
  fprintf(stderr, "%-28s %5zu values, worst relative error %.2e\n", what, n, worst);
}

/* ---- conv2d ---- */
typedef struct {
  wv_nn_conv2d cv;
  float *x, *w, *b, *y, *dy, *s;
} conv_ctx;

static double conv_loss(void *p) {
  conv_ctx *c = p;
  wv_nn_conv2d_forward(&c->cv, c->x, c->w, c->b, c->y, c->s);
  return dot(c->y, c->dy, (size_t)c->cv.n * c->cv.oc * c->cv.oh * c->cv.ow);
}

static void conv_reference(const wv_nn_conv2d *cv, const float *x, const float *w, const float *b,
                           double *y) {
  for (int n = 0; n < cv->n; n++)
    for (int o = 0; o < cv->oc; o++)
      for (int oy = 0; oy < cv->oh; oy++)
        for (int ox = 0; ox < cv->ow; ox++) {
          double s = b ? b[o] : 0;
          for (int c = 0; c < cv->c; c++)
            for (int i = 0; i < cv->k; i++)
              for (int j = 0; j < cv->k; j++) {
                int iy = oy * cv->stride + i - cv->pad, ix = ox * cv->stride + j - cv->pad;
                if (iy < 0 || ix < 0 || iy >= cv->h || ix >= cv->w) continue;
                s += (double)w[((o * cv->c + c) * cv->k + i) * cv->k + j] *
                     x[((size_t)(n * cv->c + c) * cv->h + iy) * cv->w + ix];
              }
          y[((size_t)(n * cv->oc + o) * cv->oh + oy) * cv->ow + ox] = s;
        }
}

static void conv_case(int n, int c, int h, int w, int oc, int k, int stride, int pad) {
  char what[96];
  snprintf(what, sizeof what, "conv2d %dx%dx%dx%d k%d s%d p%d", n, c, h, w, k, stride, pad);
  wv_rng r;
  wv_rng_seed(&r, 100 + k * 10 + stride + pad);
  conv_ctx cc;
  wv_error err;
  assert_int_equal(wv_nn_conv2d_init(&cc.cv, n, c, h, w, oc, k, stride, pad, &err), WV_OK);
  size_t nx = (size_t)n * c * h * w, nw = (size_t)oc * c * k * k,
         ny = (size_t)n * oc * cc.cv.oh * cc.cv.ow;
  cc.x = rnd(&r, nx, -1, 1), cc.w = rnd(&r, nw, -1, 1), cc.b = rnd(&r, oc, -1, 1);
  cc.y = rnd(&r, ny, 0, 0), cc.dy = rnd(&r, ny, -1, 1);
  cc.s = malloc(sizeof(float) * wv_nn_conv2d_scratch_floats(&cc.cv));
  /* Forward against the direct sum. */
  double *ref = malloc(sizeof(double) * ny);
  conv_reference(&cc.cv, cc.x, cc.w, cc.b, ref);
  conv_loss(&cc);
  for (size_t i = 0; i < ny; i++) assert_true(fabs(cc.y[i] - ref[i]) < 1e-4 * (1 + fabs(ref[i])));
  /* Backward: gradients accumulate, so start from a known offset and subtract it. */
  float *dx = rnd(&r, nx, 0, 0), *dw = rnd(&r, nw, 0, 0), *db = rnd(&r, oc, 0, 0);
  for (size_t i = 0; i < nx; i++) dx[i] = 0.5f;
  wv_nn_conv2d_backward(&cc.cv, cc.x, cc.w, cc.dy, dx, dw, db, cc.s);
  for (size_t i = 0; i < nx; i++) dx[i] -= 0.5f;
  char wx[128];
  snprintf(wx, sizeof wx, "%s dx", what);
  check_grad(wx, cc.x, nx, dx, conv_loss, &cc, 5e-2f, 2e-3);
  snprintf(wx, sizeof wx, "%s dw", what);
  check_grad(wx, cc.w, nw, dw, conv_loss, &cc, 5e-2f, 2e-3);
  snprintf(wx, sizeof wx, "%s db", what);
  check_grad(wx, cc.b, oc, db, conv_loss, &cc, 5e-2f, 2e-3);
  free(ref), free(dx), free(dw), free(db);
  free(cc.x), free(cc.w), free(cc.b), free(cc.y), free(cc.dy), free(cc.s);
}

static void test_conv2d(void **state) {
  (void)state;
  conv_case(2, 3, 7, 6, 4, 3, 1, 1);   /* VGG-style same convolution */
  conv_case(1, 2, 9, 8, 3, 5, 1, 0);   /* valid convolution, as the default descriptor */
  conv_case(2, 3, 8, 7, 2, 3, 2, 1);   /* strided */
  conv_case(2, 4, 5, 6, 3, 1, 1, 0);   /* pointwise (no im2col) */
  conv_case(1, 2, 40, 33, 3, 3, 1, 1); /* several blocks per thread */
  conv_case(2, 120, 4, 3, 2, 3, 1, 1); /* long columns: the shared schedule */
}

static void test_conv2d_invalid(void **state) {
  (void)state;
  wv_nn_conv2d cv;
  wv_error err = {0};
  assert_int_equal(wv_nn_conv2d_init(&cv, 1, 3, 2, 2, 4, 5, 1, 0, &err), WV_ERR_INVALID);
  assert_non_null(strstr(err.msg, "smaller than"));
  assert_int_equal(wv_nn_conv2d_init(&cv, 1, 3, 8, 8, 4, 3, 1, 3, &err), WV_ERR_INVALID);
  assert_int_equal(wv_nn_conv2d_init(&cv, 1, 0, 8, 8, 4, 3, 1, 1, &err), WV_ERR_INVALID);
}

/* ---- element-wise ops ---- */
typedef struct {
  int kind; /* 0 relu, 1 leaky, 2 sigmoid, 3 bias */
  size_t n;
  int nn, c, hw;
  float *x, *b, *y, *dy;
} ew_ctx;

static double ew_loss(void *p) {
  ew_ctx *e = p;
  if (e->kind == 0) wv_nn_relu_forward(e->y, e->x, e->n);
  if (e->kind == 1) wv_nn_leaky_relu_forward(e->y, e->x, 0.2f, e->n);
  if (e->kind == 2) wv_nn_sigmoid_forward(e->y, e->x, e->n);
  if (e->kind == 3) wv_nn_bias_forward(e->y, e->x, e->b, e->nn, e->c, e->hw);
  return dot(e->y, e->dy, e->n);
}

static void test_elementwise(void **state) {
  (void)state;
  static const char *names[] = {"relu", "leaky_relu", "sigmoid", "bias"};
  wv_rng r;
  wv_rng_seed(&r, 7);
  for (int kind = 0; kind < 4; kind++) {
    ew_ctx e = {.kind = kind, .nn = 2, .c = 3, .hw = 10};
    e.n = (size_t)e.nn * e.c * e.hw;
    e.x = rnd_nokink(&r, e.n, 0.05f), e.b = rnd(&r, 3, -1, 1);
    e.y = rnd(&r, e.n, 0, 0), e.dy = rnd(&r, e.n, -1, 1);
    float *dx = calloc(e.n, sizeof(float)), *db = calloc(3, sizeof(float));
    ew_loss(&e);
    if (kind == 0) wv_nn_relu_backward(dx, e.x, e.dy, e.n);
    if (kind == 1) wv_nn_leaky_relu_backward(dx, e.x, e.dy, 0.2f, e.n);
    if (kind == 2) wv_nn_sigmoid_backward(dx, e.y, e.dy, e.n);
    if (kind == 3) wv_nn_bias_backward(dx, db, e.dy, e.nn, e.c, e.hw);
    check_grad(names[kind], e.x, e.n, dx, ew_loss, &e, 1e-2f, 2e-3);
    if (kind == 3) check_grad("bias db", e.b, 3, db, ew_loss, &e, 5e-2f, 2e-3);
    if (kind == 0) {
      /* The in-place variant on the output gives the same gradient. */
      float *d2 = malloc(sizeof(float) * e.n);
      memcpy(d2, e.dy, sizeof(float) * e.n);
      wv_nn_relu_mask(d2, e.y, e.n);
      for (size_t i = 0; i < e.n; i++) assert_true(d2[i] == dx[i]);
      free(d2);
    }
    free(dx), free(db), free(e.x), free(e.b), free(e.y), free(e.dy);
  }
  /* Sigmoid stays finite and saturates cleanly for large inputs. */
  float big[2] = {-200.0f, 200.0f}, out[2];
  wv_nn_sigmoid_forward(out, big, 2);
  assert_true(out[0] == 0.0f && out[1] == 1.0f);
}

/* ---- pooling ---- */
typedef struct {
  int nc, h, w;
  float *x, *y, *dy;
} pool_ctx;

static double pool_loss(void *p) {
  pool_ctx *c = p;
  wv_nn_avgpool2_forward(c->y, c->x, c->nc, c->h, c->w);
  return dot(c->y, c->dy, (size_t)c->nc * (c->h / 2) * (c->w / 2));
}

static void test_avgpool(void **state) {
  (void)state;
  wv_rng r;
  wv_rng_seed(&r, 8);
  pool_ctx c = {.nc = 3, .h = 7, .w = 6}; /* odd height: the last row is dropped */
  size_t nx = (size_t)c.nc * c.h * c.w, ny = (size_t)c.nc * 3 * 3;
  c.x = rnd(&r, nx, -1, 1), c.y = rnd(&r, ny, 0, 0), c.dy = rnd(&r, ny, -1, 1);
  pool_loss(&c);
  assert_true(fabsf(c.y[0] - 0.25f * (c.x[0] + c.x[1] + c.x[6] + c.x[7])) < 1e-6f);
  float *dx = calloc(nx, sizeof(float));
  wv_nn_avgpool2_backward(dx, c.dy, c.nc, c.h, c.w);
  check_grad("avgpool2", c.x, nx, dx, pool_loss, &c, 5e-2f, 2e-3);
  for (int x = 0; x < c.w; x++) assert_true(dx[6 * c.w + x] == 0.0f); /* dropped row */
  free(dx), free(c.x), free(c.y), free(c.dy);
}

/* ---- Gram ---- */
typedef struct {
  int n, c, hw;
  float *f, *g, *dg;
} gram_ctx;

static double gram_loss(void *p) {
  gram_ctx *c = p;
  wv_nn_gram_forward(c->g, c->f, c->n, c->c, c->hw);
  return dot(c->g, c->dg, (size_t)c->n * c->c * c->c);
}

static void test_gram(void **state) {
  (void)state;
  wv_rng r;
  wv_rng_seed(&r, 9);
  gram_ctx c = {.n = 2, .c = 4, .hw = 15};
  size_t nf = (size_t)c.n * c.c * c.hw, ng = (size_t)c.n * c.c * c.c;
  c.f = rnd(&r, nf, -1, 1), c.g = rnd(&r, ng, 0, 0), c.dg = rnd(&r, ng, -1, 1); /* dg not symmetric */
  gram_loss(&c);
  for (int i = 0; i < c.c; i++)
    for (int j = 0; j < c.c; j++) {
      double s = 0;
      for (int p = 0; p < c.hw; p++) s += (double)c.f[i * c.hw + p] * c.f[j * c.hw + p];
      assert_true(fabs(c.g[i * c.c + j] - s / c.hw) < 1e-5);
    }
  float *df = calloc(nf, sizeof(float));
  wv_nn_gram_backward(df, c.f, c.dg, c.n, c.c, c.hw);
  check_grad("gram", c.f, nf, df, gram_loss, &c, 5e-2f, 2e-3);
  free(df), free(c.f), free(c.g), free(c.dg);
}

/* ---- fully connected ---- */
typedef struct {
  int batch, in, out;
  float *x, *w, *b, *y, *dy;
} fc_ctx;

static double fc_loss(void *p) {
  fc_ctx *c = p;
  wv_nn_fc_forward(c->y, c->x, c->w, c->b, c->batch, c->in, c->out);
  return dot(c->y, c->dy, (size_t)c->batch * c->out);
}

static void fc_case(int batch, int in, int out, int check_all) {
  wv_rng r;
  wv_rng_seed(&r, 10 + in);
  fc_ctx c = {.batch = batch, .in = in, .out = out};
  size_t nx = (size_t)batch * in, nw = (size_t)out * in, ny = (size_t)batch * out;
  c.x = rnd(&r, nx, -1, 1), c.w = rnd(&r, nw, -1, 1), c.b = rnd(&r, out, -1, 1);
  c.y = rnd(&r, ny, 0, 0), c.dy = rnd(&r, ny, -1, 1);
  fc_loss(&c);
  for (int i = 0; i < batch; i++)
    for (int o = 0; o < out; o++) {
      double s = c.b[o];
      for (int k = 0; k < in; k++) s += (double)c.x[i * in + k] * c.w[(size_t)o * in + k];
      assert_true(fabs(c.y[i * out + o] - s) < 1e-4 * (1 + fabs(s)));
    }
  float *dx = calloc(nx, sizeof(float)), *dw = calloc(nw, sizeof(float)),
        *db = calloc(out, sizeof(float));
  wv_nn_fc_backward(dx, dw, db, c.dy, c.x, c.w, batch, in, out);
  /* Large layers: check a sample of entries (the FD of every one costs O(n^2)). */
  size_t cx = check_all ? nx : 64, cw = check_all ? nw : 64;
  check_grad("fc dx", c.x, cx, dx, fc_loss, &c, 5e-2f, 2e-3);
  check_grad("fc dw", c.w, cw, dw, fc_loss, &c, 5e-2f, 2e-3);
  check_grad("fc db", c.b, out, db, fc_loss, &c, 5e-2f, 2e-3);
  free(dx), free(dw), free(db), free(c.x), free(c.w), free(c.b), free(c.y), free(c.dy);
}

static void test_fc(void **state) {
  (void)state;
  fc_case(3, 5, 4, 1);
  fc_case(32, 300, 21, 0); /* large enough for the threaded sgemm split */
}

/* ---- L1 ---- */
typedef struct {
  size_t n;
  float *p, *t;
} l1_ctx;

static double l1_loss(void *ctx) {
  l1_ctx *c = ctx;
  return 3.0 * wv_nn_l1_forward(c->p, c->t, c->n);
}

static void test_l1(void **state) {
  (void)state;
  wv_rng r;
  wv_rng_seed(&r, 11);
  l1_ctx c = {.n = 21};
  c.p = rnd(&r, c.n, 0, 1), c.t = rnd(&r, c.n, 0, 1);
  for (size_t i = 0; i < c.n; i++)
    if (fabsf(c.p[i] - c.t[i]) < 0.05f) c.p[i] = c.t[i] + 0.1f;
  double s = 0;
  for (size_t i = 0; i < c.n; i++) s += fabs(c.p[i] - c.t[i]);
  assert_true(fabs(wv_nn_l1_forward(c.p, c.t, c.n) - s / c.n) < 1e-6);
  float *d = calloc(c.n, sizeof(float));
  wv_nn_l1_backward(d, c.p, c.t, 3.0f, c.n);
  check_grad("l1", c.p, c.n, d, l1_loss, &c, 1e-3f, 2e-3);
  free(d), free(c.p), free(c.t);
}

/* ---- sgemm split ---- */
static void test_sgemm(void **state) {
  (void)state;
  wv_rng r;
  wv_rng_seed(&r, 12);
  int shapes[][3] = {{300, 200, 50}, {20, 900, 64}, {500, 30, 70}, {3, 5, 7}};
  for (int s = 0; s < 4; s++)
    for (int ta = 0; ta < 2; ta++)
      for (int tb = 0; tb < 2; tb++) {
        int m = shapes[s][0], n = shapes[s][1], k = shapes[s][2];
        int lda = ta ? m : k, ldb = tb ? k : n;
        float *a = rnd(&r, (size_t)m * k, -1, 1), *b = rnd(&r, (size_t)k * n, -1, 1);
        float *c1 = rnd(&r, (size_t)m * n, -1, 1), *c2 = malloc(sizeof(float) * m * n);
        memcpy(c2, c1, sizeof(float) * m * n);
        wv_nn_sgemm(ta, tb, m, n, k, 0.5f, a, lda, b, ldb, 0.25f, c1, n);
        for (int i = 0; i < m; i++)
          for (int j = 0; j < n; j++) {
            double v = 0;
            for (int p = 0; p < k; p++)
              v += (double)(ta ? a[p * lda + i] : a[i * lda + p]) *
                   (tb ? b[j * ldb + p] : b[p * ldb + j]);
            v = 0.5 * v + 0.25 * c2[i * n + j];
            assert_true(fabs(c1[i * n + j] - v) < 1e-4 * (1 + fabs(v)));
          }
        free(a), free(b), free(c1), free(c2);
      }
}

/* The kernels' name is what a capture reports: a word, as the environment set it when it
 * chose them (ctest runs this test once more with OPENBLAS_CORETYPE=Haswell: test_nn_haswell). */
static void test_blas_core(void **state) {
  (void)state;
  const char *name = wv_nn_blas_core();
  assert_non_null(name);
  assert_true(strlen(name) > 0 && strlen(name) < 64);
  for (const char *c = name; *c; c++) assert_true(isalnum((unsigned char)*c) || *c == '_');
  const char *want = getenv("OPENBLAS_CORETYPE");
  if (want && !strcasecmp(want, "Haswell")) assert_string_equal(name, "Haswell");
}

/* ---- Adam ---- */
static void test_adam(void **state) {
  (void)state;
  wv_nn_adam a;
  wv_error err;
  float p[3] = {1.0f, -2.0f, 0.5f}, g[3];
  assert_int_equal(wv_nn_adam_init(&a, 3, 0.1f, &err), WV_OK);
  /* First step: m^ = g, v^ = g^2, so every parameter moves by lr against its gradient sign. */
  g[0] = 4.0f, g[1] = -0.01f, g[2] = 0.0f;
  wv_nn_adam_step(&a, p, g);
  assert_true(fabsf(p[0] - 0.9f) < 1e-6f && fabsf(p[1] + 1.9f) < 1e-4f && p[2] == 0.5f);
  /* Minimises a quadratic sum (p - t)^2. */
  const float t[3] = {0.3f, -0.7f, 2.0f};
  for (int it = 0; it < 2000; it++) {
    for (int i = 0; i < 3; i++) g[i] = 2.0f * (p[i] - t[i]);
    wv_nn_adam_step(&a, p, g);
  }
  for (int i = 0; i < 3; i++) assert_true(fabsf(p[i] - t[i]) < 1e-2f);
  assert_int_equal(a.t, 2001);
  wv_nn_adam_free(&a);
}

/* ---- L-BFGS on a box ---- */
/* f = 0.5 (x - t)' A (x - t), A = Q diag(l) Q' with eigenvalues 1 .. 100 (Q a product of
 * Givens turns); the gradient A (x - t). */
static void quad_grad(const double A[12][12], const double *t, const double *x, double *g, double *f) {
  *f = 0;
  for (int i = 0; i < 12; i++) {
    g[i] = 0;
    for (int j = 0; j < 12; j++) g[i] += A[i][j] * (x[j] - t[j]);
    *f += 0.5 * (x[i] - t[i]) * g[i];
  }
}

/* Steps along wv_nn_lbfgs_direction with the fit's line search (1, 1/4, ... until the value falls,
 * the box [0, 1] by clamping); returns the iterations taken to reach f - fmin < tol. */
static int lbfgs_run(const double A[12][12], const double *t, double *x, double fmin, double tol, int max_it) {
  wv_nn_lbfgs q;
  wv_nn_lbfgs_reset(&q, 12);
  double g[12], f, d[12];
  quad_grad(A, t, x, g, &f);
  for (int it = 0; it < max_it; it++) {
    if (f - fmin < tol) return it;
    double alpha = 1;
    int pairs = wv_nn_lbfgs_direction(&q, x, f, g, 0, 1, d);
    if (pairs < 0) break; /* nothing left to try */
    if (pairs == 0) {
      double m = 0;
      for (int i = 0; i < 12; i++) m = fabs(d[i]) > m ? fabs(d[i]) : m;
      alpha = 0.1 / m;
    }
    int ok = 0;
    for (int k = 0; k < 4 && !ok; k++, alpha *= 0.25) {
      double xt[12], gt[12], ft, dec = 0;
      for (int i = 0; i < 12; i++) {
        xt[i] = x[i] + alpha * d[i];
        xt[i] = xt[i] < 0 ? 0 : xt[i] > 1 ? 1 : xt[i];
        dec += g[i] * (xt[i] - x[i]);
      }
      assert_true(dec < 0); /* a descent direction, also on the box's faces */
      quad_grad(A, t, xt, gt, &ft);
      if (ft < f) {
        ok = 1, f = ft;
        memcpy(x, xt, sizeof xt), memcpy(g, gt, sizeof gt);
      }
    }
    if (!ok) wv_nn_lbfgs_reject(&q);
  }
  return max_it;
}

static void make_quadratic(double A[12][12]) {
  double Q[12][12] = {{0}};
  for (int i = 0; i < 12; i++) Q[i][i] = 1;
  for (int r = 0; r < 11; r++) { /* turn rows r and r + 1 by 0.7 rad: Q stays orthogonal */
    double c = cos(0.7), s = sin(0.7);
    for (int j = 0; j < 12; j++) {
      double a = Q[r][j], b = Q[r + 1][j];
      Q[r][j] = c * a - s * b, Q[r + 1][j] = s * a + c * b;
    }
  }
  for (int i = 0; i < 12; i++)
    for (int j = 0; j < 12; j++) {
      A[i][j] = 0;
      for (int k = 0; k < 12; k++) A[i][j] += Q[k][i] * pow(100.0, k / 11.0) * Q[k][j];
    }
}

/* An ill-conditioned quadratic (condition number 100) with its minimum inside the box: L-BFGS
 * reaches it to 1e-10 in a few dozen evaluations, where projected Adam at the fit's learning
 * rate is still far after as many; with the minimum outside (a separable quadratic, whose
 * box minimum is the clamped target) it ends on the box's faces. */
static void test_lbfgs_box(void **state) {
  (void)state;
  double A[12][12], t[12], x[12];
  make_quadratic(A);
  for (int i = 0; i < 12; i++) t[i] = 0.1 + 0.8 * i / 11.0, x[i] = 0.5;
  int it = lbfgs_run(A, t, x, 0, 1e-10, 200);
  print_message("L-BFGS: f < 1e-10 after %d iterations\n", it);
  assert_true(it < 60);
  for (int i = 0; i < 12; i++) assert_true(fabs(x[i] - t[i]) < 1e-4);
  /* Adam at the fit's learning rate for the same number of steps */
  wv_fit_opts fo;
  wv_fit_opts_default(&fo);
  float z[12], gz[12], m[12] = {0}, v[12] = {0};
  wv_nn_adam a = {.n = 12, .lr = (float)fo.lr, .beta1 = 0.9f, .beta2 = 0.999f, .eps = 1e-8f, .m = m, .v = v};
  for (int i = 0; i < 12; i++) z[i] = 0.5f;
  double f = 0;
  for (int k = 0; k < it; k++) {
    double xd[12], g[12];
    for (int i = 0; i < 12; i++) xd[i] = z[i];
    quad_grad(A, t, xd, g, &f);
    for (int i = 0; i < 12; i++) gz[i] = (float)g[i];
    wv_nn_adam_step_box(&a, z, gz, 0.0f, 1.0f);
  }
  print_message("Adam after as many steps: f = %.3g\n", f);
  assert_true(f > 1e-6);
  /* separable, with targets outside the box: the clamped target */
  double D[12][12] = {{0}};
  for (int i = 0; i < 12; i++) D[i][i] = pow(100.0, i / 11.0), t[i] = -0.5 + 2.0 * i / 11.0, x[i] = 0.5;
  double fmin = 0;
  for (int i = 0; i < 12; i++) {
    double c = t[i] < 0 ? 0 : t[i] > 1 ? 1 : t[i];
    fmin += 0.5 * D[i][i] * (c - t[i]) * (c - t[i]);
  }
  /* every step turned down: the memory cleared, then, from the steepest descent, the point kept */
  wv_nn_lbfgs q;
  wv_nn_lbfgs_reset(&q, 2);
  double p0[2] = {0.5, 0.5}, p1[2] = {0.6, 0.5}, g0[2] = {1, 0}, g1[2] = {2, 0}, dd[2];
  assert_int_equal(wv_nn_lbfgs_direction(&q, p0, 1.0, g0, 0, 1, dd), 0);
  assert_true(dd[0] == -1 && dd[1] == 0);
  assert_int_equal(wv_nn_lbfgs_direction(&q, p1, 1.15, g1, 0, 1, dd), 1); /* s.y = 0.1, f as the trapezoid */
  wv_nn_lbfgs_reject(&q);
  assert_int_equal(q.count, 0);
  assert_int_equal(wv_nn_lbfgs_direction(&q, p1, 1.15, g1, 0, 1, dd), 0);
  wv_nn_lbfgs_reject(&q);
  assert_int_equal(wv_nn_lbfgs_direction(&q, p1, 1.15, g1, 0, 1, dd), -1);
  assert_true(dd[0] == 0 && dd[1] == 0);
  assert_int_equal(wv_nn_lbfgs_direction(&q, p0, 1.0, g0, 0, 1, dd), 1); /* elsewhere: steps again */
  /* a pair whose gradients do not tell the change of f (a slope without bound at the start)
   * is not kept */
  wv_nn_lbfgs_reset(&q, 2);
  double gw[2] = {-1e15, 0};
  assert_int_equal(wv_nn_lbfgs_direction(&q, p0, 1.0, gw, 0, 1, dd), 0);
  assert_int_equal(wv_nn_lbfgs_direction(&q, p1, 0.9, g1, 0, 1, dd), 0);
  /* a coordinate on a bound whose descent points out of the box takes no part */
  double pb[2] = {0, 0.5}, gb[2] = {3, -1};
  wv_nn_lbfgs_reset(&q, 2);
  assert_int_equal(wv_nn_lbfgs_direction(&q, pb, 1.0, gb, 0, 1, dd), 0);
  assert_true(dd[0] == 0 && dd[1] == 1);
  it = lbfgs_run((const double(*)[12])D, t, x, fmin, 1e-12, 200);
  print_message("L-BFGS, the box minimum: %d iterations\n", it);
  assert_true(it < 30);
  for (int i = 0; i < 12; i++) {
    double c = t[i] < 0 ? 0 : t[i] > 1 ? 1 : t[i];
    assert_true(fabs(x[i] - c) < 1e-4);
  }
}

/* Projected Adam, as the fit uses it: the same steps as plain Adam inside the box, clamped
 * at its faces; a target outside the box ends on the nearest face. */
static void test_adam_box(void **state) {
  (void)state;
  float m[2] = {0}, v[2] = {0}, m2[2] = {0}, v2[2] = {0};
  wv_nn_adam
      a = {.n = 2, .lr = 0.05f, .beta1 = 0.9f, .beta2 = 0.999f, .eps = 1e-8f, .weight_decay = 0.0f, .m = m, .v = v},
      b = {.n = 2, .lr = 0.05f, .beta1 = 0.9f, .beta2 = 0.999f, .eps = 1e-8f, .weight_decay = 0.0f, .m = m2, .v = v2};
  float p[2] = {0.5f, 0.5f}, q[2] = {0.5f, 0.5f}, g[2];
  const float t[2] = {0.7f, 1.6f}; /* the second target lies outside [0, 1] */
  for (int it = 0; it < 400; it++) {
    for (int i = 0; i < 2; i++) g[i] = 2.0f * (p[i] - t[i]);
    wv_nn_adam_step_box(&a, p, g, 0.0f, 1.0f);
    assert_true(p[0] >= 0 && p[0] <= 1 && p[1] >= 0 && p[1] <= 1);
    if (it < 5) { /* before any clamp, identical to the plain step */
      for (int i = 0; i < 2; i++) g[i] = 2.0f * (q[i] - t[i]);
      wv_nn_adam_step(&b, q, g);
      assert_true(q[0] == p[0] && q[1] == p[1]);
    }
  }
  assert_true(fabsf(p[0] - 0.7f) < 1e-2f && p[1] == 1.0f);
  assert_int_equal(a.t, 400);
}

/* ---- The FabricNet pieces together: FC -> LeakyReLU -> FC -> sigmoid, L1, Adam ---- */
static void test_mlp_training(void **state) {
  (void)state;
  enum { B = 32, IN = 96, HID = 48, OUT = 5, STEPS = 300 };
  wv_rng r;
  wv_rng_seed(&r, 13);
  /* Targets from a fixed random teacher network, so the student can fit them. */
  float *x = rnd(&r, B * IN, -1, 1), *t = malloc(sizeof(float) * B * OUT);
  float *tw = rnd(&r, OUT * IN, -0.3f, 0.3f);
  wv_nn_fc_forward(t, x, tw, NULL, B, IN, OUT);
  wv_nn_sigmoid_forward(t, t, B * OUT);
  size_t n1 = (size_t)HID * IN, n2 = (size_t)OUT * HID, np = n1 + HID + n2 + OUT;
  float *p = calloc(np, sizeof(float)), *g = malloc(sizeof(float) * np);
  float *w1 = p, *b1 = w1 + n1, *w2 = b1 + HID, *b2 = w2 + n2;
  wv_rng_fill_uniform(&r, w1, n1, -sqrtf(6.0f / IN), sqrtf(6.0f / IN));
  wv_rng_fill_uniform(&r, w2, n2, -sqrtf(6.0f / HID), sqrtf(6.0f / HID));
  float *h = malloc(sizeof(float) * B * HID), *a = malloc(sizeof(float) * B * HID),
        *z = malloc(sizeof(float) * B * OUT), *y = malloc(sizeof(float) * B * OUT),
        *dy = malloc(sizeof(float) * B * OUT), *dz = malloc(sizeof(float) * B * OUT),
        *da = malloc(sizeof(float) * B * HID), *dh = malloc(sizeof(float) * B * HID);
  wv_nn_adam opt;
  wv_error err;
  assert_int_equal(wv_nn_adam_init(&opt, np, 1e-2f, &err), WV_OK);
  float first = 0, last = 0;
  for (int it = 0; it < STEPS; it++) {
    wv_nn_fc_forward(h, x, w1, b1, B, IN, HID);
    wv_nn_leaky_relu_forward(a, h, 0.01f, B * HID);
    wv_nn_fc_forward(z, a, w2, b2, B, HID, OUT);
    wv_nn_sigmoid_forward(y, z, B * OUT);
    float loss = wv_nn_l1_forward(y, t, B * OUT);
    if (it == 0) first = loss;
    last = loss;
    memset(g, 0, sizeof(float) * np);
    memset(dy, 0, sizeof(float) * B * OUT), memset(dz, 0, sizeof(float) * B * OUT);
    memset(da, 0, sizeof(float) * B * HID), memset(dh, 0, sizeof(float) * B * HID);
    wv_nn_l1_backward(dy, y, t, 1.0f, B * OUT);
    wv_nn_sigmoid_backward(dz, y, dy, B * OUT);
    wv_nn_fc_backward(da, g + (w2 - p), g + (b2 - p), dz, a, w2, B, HID, OUT);
    wv_nn_leaky_relu_backward(dh, h, da, 0.01f, B * HID);
    wv_nn_fc_backward(NULL, g + (w1 - p), g + (b1 - p), dh, x, w1, B, IN, HID);
    wv_nn_adam_step(&opt, p, g);
  }
  fprintf(stderr, "MLP with Adam: L1 loss %.4f -> %.4f after %d steps\n", first, last, STEPS);
  assert_true(last < 0.2f * first);
  wv_nn_adam_free(&opt);
  free(x), free(t), free(tw), free(p), free(g), free(h), free(a), free(z), free(y), free(dy);
  free(dz), free(da), free(dh);
}

/* ---- RNG and half floats ---- */
static void test_rng_half(void **state) {
  (void)state;
  wv_rng r;
  wv_rng_seed(&r, 0);
  /* splitmix64's published first outputs for seed 0. */
  assert_true(wv_rng_u64(&r) == 0xe220a8397b1dcdafULL);
  assert_true(wv_rng_u64(&r) == 0x6e789e6aa1b965f4ULL);
  double s = 0, s2 = 0;
  wv_rng_seed(&r, 42);
  for (int i = 0; i < 20000; i++) {
    float u = wv_rng_uniform(&r);
    assert_true(u >= 0.0f && u < 1.0f);
    float z = wv_rng_normal(&r);
    s += z, s2 += (double)z * z;
  }
  assert_true(fabs(s / 20000) < 0.05 && fabs(s2 / 20000 - 1) < 0.05);
  assert_true(wv_nn_f16_to_f32(0x3c00) == 1.0f);
  assert_true(wv_nn_f16_to_f32(0xc000) == -2.0f);
  assert_true(wv_nn_f16_to_f32(0x7bff) == 65504.0f);
  assert_true(wv_nn_f16_to_f32(0x0001) == ldexpf(1.0f, -24)); /* smallest subnormal */
  assert_true(wv_nn_f16_to_f32(0x3555) == 0.25f + 341.0f / 4096.0f); /* (1 + 341/1024) 2^-2 */
  assert_true(isinf(wv_nn_f16_to_f32(0x7c00)) && isnan(wv_nn_f16_to_f32(0x7e00)));
  assert_true(wv_nn_bf16_to_f32(0x3f80) == 1.0f);
  assert_true(wv_nn_bf16_to_f32(0xc0a0) == -5.0f);
}

/* An argument runs only the tests whose names match it (cmocka's pattern). */
int main(int argc, char **argv) {
  if (argc > 1) cmocka_set_test_filter(argv[1]);
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_conv2d),  cmocka_unit_test(test_conv2d_invalid),
      cmocka_unit_test(test_elementwise), cmocka_unit_test(test_avgpool),
      cmocka_unit_test(test_gram),    cmocka_unit_test(test_fc),
      cmocka_unit_test(test_l1),      cmocka_unit_test(test_sgemm),
      cmocka_unit_test(test_blas_core),
      cmocka_unit_test(test_adam),    cmocka_unit_test(test_adam_box), cmocka_unit_test(test_lbfgs_box),  cmocka_unit_test(test_mlp_training),
      cmocka_unit_test(test_rng_half),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
