/* woven: neural-network building blocks, in the style of llm.c.
 *
 * Tensors are plain float arrays owned by the caller: images are NCHW (batch,
 * channel, row, column), fully connected layers use row-major (batch, features).
 * Every op is a pair <op>_forward / <op>_backward. Backward functions ACCUMULATE
 * (+=) into every gradient they are given (dx, dw, db), so the caller zeroes them
 * first; a NULL gradient pointer skips that gradient.
 *
 * Threads. Ops parallelise with OpenMP and call OpenBLAS from inside their OpenMP
 * regions, one single-threaded sgemm per thread: OpenBLAS's own thread pool and
 * OpenMP's spinning workers fight over the same cores otherwise (measured on 2
 * cores: im2col under OpenMP + threaded sgemm ran a 64->64 3x3 convolution 4x
 * slower than this scheme). So every op that calls BLAS first makes OpenBLAS
 * single-threaded with openblas_set_num_threads(1) (wv_nn_blas_serial); that
 * setting is process-wide. Results are deterministic for a given OpenMP thread
 * count (partial sums are combined in thread order, never with atomics) and a given
 * set of OpenBLAS kernels, which OpenBLAS chooses by the CPU (wv_nn_blas_core).
 */
#ifndef WOVEN_NN_H
#define WOVEN_NN_H

#include <stddef.h>
#include <stdint.h>
#include "woven/error.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- Deterministic random numbers: splitmix64 (Steele, Lea & Flood 2014). ---- */
typedef struct {
  uint64_t state;
} wv_rng;

void wv_rng_seed(wv_rng *r, uint64_t seed);
uint64_t wv_rng_u64(wv_rng *r);
/* Uniform in [0, 1) with 24 random bits: exact, identical on every platform. */
float wv_rng_uniform(wv_rng *r);
/* Standard normal (Box-Muller in double precision). */
float wv_rng_normal(wv_rng *r);
/* x[i] uniform in [lo, hi). */
void wv_rng_fill_uniform(wv_rng *r, float *x, size_t n, float lo, float hi);

/* ---- BLAS ---- */
/* Makes OpenBLAS single-threaded (process-wide; see the top of this file). */
void wv_nn_blas_serial(void);
/* The name of the kernels OpenBLAS runs on this CPU ("Haswell", "SkylakeX", ...; the
 * environment's OPENBLAS_CORETYPE can choose them): products summed by other kernels differ
 * in their last bits, and a fit's iterations carry that to another end (docs/fit.md, "The
 * same capture on another CPU"). A static string; "unknown" where OpenBLAS gives none. */
const char *wv_nn_blas_core(void);
/* Row-major C (m x n) = alpha op(A) op(B) + beta C, op = transpose when ta/tb is
 * nonzero. Large products are split over the OpenMP threads (by rows of C or by
 * columns, whichever is longer), each part a single-threaded OpenBLAS call. */
void wv_nn_sgemm(int ta, int tb, int m, int n, int k, float alpha, const float *a, int lda,
                 const float *b, int ldb, float beta, float *c, int ldc);

/* ---- 2-D convolution (im2col + sgemm) ----
 * x (n, c, h, w), weights (oc, c, k, k) as in PyTorch, bias (oc) or NULL,
 * y (n, oc, oh, ow) with oh = (h + 2 pad - k) / stride + 1. Zero padding. */
typedef struct {
  int n, c, h, w;          /* input */
  int oc, k, stride, pad;  /* filters */
  int oh, ow;              /* output size, set by init */
  int chunk;               /* output positions per per-thread block, set by init */
  int shared;              /* 1: threads share blocks (see conv.c), set by init */
  int nthreads;            /* OpenMP threads the op uses, set by init */
} wv_nn_conv2d;

wv_status wv_nn_conv2d_init(wv_nn_conv2d *cv, int n, int c, int h, int w, int oc, int k,
                            int stride, int pad, wv_error *err);
/* Scratch floats that forward and backward need. */
size_t wv_nn_conv2d_scratch_floats(const wv_nn_conv2d *cv);
void wv_nn_conv2d_forward(const wv_nn_conv2d *cv, const float *x, const float *w, const float *b,
                          float *y, float *scratch);
/* dx, dw, db accumulate; any may be NULL. */
void wv_nn_conv2d_backward(const wv_nn_conv2d *cv, const float *x, const float *w, const float *dy,
                           float *dx, float *dw, float *db, float *scratch);
/* The column matrix of one image for output positions [p0, p1) (row-major over the
 * output map): col is (c k k) x (p1 - p0). col2im adds such a matrix back into dx. */
