/* 2-D convolution as im2col + sgemm with single-threaded sgemm calls inside OpenMP
 * regions (nn.h explains why). Two schedules:
 *  - blocks: each thread takes whole blocks of output positions (im2col + sgemm on
 *    its own block, no synchronisation); best for the first layers of a network:
 *    many positions, few input channels.
 *  - shared: one large block at a time; each thread builds the column rows of its
 *    share of the input channels, then multiplies its share of the output channels.
 *    The backward pass always uses this one: a thread owns input channels (its rows
 *    of the column gradient, and col2im into its own planes of dx) and output
 *    channels (its rows of dW), so nothing is summed across threads.
 * Measured on 2 cores for VGG-19 at 400x150, this is as fast as or faster than
 * OpenBLAS's own threaded sgemm on the same matrix shapes. */
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "woven/nn.h"

/* A block's column matrix stays in the thread's L2/L3 between im2col and sgemm. */
#define CONV_BLOCK_FLOATS (1 << 18)

wv_status wv_nn_conv2d_init(wv_nn_conv2d *cv, int n, int c, int h, int w, int oc, int k,
                            int stride, int pad, wv_error *err) {
  memset(cv, 0, sizeof *cv);
  if (n <= 0 || c <= 0 || h <= 0 || w <= 0 || oc <= 0 || k <= 0 || stride <= 0 || pad < 0 ||
      pad >= k)
    return wv_fail(err, WV_ERR_INVALID,
                   "invalid convolution: input %dx%dx%dx%d, %d filters %dx%d, stride %d, pad %d",
                   n, c, h, w, oc, k, k, stride, pad);
  if (h + 2 * pad < k || w + 2 * pad < k)
    return wv_fail(err, WV_ERR_INVALID, "convolution input %dx%d is smaller than its %dx%d filter",
                   w, h, k, k);
  if ((double)c * k * k > 1e7 || (double)h * w > 1e9)
    return wv_fail(err, WV_ERR_NOMEM, "convolution too large (%d channels, %dx%d filter, %dx%d)",
                   c, k, k, w, h);
  cv->n = n, cv->c = c, cv->h = h, cv->w = w;
  cv->oc = oc, cv->k = k, cv->stride = stride, cv->pad = pad;
  cv->oh = (h + 2 * pad - k) / stride + 1;
  cv->ow = (w + 2 * pad - k) / stride + 1;
  int nt = omp_get_max_threads();
  cv->nthreads = nt < 1 ? 1 : nt;
  long kk = (long)c * k * k, npos = (long)cv->oh * cv->ow;
  long chunk = CONV_BLOCK_FLOATS / kk;
  if (chunk < 32) chunk = 32;
  /* With fewer images than threads, cut each image into at least one block per thread. */
  if (n < cv->nthreads) {
    long per = (npos + cv->nthreads - 1) / cv->nthreads;
    if (chunk > per) chunk = per;
  }
  if (chunk > npos) chunk = npos;
  long nb = (npos + chunk - 1) / chunk;
  cv->chunk = (int)((npos + nb - 1) / nb); /* equal blocks */
  /* Per-thread blocks suit many positions and short columns (the first layers); with
   * long columns (many input channels) each block's sgemm would repack the whole weight
   * matrix for few positions, so the threads then share one large block instead. */
  cv->shared = kk * 256 > CONV_BLOCK_FLOATS || n * nb < cv->nthreads;
  return WV_OK;
}

static int is_pointwise(const wv_nn_conv2d *cv) {
  return cv->k == 1 && cv->stride == 1 && cv->pad == 0;
}

/* The shared block (16 MB) stays in L3; at least 256 positions per sgemm. */
#define SHARED_FLOATS (1 << 22)
static int shared_len(const wv_nn_conv2d *cv) {
  long kk = (long)cv->c * cv->k * cv->k, npos = (long)cv->oh * cv->ow;
  long len = SHARED_FLOATS / kk;
  if (len < 256) len = 256;
  if (len > npos) len = npos;
  long nb = (npos + len - 1) / len;
  return (int)((npos + nb - 1) / nb);
}

size_t wv_nn_conv2d_scratch_floats(const wv_nn_conv2d *cv) {
  size_t kk = (size_t)cv->c * cv->k * cv->k;
  size_t blocks = (size_t)cv->nthreads * kk * cv->chunk, shared = kk * shared_len(cv);
  return blocks > shared ? blocks : shared;
}

