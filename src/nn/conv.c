/* 2-D convolution as im2col + sgemm, one block of output positions per OpenMP
 * thread and a single-threaded sgemm per block (nn.h explains why). */
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
  /* Backward blocks are whole output rows; blocks two apart never touch the same input
   * row in col2im, so even blocks and then odd blocks can run in parallel. */
  int minrows = (k + stride - 1) / stride;
  long rows = CONV_BLOCK_FLOATS / (kk * cv->ow);
  if (n < cv->nthreads) {
    long per = (cv->oh + 2 * cv->nthreads - 1) / (2 * cv->nthreads);
    if (rows > per) rows = per;
  }
  if (rows < minrows) rows = minrows;
  if (rows > cv->oh) rows = cv->oh;
  cv->rows = (int)rows;
  return WV_OK;
}

static int is_pointwise(const wv_nn_conv2d *cv) {
  return cv->k == 1 && cv->stride == 1 && cv->pad == 0;
}

size_t wv_nn_conv2d_scratch_floats(const wv_nn_conv2d *cv, int with_dw) {
  size_t kk = (size_t)cv->c * cv->k * cv->k;
  size_t blk = (size_t)cv->chunk;
  if ((size_t)cv->rows * cv->ow > blk) blk = (size_t)cv->rows * cv->ow;
  size_t s = (size_t)cv->nthreads * kk * blk;
  if (with_dw) s += (size_t)cv->nthreads * cv->oc * kk;
  return s;
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
      float *d = dst + (pos - p0) - ox0; /* d[ox] for ox in [ox0, ox1) */
      int iy = oy * stride + ki - pad;
      if (iy < 0 || iy >= h) {
        memset(d + ox0, 0, sizeof(float) * (ox1 - ox0));
      } else {
        const float *src = plane + (size_t)iy * w;
        if (stride == 1) {
          /* Inside the image for ox in [pad - kj, w + pad - kj). */
          int a = pad - kj > ox0 ? pad - kj : ox0;
          int b = w + pad - kj < ox1 ? w + pad - kj : ox1;
          if (b < a) b = a;
          for (int ox = ox0; ox < a; ox++) d[ox] = 0.0f;
          if (b > a) memcpy(d + a, src + a + kj - pad, sizeof(float) * (b - a));
          for (int ox = b; ox < ox1; ox++) d[ox] = 0.0f;
        } else {
          for (int ox = ox0; ox < ox1; ox++) {
            int ix = ox * stride + kj - pad;
            d[ox] = (ix >= 0 && ix < w) ? src[ix] : 0.0f;
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
      const float *s = src + (pos - p0) - ox0;
      int iy = oy * stride + ki - pad;
      if (iy >= 0 && iy < h) {
        float *d = plane + (size_t)iy * w;
        if (stride == 1) {
          int a = pad - kj > ox0 ? pad - kj : ox0;
          int b = w + pad - kj < ox1 ? w + pad - kj : ox1;
          float *dd = d + kj - pad;
          for (int ox = a; ox < b; ox++) dd[ox] += s[ox];
        } else {
          for (int ox = ox0; ox < ox1; ox++) {
            int ix = ox * stride + kj - pad;
            if (ix >= 0 && ix < w) d[ix] += s[ox];
          }
        }
      }
      pos += ox1 - ox0;
    }
  }
}

void wv_nn_conv2d_forward(const wv_nn_conv2d *cv, const float *x, const float *w, const float *b,
                          float *y, float *scratch) {
  wv_nn_blas_serial();
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
  int kk = cv->c * cv->k * cv->k, npos = cv->oh * cv->ow, nth = cv->nthreads;
  if (db) wv_nn_bias_backward(NULL, db, dy, cv->n, cv->oc, npos);
  if (!dx && !dw) return;
  size_t blk = (size_t)cv->chunk;
  if ((size_t)cv->rows * cv->ow > blk) blk = (size_t)cv->rows * cv->ow;
  float *dwpart = scratch + (size_t)nth * kk * blk;
  if (dw) memset(dwpart, 0, sizeof(float) * nth * cv->oc * kk);
  int nb = (cv->oh + cv->rows - 1) / cv->rows; /* row blocks per image */
  int pw = is_pointwise(cv);
#pragma omp parallel num_threads(nth)
  {
    int tid = omp_get_thread_num();
    float *buf = scratch + (size_t)tid * kk * blk;
    float *dwt = dwpart + (size_t)tid * cv->oc * kk;
    for (int phase = 0; phase < 2; phase++) {
      int nphase = (nb + 1 - phase) / 2; /* blocks of this parity per image */
#pragma omp for schedule(static)
      for (int t = 0; t < cv->n * nphase; t++) {
        int img = t / nphase, blkno = 2 * (t % nphase) + phase;
        int p0 = blkno * cv->rows * cv->ow;
        int p1 = p0 + cv->rows * cv->ow < npos ? p0 + cv->rows * cv->ow : npos, len = p1 - p0;
        const float *xi = x + (size_t)img * cv->c * cv->h * cv->w;
        const float *dyi = dy + (size_t)img * cv->oc * npos + p0;
        float *dxi = dx ? dx + (size_t)img * cv->c * cv->h * cv->w : NULL;
        if (dw) {
          const float *col = xi + p0;
          int ldcol = npos;
          if (!pw) {
            wv_nn_im2col(xi, cv->c, cv->h, cv->w, cv->k, cv->stride, cv->pad, cv->ow, p0, p1, buf);
            col = buf, ldcol = len;
          }
          /* dW += dy_block col^T */
          wv_nn_sgemm(0, 1, cv->oc, kk, len, 1.0f, dyi, npos, col, ldcol, 1.0f, dwt, kk);
        }
        if (dx) {
          if (pw) {
            wv_nn_sgemm(1, 0, kk, len, cv->oc, 1.0f, w, kk, dyi, npos, 1.0f, dxi + p0, npos);
          } else {
            /* dcol = W^T dy_block, then scattered back onto the input. */
            wv_nn_sgemm(1, 0, kk, len, cv->oc, 1.0f, w, kk, dyi, npos, 0.0f, buf, len);
            wv_nn_col2im(buf, cv->c, cv->h, cv->w, cv->k, cv->stride, cv->pad, cv->ow, p0, p1,
                         dxi);
          }
        }
      }
    }
    if (dw) {
      /* Sum the per-thread parts in thread order: deterministic. */
      size_t total = (size_t)cv->oc * kk;
#pragma omp for schedule(static)
      for (size_t i = 0; i < total; i++) {
        float s = 0.0f;
        for (int t = 0; t < nth; t++) s += dwpart[(size_t)t * total + i];
        dw[i] += s;
      }
    }
  }
}