void wv_nn_im2col(const float *x, int c, int h, int w, int k, int stride, int pad, int ow, int p0,
                  int p1, float *col);
void wv_nn_col2im(const float *col, int c, int h, int w, int k, int stride, int pad, int ow,
                  int p0, int p1, float *dx);

/* ---- Per-channel bias: y = x + b[c] over (n, c, hw); y may be x. ---- */
void wv_nn_bias_forward(float *y, const float *x, const float *b, int n, int c, int hw);
void wv_nn_bias_backward(float *dx, float *db, const float *dy, int n, int c, int hw);

/* ---- ReLU and LeakyReLU (y may be x). Backward takes the input x; the output y
 * works as well since it has the same sign (slope > 0). ---- */
void wv_nn_relu_forward(float *y, const float *x, size_t n);
void wv_nn_relu_backward(float *dx, const float *x, const float *dy, size_t n);
/* In-place ReLU backward: d[i] = 0 where y[i] <= 0. */
void wv_nn_relu_mask(float *d, const float *y, size_t n);
void wv_nn_leaky_relu_forward(float *y, const float *x, float slope, size_t n);
void wv_nn_leaky_relu_backward(float *dx, const float *x, const float *dy, float slope, size_t n);

/* ---- 2x2 average pooling, stride 2, over nc planes of h x w; odd sizes are
 * floored like PyTorch's AvgPool2d(2, 2) (the last row or column is dropped). ---- */
void wv_nn_avgpool2_forward(float *y, const float *x, int nc, int h, int w);
void wv_nn_avgpool2_backward(float *dx, const float *dy, int nc, int h, int w);

/* ---- Gram matrix: g[i] = F_i F_i^T / hw for each of n feature maps F_i (c x hw). ---- */
void wv_nn_gram_forward(float *g, const float *f, int n, int c, int hw);
void wv_nn_gram_backward(float *df, const float *f, const float *dg, int n, int c, int hw);

/* ---- Fully connected: y (batch, out) = x (batch, in) W^T + b, W (out, in) as in
 * PyTorch's nn.Linear, b (out) or NULL. ---- */
void wv_nn_fc_forward(float *y, const float *x, const float *w, const float *b, int batch, int in,
                      int out);
void wv_nn_fc_backward(float *dx, float *dw, float *db, const float *dy, const float *x,
                       const float *w, int batch, int in, int out);

/* ---- Sigmoid (backward takes the output y). ---- */
void wv_nn_sigmoid_forward(float *y, const float *x, size_t n);
void wv_nn_sigmoid_backward(float *dx, const float *y, const float *dy, size_t n);

/* ---- L1 distance, the library's one (also the texture and pixel losses of loss.h
 * and imgops.h, and wv_image_mad): returns sum |a - b| over n values, summed in
 * double; when grad is not NULL, adds g sign(a - b) to it (the subgradient 0 at
 * a == b). Each difference is taken in double, or with float_diff rounded to float
 * first. ---- */
double wv_nn_l1(const float *a, const float *b, size_t n, int float_diff, float *grad, float g);
/* L1 loss: mean |pred - target| over n values; backward adds dloss * dL/dpred. */
float wv_nn_l1_forward(const float *pred, const float *target, size_t n);
void wv_nn_l1_backward(float *dpred, const float *pred, const float *target, float dloss, size_t n);

/* ---- Softmax cross-entropy over k classes: logits (batch, k), labels (batch) in 0..k-1.
 * forward returns the mean over the batch of -log softmax(logits)[label] and, when
 * prob is not NULL, fills it with the softmax (batch, k); backward adds
 * dloss (softmax - onehot) / batch to dlogits, from the probabilities. ---- */
float wv_nn_softmax_xent_forward(float *prob, const float *logits, const int *labels, int batch, int k);
void wv_nn_softmax_xent_backward(float *dlogits, const float *prob, const int *labels, float dloss, int batch, int k);

/* ---- Adam (Kingma & Ba 2015) with bias correction; optional decoupled weight decay
 * (AdamW, Loshchilov & Hutter 2019). ---- */
typedef struct {
  size_t n;
  float lr, beta1, beta2, eps, weight_decay;
  long t;          /* steps taken */
  float *m, *v;    /* moments, n floats each, owned */
} wv_nn_adam;

/* Defaults beta1 0.9, beta2 0.999, eps 1e-8, weight_decay 0; moments zero. A caller may
 * also fill the struct itself with m, v pointing at its own storage (then it must not
 * call wv_nn_adam_free). */