void wv_nn_im2col(const float *x, int c, int h, int w, int k, int stride, int pad, int ow, int p0,
                  int p1, float *col) {
  int len = p1 - p0;
  for (int r = 0; r < c * k * k; r++) {
    int ci = r / (k * k), ki = (r / k) % k, kj = r % k;
    const float *plane = x + (size_t)ci * h * w;
    float *dst = col + (size_t)r * len;
    for (int pos = p0; pos < p1;) {
      int oy = pos / ow, ox0 = pos % ow;
      int ox1 = ow < ox0 + (p1 - pos) ? ow : ox0 + (p1 - pos);
      float *d = dst + (pos - p0); /* d[ox - ox0] for ox in [ox0, ox1) */
      int iy = oy * stride + ki - pad;
      if (iy < 0 || iy >= h) {
        memset(d, 0, sizeof(float) * (ox1 - ox0));
      } else {
        const float *src = plane + (size_t)iy * w;
        if (stride == 1) {
          /* Inside the image for ox in [pad - kj, w + pad - kj). */
          int a = pad - kj > ox0 ? pad - kj : ox0;
          int b = w + pad - kj < ox1 ? w + pad - kj : ox1;
          if (b < a) b = a;
          for (int ox = ox0; ox < a; ox++) d[ox - ox0] = 0.0f;
          if (b > a) memcpy(d + (a - ox0), src + (a + kj - pad), sizeof(float) * (b - a));
          for (int ox = b; ox < ox1; ox++) d[ox - ox0] = 0.0f;
        } else {
          for (int ox = ox0; ox < ox1; ox++) {
            int ix = ox * stride + kj - pad;
            d[ox - ox0] = (ix >= 0 && ix < w) ? src[ix] : 0.0f;
          }
        }
      }
      pos += ox1 - ox0;
    }
  }
}

void wv_nn_col2im(const float *col, int c, int h, int w, int k, int stride, int pad, int ow,
                  int p0, int p1, float *dx) {
  int len = p1 - p0;
  for (int r = 0; r < c * k * k; r++) {
    int ci = r / (k * k), ki = (r / k) % k, kj = r % k;
    float *plane = dx + (size_t)ci * h * w;
    const float *src = col + (size_t)r * len;
    for (int pos = p0; pos < p1;) {
      int oy = pos / ow, ox0 = pos % ow;
      int ox1 = ow < ox0 + (p1 - pos) ? ow : ox0 + (p1 - pos);
      const float *sp = src + (pos - p0); /* sp[ox - ox0] for ox in [ox0, ox1) */
      int iy = oy * stride + ki - pad;
      if (iy >= 0 && iy < h) {
        float *d = plane + (size_t)iy * w;
        if (stride == 1) {
          int a = pad - kj > ox0 ? pad - kj : ox0;
          int b = w + pad - kj < ox1 ? w + pad - kj : ox1;
          int off = kj - pad;
#pragma omp simd /* -O2 alone leaves it scalar */
          for (int ox = a; ox < b; ox++) d[ox + off] += sp[ox - ox0];
        } else {
          for (int ox = ox0; ox < ox1; ox++) {
            int ix = ox * stride + kj - pad;
            if (ix >= 0 && ix < w) d[ix] += sp[ox - ox0];
          }
        }
      }
      pos += ox1 - ox0;
    }
  }
}

static void split(int n, int tid, int nth, int *a, int *b) {
  *a = (int)((long)n * tid / nth), *b = (int)((long)n * (tid + 1) / nth);
}

/* The calling thread's input channels [c0, c1) and output channels [m0, m1). */
static void thread_share(const wv_nn_conv2d *cv, int *c0, int *c1, int *m0, int *m1) {
  int tid = omp_get_thread_num(), nth = omp_get_num_threads();
  split(cv->c, tid, nth, c0, c1);
  split(cv->oc, tid, nth, m0, m1);
}

static void forward_shared(const wv_nn_conv2d *cv, const float *x, const float *w, const float *b,
                           float *y, float *col) {
  int kk = cv->c * cv->k * cv->k, npos = cv->oh * cv->ow, k2 = cv->k * cv->k;
  int len = shared_len(cv), pw = is_pointwise(cv);
#pragma omp parallel num_threads(cv->nthreads)
  {
    int c0, c1, m0, m1;
    thread_share(cv, &c0, &c1, &m0, &m1);
    for (int img = 0; img < cv->n; img++) {
      const float *xi = x + (size_t)img * cv->c * cv->h * cv->w;
      float *yi = y + (size_t)img * cv->oc * npos;
      for (int p0 = 0; p0 < npos; p0 += len) {
        int p1 = p0 + len < npos ? p0 + len : npos, l = p1 - p0;
        const float *cp = xi + p0; /* pointwise: the input is its own column matrix */
        int ldb = npos;
        if (!pw) {
          wv_nn_im2col(xi + (size_t)c0 * cv->h * cv->w, c1 - c0, cv->h, cv->w, cv->k, cv->stride,
                       cv->pad, cv->ow, p0, p1, col + (size_t)c0 * k2 * l);
          cp = col, ldb = l;
#pragma omp barrier
        }
        if (m1 > m0)
          wv_nn_sgemm(0, 0, m1 - m0, l, kk, 1.0f, w + (size_t)m0 * kk, kk, cp, ldb, 0.0f,
                      yi + (size_t)m0 * npos + p0, npos);
        if (b)
          for (int o = m0; o < m1; o++) {
            float *row = yi + (size_t)o * npos + p0;
            for (int i = 0; i < l; i++) row[i] += b[o];
          }
#pragma omp barrier
      }
    }
  }
}

