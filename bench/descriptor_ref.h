/* The default descriptor as it was computed before its fused kernel: im2col, OpenBLAS
 * sgemm, ReLU, ssyrk for the Gram matrix and, for the gradient, two more sgemms and
 * col2im, per block of output positions on each OpenMP thread. Kept for
 * bench_descriptor only, which times it against the library in the same run and
 * reports how far the two results differ. Same interface as the descriptor's run
 * hook (descriptor/internal.h): planar normalised input, unweighted Gram blocks. */
#ifndef WOVEN_BENCH_DESCRIPTOR_REF_H
#define WOVEN_BENCH_DESCRIPTOR_REF_H
#include <cblas.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "descriptor/internal.h"
#include "woven/nn.h"

#define REF_LEVELS 5
#define REF_BLOCK_FLOATS (3 << 16) /* 768 kB */

typedef struct {
  const float *w[REF_LEVELS];
  int k, c, nthreads;
  float *lev[REF_LEVELS], *dlev[REF_LEVELS];
  int lw[REF_LEVELS], lh[REF_LEVELS], blk[REF_LEVELS];
  float *scratch, *gpart, *dxpart;
  size_t per_thread;
} ref_net;

static void ref_free(ref_net *m) {
  for (int s = 1; s < REF_LEVELS; s++) free(m->lev[s]), free(m->dlev[s]);
  free(m->scratch), free(m->gpart), free(m->dxpart);
}

/* Buffers for a w x h image; 0 on success. */
static int ref_init(ref_net *m, const wv_descriptor *d, int w, int h) {
  memset(m, 0, sizeof *m);
  for (int s = 0; s < REF_LEVELS; s++)
    if (wv_descriptor_default_filters(d, s, &m->k, &m->c, &m->w[s]) != REF_LEVELS) return -1;
  int nt = omp_get_max_threads(), k = m->k, c = m->c, kk = 3 * k * k;
  m->nthreads = nt;
  size_t per = 0;
  for (int s = 0; s < REF_LEVELS; s++) {
    m->lw[s] = s ? m->lw[s - 1] / 2 : w;
    m->lh[s] = s ? m->lh[s - 1] / 2 : h;
    int oh = m->lh[s] - k + 1, ow = m->lw[s] - k + 1;
    long npos = (long)oh * ow, len = REF_BLOCK_FLOATS / (kk + 2 * c);
    if (len < 256) len = 256;
    long nb = (npos + len - 1) / len;
    if (nb < 4 * nt) nb = 4 * nt;
    if (nb > npos) nb = npos;
    m->blk[s] = (int)((npos + nb - 1) / nb);
    size_t need = (size_t)m->blk[s] * (kk + 2 * c);
    if (need > per) per = need;
    if (s) {
      size_t n = (size_t)3 * m->lw[s] * m->lh[s];
      m->lev[s] = malloc(sizeof(float) * n), m->dlev[s] = malloc(sizeof(float) * n);
    }
  }
  m->per_thread = per;
  m->scratch = malloc(sizeof(float) * per * nt);
  m->gpart = malloc(sizeof(float) * (size_t)c * c * nt);
  m->dxpart = malloc(sizeof(float) * 3 * (size_t)w * h * (nt > 1 ? nt - 1 : 1));
  return 0;
}

static double ref_cpu_ms(void) { /* the calling thread's CPU time */
  struct timespec t;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return t.tv_sec * 1e3 + t.tv_nsec * 1e-6;
}

/* REF_PARTS parts of a level pass, in the order ref_level runs them. */
#define REF_PARTS 7
static const char *const ref_part_name[REF_PARTS] = {
    "im2col", "filters (sgemm 64 x n x 27)", "ReLU", "Gram (ssyrk 64 x 64, upper)",
    "dF = S F (sgemm 64 x n x 64) and the ReLU mask", "W^T dF (sgemm 27 x n x 64)", "col2im"};

/* part: NULL, or REF_PARTS sums of the first thread's CPU milliseconds per part (meant
 * for one thread). */