wv_status wv_nn_adam_init(wv_nn_adam *a, size_t n, float lr, wv_error *err);
void wv_nn_adam_step(wv_nn_adam *a, float *params, const float *grads);
/* The same step, then every parameter clamped to [lo, hi] (projected Adam: the fit keeps
 * each normalised parameter inside its range this way). */
void wv_nn_adam_step_box(wv_nn_adam *a, float *params, const float *grads, float lo, float hi);
void wv_nn_adam_free(wv_nn_adam *a);

/* ---- Limited-memory BFGS directions on a box [lo, hi]^n (Nocedal & Wright, algorithm 7.4),
 * for small problems (n <= WV_NN_LBFGS_DIM) with dear evaluations. Plain data: a caller keeps
 * the struct (and may save it) and runs its own line search along the direction. ---- */
#define WV_NN_LBFGS_DIM 18 /* the largest n */
#define WV_NN_LBFGS_MEM 5  /* curvature pairs kept */
typedef struct {
  int n, count, has_prev, stuck;
  double s[WV_NN_LBFGS_MEM][WV_NN_LBFGS_DIM], y[WV_NN_LBFGS_MEM][WV_NN_LBFGS_DIM]; /* oldest first */
  double f_prev, x_prev[WV_NN_LBFGS_DIM], g_prev[WV_NN_LBFGS_DIM]; /* the point of the last call */
} wv_nn_lbfgs;

/* No curvature seen, n coordinates. */
void wv_nn_lbfgs_reset(wv_nn_lbfgs *q, int n);
/* n coordinates (at least q->n), the new ones appended: the pairs kept, with 0 along the new
 * coordinates (no step moved them), and the last point forgotten (its gradient had none). */
void wv_nn_lbfgs_grow(wv_nn_lbfgs *q, int n);
/* The direction d at x with value f and gradient g: first the pair (x - x_prev, g - g_prev) of
 * the last call joins the memory (where its curvature is positive and the mean of the two
 * gradients along the step gives f - f_prev within half), then d = -H g over the coordinates
 * free to move (a coordinate on a bound whose descent points out of the box gets 0). With no
 * curvature yet, or when -H g does not descend, d = -g on the free coordinates. Returns the
 * number of pairs d was made from (0: steepest descent), or -1 with d = 0 when x is the point
 * where a steepest descent was last turned down (wv_nn_lbfgs_reject): nothing is left to try. */
int wv_nn_lbfgs_direction(wv_nn_lbfgs *q, const double *x, double f, const double *g, double lo, double hi,
                          double *d);
/* The caller's line search turned down every step along the last direction: the memory is
 * cleared (the next direction is the steepest descent), or, when that direction already was,
 * the point is marked as one to stay at. */
void wv_nn_lbfgs_reject(wv_nn_lbfgs *q);

/* ---- safetensors (Hugging Face): 8-byte little-endian header length, a JSON
 * header {name: {dtype, shape, data_offsets [begin, end)}} and the data bytes.
 * open() validates the whole header (length, JSON, dtypes, shapes, sizes, offsets
 * inside the file, no overlaps) and keeps the file open; tensors are read on demand. */
#define WV_ST_MAX_DIMS 8
typedef struct {
  char *name;
  char dtype[8];
  int ndim;
  int64_t shape[WV_ST_MAX_DIMS];
  uint64_t begin, end; /* byte offsets into the data section */
} wv_st_tensor;

typedef struct {
  void *file;          /* FILE *, kept open */
  char *path;
  uint64_t data_start; /* file offset of the data section */
  uint64_t data_size;
  int n;
  wv_st_tensor *t;
} wv_safetensors;

wv_status wv_st_open(wv_safetensors *st, const char *path, wv_error *err);
void wv_st_close(wv_safetensors *st);
const wv_st_tensor *wv_st_find(const wv_safetensors *st, const char *name);
/* Reads tensor `name` as floats (F32, F16 or BF16) after checking it exists and has
 * exactly the given shape. out holds the product of shape floats. */
wv_status wv_st_read_f32(wv_safetensors *st, const char *name, int ndim, const int64_t *shape,
                         float *out, wv_error *err);
/* Writes n F32 tensors (written to path.tmp, then renamed into place). */
wv_status wv_st_write_f32(const char *path, int n, const char *const *names, const int *ndims,
                          const int64_t *const *shapes, const float *const *data, wv_error *err);

float wv_nn_f16_to_f32(uint16_t h);
float wv_nn_bf16_to_f32(uint16_t h);

#ifdef __cplusplus
}
#endif
#endif