static void backward_shared(const wv_nn_conv2d *cv, const float *x, const float *w, const float *dy,
                            float *dx, float *dw, float *col) {
  int kk = cv->c * cv->k * cv->k, npos = cv->oh * cv->ow, k2 = cv->k * cv->k;
  int len = shared_len(cv), pw = is_pointwise(cv);
#pragma omp parallel num_threads(cv->nthreads)
  {
    int c0, c1, m0, m1;
    thread_share(cv, &c0, &c1, &m0, &m1);
    int r0 = c0 * k2, r1 = c1 * k2;
    for (int img = 0; img < cv->n; img++) {
      const float *xi = x + (size_t)img * cv->c * cv->h * cv->w;
      const float *dyi = dy + (size_t)img * cv->oc * npos;
      float *dxi = dx ? dx + (size_t)img * cv->c * cv->h * cv->w : NULL;
      for (int p0 = 0; p0 < npos; p0 += len) {
        int p1 = p0 + len < npos ? p0 + len : npos, l = p1 - p0;
        if (dw) {
          const float *cp = xi + p0;
          int ldb = npos;
          if (!pw) {
            wv_nn_im2col(xi + (size_t)c0 * cv->h * cv->w, c1 - c0, cv->h, cv->w, cv->k,
                         cv->stride, cv->pad, cv->ow, p0, p1, col + (size_t)r0 * l);
            cp = col, ldb = l;
#pragma omp barrier
          }
          /* Each thread owns rows m0..m1 of dW: no partial sums. */
          if (m1 > m0)
            wv_nn_sgemm(0, 1, m1 - m0, kk, l, 1.0f, dyi + (size_t)m0 * npos + p0, npos, cp, ldb,
                        1.0f, dw + (size_t)m0 * kk, kk);
#pragma omp barrier
        }
        if (dx && r1 > r0) {
          /* Each thread owns input channels c0..c1: its rows of dcol and its planes of dx. */
          if (pw) {
            wv_nn_sgemm(1, 0, r1 - r0, l, cv->oc, 1.0f, w + r0, kk, dyi + p0, npos, 1.0f,
                        dxi + (size_t)r0 * npos + p0, npos);
          } else {
            wv_nn_sgemm(1, 0, r1 - r0, l, cv->oc, 1.0f, w + r0, kk, dyi + p0, npos, 0.0f,
                        col + (size_t)r0 * l, l);
            wv_nn_col2im(col + (size_t)r0 * l, c1 - c0, cv->h, cv->w, cv->k, cv->stride, cv->pad,
                         cv->ow, p0, p1, dxi + (size_t)c0 * cv->h * cv->w);
          }
        }
#pragma omp barrier
      }
    }
  }
}

void wv_nn_conv2d_forward(const wv_nn_conv2d *cv, const float *x, const float *w, const float *b,
                          float *y, float *scratch) {
  wv_nn_blas_serial();
  if (cv->shared) {
    forward_shared(cv, x, w, b, y, scratch);
    return;
  }
  int kk = cv->c * cv->k * cv->k, npos = cv->oh * cv->ow;
  int nb = (npos + cv->chunk - 1) / cv->chunk, ntask = cv->n * nb;
  int pw = is_pointwise(cv);
#pragma omp parallel for schedule(static) num_threads(cv->nthreads)
  for (int t = 0; t < ntask; t++) {
    int img = t / nb, p0 = (t % nb) * cv->chunk;
    int p1 = p0 + cv->chunk < npos ? p0 + cv->chunk : npos, len = p1 - p0;
    const float *xi = x + (size_t)img * cv->c * cv->h * cv->w;
    float *yi = y + (size_t)img * cv->oc * npos + p0;
    const float *col;
    int ldcol;
    if (pw) {
      col = xi + p0, ldcol = npos;
    } else {
      float *buf = scratch + (size_t)omp_get_thread_num() * kk * cv->chunk;
      wv_nn_im2col(xi, cv->c, cv->h, cv->w, cv->k, cv->stride, cv->pad, cv->ow, p0, p1, buf);
      col = buf, ldcol = len;
    }
    wv_nn_sgemm(0, 0, cv->oc, len, kk, 1.0f, w, kk, col, ldcol, 0.0f, yi, npos);
    if (b)
      for (int o = 0; o < cv->oc; o++) {
        float *row = yi + (size_t)o * npos;
        for (int i = 0; i < len; i++) row[i] += b[o];
      }
  }
}

void wv_nn_conv2d_backward(const wv_nn_conv2d *cv, const float *x, const float *w, const float *dy,
                           float *dx, float *dw, float *db, float *scratch) {
  wv_nn_blas_serial();
  if (db) wv_nn_bias_backward(NULL, db, dy, cv->n, cv->oc, cv->oh * cv->ow);
  if (dx || dw) backward_shared(cv, x, w, dy, dx, dw, scratch);
}