static void ref_level(ref_net *m, int s, const float *S, float *gram, float *dx, double *part) {
  const float *x = m->lev[s], *W = m->w[s];
  int w = m->lw[s], h = m->lh[s], k = m->k, c = m->c, kk = 3 * k * k;
  int oh = h - k + 1, ow = w - k + 1, npos = oh * ow, bl = m->blk[s];
  int nb = (npos + bl - 1) / bl, nt = m->nthreads;
  size_t nx = (size_t)3 * w * h;
#pragma omp parallel num_threads(nt)
  {
    int tid = omp_get_thread_num();
    float *col = m->scratch + (size_t)tid * m->per_thread;
    float *f = col + (size_t)kk * bl, *df = f + (size_t)c * bl;
    float *gp = m->gpart + (size_t)tid * c * c;
    float *dxt = tid ? m->dxpart + (size_t)(tid - 1) * nx : dx;
    memset(gp, 0, sizeof(float) * c * c);
    if (S && tid) memset(dxt, 0, sizeof(float) * nx);
#pragma omp for schedule(static)
    for (int b = 0; b < nb; b++) {
      int p0 = b * bl, p1 = p0 + bl < npos ? p0 + bl : npos, len = p1 - p0;
      double t[REF_PARTS + 1];
#define REF_MARK(i) \
  if (part && !tid) t[i] = ref_cpu_ms()
      REF_MARK(0);
      wv_nn_im2col(x, 3, h, w, k, 1, 0, ow, p0, p1, col);
      REF_MARK(1);
      cblas_sgemm(CblasRowMajor, CblasNoTrans, CblasNoTrans, c, len, kk, 1.0f, W, kk, col, len,
                  0.0f, f, len);
      REF_MARK(2);
#pragma omp simd
      for (size_t i = 0; i < (size_t)c * len; i++) f[i] = f[i] > 0.0f ? f[i] : 0.0f;
      REF_MARK(3);
      cblas_ssyrk(CblasRowMajor, CblasUpper, CblasNoTrans, c, len, 1.0f, f, len, 1.0f, gp, c);
      REF_MARK(4);
      if (S) {
        cblas_sgemm(CblasRowMajor, CblasNoTrans, CblasNoTrans, c, len, c, 1.0f, S, c, f, len,
                    0.0f, df, len);
#pragma omp simd
        for (size_t i = 0; i < (size_t)c * len; i++) df[i] = f[i] > 0.0f ? df[i] : 0.0f;
        REF_MARK(5);
        cblas_sgemm(CblasRowMajor, CblasTrans, CblasNoTrans, kk, len, c, 1.0f, W, kk, df, len,
                    0.0f, col, len);
        REF_MARK(6);
        wv_nn_col2im(col, 3, h, w, k, 1, 0, ow, p0, p1, dxt);
        REF_MARK(7);
        if (part && !tid)
          for (int i = 0; i < REF_PARTS; i++) part[i] += t[i + 1] - t[i];
      }
#undef REF_MARK
    }
    if (S && nt > 1) {
#pragma omp for schedule(static)
      for (size_t i = 0; i < nx; i++) {
        float v = dx[i];
        for (int t = 1; t < nt; t++) v += m->dxpart[(size_t)(t - 1) * nx + i];
        dx[i] = v;
      }
    }
  }
  float inv = 1.0f / (float)npos;
  for (int i = 0; i < c; i++)
    for (int j = i; j < c; j++) {
      float v = 0.0f;
      for (int t = 0; t < nt; t++) v += m->gpart[(size_t)t * c * c + (size_t)i * c + j];
      gram[(size_t)i * c + j] = gram[(size_t)j * c + i] = v * inv;
    }
}

/* Gram blocks of the planar normalised image x (w x h, the size given to ref_init);
 * with dgram, also the gradient of sum(dgram .* gram) into dx (overwritten). part:
 * NULL, or the parts of level 0's pass (ref_level). */
static void ref_run(ref_net *m, const float *x, const float *dgram, float *gram, float *dx,
                    double *part) {
  wv_nn_blas_serial();
  int c = m->c;
  m->lev[0] = (float *)x;
  m->dlev[0] = dx;
  for (int s = 1; s < REF_LEVELS; s++)
    wv_nn_avgpool2_forward(m->lev[s], m->lev[s - 1], 3, m->lh[s - 1], m->lw[s - 1]);
  float *S = malloc(sizeof(float) * c * c);
  for (int s = 0; s < REF_LEVELS; s++) {
    const float *Sp = NULL;
    if (dgram) {
      const float *dg = dgram + (size_t)s * c * c;
      float inv = 1.0f / (float)((m->lh[s] - m->k + 1) * (m->lw[s] - m->k + 1));
      for (int i = 0; i < c; i++)
        for (int j = 0; j < c; j++) S[i * c + j] = (dg[i * c + j] + dg[j * c + i]) * inv;
      memset(m->dlev[s], 0, sizeof(float) * 3 * m->lw[s] * m->lh[s]);
      Sp = S;
    }
    ref_level(m, s, Sp, gram + (size_t)s * c * c, m->dlev[s], s ? NULL : part);
  }
  free(S);
  if (dgram)
    for (int s = REF_LEVELS - 1; s > 0; s--)
      wv_nn_avgpool2_backward(m->dlev[s - 1], m->dlev[s], 3, m->lh[s - 1], m->lw[s - 1]);
}
#endif
