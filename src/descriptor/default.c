/* The default descriptor: random multi-scale filters (docs/descriptor.md).
 *
 * Ustyuzhaninov et al. (ICLR 2017, "What does it take to generate natural
 * textures?") found that Gram matrices of a single layer of random filters of
 * several sizes, followed by ReLU, describe textures nearly as well as VGG's.
 * Large filters are costly at full resolution, so we apply 3x3 random filters to
 * every level of an average-pooled image pyramid (a filter on level s spans
 * 3 * 2^s pixels of the image), with their flat-colour response attenuated so
 * that they are mostly band-pass. Each level: valid convolution (no padding, so
 * no border artefacts), ReLU, Gram / (H W). 5 levels x 64 filters: 20,480 floats.
 *
 * Speed: each level runs as one fused pass over blocks of output positions, each
 * block on one OpenMP thread: im2col, sgemm, ReLU, Gram update (ssyrk) and, for the
 * gradient, dF = (dG + dG^T) F / HW, the ReLU mask, W^T dF and col2im, all on data
 * that stays in the thread's L2 cache; the feature maps are never stored whole.
 * Forward and backward take one pass, since dF needs dG and F but not G. Each thread
 * keeps its own Gram and input-gradient sums, added in thread order at the end. */
#include <cblas.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "descriptor/internal.h"
#include "woven/nn.h"

#define RMF_LEVELS 5
#define RMF_MAXC 64
static const int rmf_k[RMF_LEVELS] = {3, 3, 3, 3, 3};      /* filter sizes */
static const int rmf_c[RMF_LEVELS] = {64, 64, 64, 64, 64}; /* filters per level */
#define RMF_DC 0.1f /* kept fraction of each filter's mean (see create) */
/* Fixed seed: the weights are part of the descriptor's definition. */
#define RMF_SEED 0x776f76656e524d46ULL /* "wovenRMF" */
#define RMF_BLOCK_FLOATS (3 << 16) /* 768 kB */

typedef struct {
  float *w[RMF_LEVELS]; /* (c, 3, k, k) per level */
  int w_img, h_img, nthreads;
  float *lev[RMF_LEVELS], *dlev[RMF_LEVELS]; /* lev[0], dlev[0] are the caller's */
  int lw[RMF_LEVELS], lh[RMF_LEVELS];
  int blk[RMF_LEVELS];                        /* output positions per block */
  float *scratch, *gpart, *dxpart;
  size_t per_thread;
} rmf_net;

static void free_buffers(rmf_net *m) {
  for (int s = 1; s < RMF_LEVELS; s++) {
    free(m->lev[s]), free(m->dlev[s]);
    m->lev[s] = m->dlev[s] = NULL;
  }
  free(m->scratch), free(m->gpart), free(m->dxpart);
  m->scratch = m->gpart = m->dxpart = NULL;
  m->w_img = m->h_img = 0;
}

static void rmf_destroy(void *impl) {
  rmf_net *m = impl;
  if (!m) return;
  free_buffers(m);
  for (int s = 0; s < RMF_LEVELS; s++) free(m->w[s]);
  free(m);
}

static wv_status ensure_buffers(rmf_net *m, int w, int h, wv_error *err) {
  int nt = omp_get_max_threads();
  if (nt < 1) nt = 1;
  if (m->w_img == w && m->h_img == h && m->nthreads == nt) return WV_OK;
  free_buffers(m);
  m->nthreads = nt;
  size_t per = 0;
  for (int s = 0; s < RMF_LEVELS; s++) {
    m->lw[s] = s ? m->lw[s - 1] / 2 : w;
    m->lh[s] = s ? m->lh[s - 1] / 2 : h;
    int k = rmf_k[s], kk = 3 * k * k, c = rmf_c[s];
    int oh = m->lh[s] - k + 1, ow = m->lw[s] - k + 1;
    /* A block's columns, features and their gradient stay in L2. */
    long npos = (long)oh * ow, len = RMF_BLOCK_FLOATS / (kk + 2 * c);
    if (len < 256) len = 256;
    long nb = (npos + len - 1) / len;
    if (nb < 4 * nt) nb = 4 * nt; /* balance */
    if (nb > npos) nb = npos;
    m->blk[s] = (int)((npos + nb - 1) / nb);
    size_t need = (size_t)m->blk[s] * (kk + 2 * c); /* col, F, dF */
    if (need > per) per = need;
    if (s) {
      size_t n = (size_t)3 * m->lw[s] * m->lh[s];
      if (!(m->lev[s] = malloc(sizeof(float) * n)) || !(m->dlev[s] = malloc(sizeof(float) * n)))
        goto oom;
    }
  }
  m->per_thread = per;
  /* Threads other than the first accumulate input gradients in their own copy. */
  if (!(m->scratch = malloc(sizeof(float) * per * nt)) ||
      !(m->gpart = malloc(sizeof(float) * (size_t)RMF_MAXC * RMF_MAXC * nt)) ||
      !(m->dxpart = malloc(sizeof(float) * 3 * (size_t)w * h * (nt > 1 ? nt - 1 : 1))))
    goto oom;
  m->w_img = w, m->h_img = h;
  return WV_OK;
oom:
  free_buffers(m);
  return wv_fail(err, WV_ERR_NOMEM, "out of memory for the default descriptor on a %d x %d image",
                 w, h);
}

/* One pyramid level: Gram into gram (c x c); with S = (dG + dG^T) / HW, also adds the
 * input gradient into dx (zero on entry). Blocks go to threads in a fixed order and
 * partial sums are added in thread order, so results are deterministic. */
static void level_pass(rmf_net *m, int s, const float *S, float *gram, float *dx) {
  const float *x = m->lev[s];
  const float *W = m->w[s];
  int w = m->lw[s], h = m->lh[s], k = rmf_k[s], c = rmf_c[s], kk = 3 * k * k;
  int oh = h - k + 1, ow = w - k + 1, npos = oh * ow, bl = m->blk[s];
  int nb = (npos + bl - 1) / bl, nt = m->nthreads;
  size_t nx = (size_t)3 * w * h;
  /* The team may be smaller than asked (a nested region gets one thread): only the
   * threads that ran hold partial sums, so only theirs are added. */
  int used = 1;
#pragma omp parallel num_threads(nt)
  {
    int tid = omp_get_thread_num();
#pragma omp single
    used = omp_get_num_threads();
    float *col = m->scratch + (size_t)tid * m->per_thread;
    float *f = col + (size_t)kk * bl, *df = f + (size_t)c * bl;
    float *gp = m->gpart + (size_t)tid * c * c;
    float *dxt = tid ? m->dxpart + (size_t)(tid - 1) * nx : dx;
    memset(gp, 0, sizeof(float) * c * c);
    if (S && tid) memset(dxt, 0, sizeof(float) * nx);
#pragma omp for schedule(static)
    for (int b = 0; b < nb; b++) {
      int p0 = b * bl, p1 = p0 + bl < npos ? p0 + bl : npos, len = p1 - p0;
      wv_nn_im2col(x, 3, h, w, k, 1, 0, ow, p0, p1, col);
      cblas_sgemm(CblasRowMajor, CblasNoTrans, CblasNoTrans, c, len, kk, 1.0f, W, kk, col, len,
                  0.0f, f, len);
#pragma omp simd /* -O2 alone leaves these loops scalar */
      for (size_t i = 0; i < (size_t)c * len; i++) f[i] = f[i] > 0.0f ? f[i] : 0.0f;
      cblas_ssyrk(CblasRowMajor, CblasUpper, CblasNoTrans, c, len, 1.0f, f, len, 1.0f, gp, c);
      if (S) {
        cblas_sgemm(CblasRowMajor, CblasNoTrans, CblasNoTrans, c, len, c, 1.0f, S, c, f, len,
                    0.0f, df, len);
#pragma omp simd
        for (size_t i = 0; i < (size_t)c * len; i++) df[i] = f[i] > 0.0f ? df[i] : 0.0f;
        cblas_sgemm(CblasRowMajor, CblasTrans, CblasNoTrans, kk, len, c, 1.0f, W, kk, df, len,
                    0.0f, col, len);
        wv_nn_col2im(col, 3, h, w, k, 1, 0, ow, p0, p1, dxt);
      }
    }
    if (S && used > 1) {
#pragma omp for schedule(static)
      for (size_t i = 0; i < nx; i++) {
        float v = dx[i];
        for (int t = 1; t < used; t++) v += m->dxpart[(size_t)(t - 1) * nx + i];
        dx[i] = v;
      }
    }
  }
  /* Sum the threads' upper triangles in thread order, mirror, normalise. */
  float inv = 1.0f / (float)npos;
  for (int i = 0; i < c; i++)
    for (int j = i; j < c; j++) {
      float v = 0.0f;
      for (int t = 0; t < used; t++) v += m->gpart[(size_t)t * c * c + (size_t)i * c + j];
      gram[(size_t)i * c + j] = gram[(size_t)j * c + i] = v * inv;
    }
}

static wv_status rmf_run(wv_descriptor *d, const float *x, int w, int h, const float *dgram,
                         float *gram, float *dx, wv_error *err) {
  rmf_net *m = d->impl;
  wv_status rc = ensure_buffers(m, w, h, err);
  if (rc) return rc;
  wv_nn_blas_serial();
  m->lev[0] = (float *)x; /* read only */
  m->dlev[0] = dx;
  for (int s = 1; s < RMF_LEVELS; s++)
    wv_nn_avgpool2_forward(m->lev[s], m->lev[s - 1], 3, m->lh[s - 1], m->lw[s - 1]);
  float S[RMF_MAXC * RMF_MAXC];
  for (int s = 0; s < RMF_LEVELS; s++) {
    int c = rmf_c[s];
    const float *Sp = NULL;
    if (dgram) {
      const float *dg = dgram + d->layer_off[s];
      float inv = 1.0f / (float)((m->lh[s] - rmf_k[s] + 1) * (m->lw[s] - rmf_k[s] + 1));
      for (int i = 0; i < c; i++)
        for (int j = 0; j < c; j++) S[i * c + j] = (dg[i * c + j] + dg[j * c + i]) * inv;
      memset(m->dlev[s], 0, sizeof(float) * 3 * m->lw[s] * m->lh[s]);
      Sp = S;
    }
    level_pass(m, s, Sp, gram + d->layer_off[s], m->dlev[s]);
  }
  if (dgram)
    for (int s = RMF_LEVELS - 1; s > 0; s--)
      wv_nn_avgpool2_backward(m->dlev[s - 1], m->dlev[s], 3, m->lh[s - 1], m->lw[s - 1]);
  return WV_OK;
}

wv_status wv_descriptor_create_default(wv_descriptor **out, wv_error *err) {
  *out = NULL;
  rmf_net *m = calloc(1, sizeof *m);
  if (!m) return wv_fail(err, WV_ERR_NOMEM, "out of memory for the default descriptor");
  wv_rng rng;
  wv_rng_seed(&rng, RMF_SEED);
  for (int s = 0; s < RMF_LEVELS; s++) {
    int kk = 3 * rmf_k[s] * rmf_k[s], c = rmf_c[s];
    m->w[s] = malloc(sizeof(float) * c * kk);
    if (!m->w[s]) {
      rmf_destroy(m);
      return wv_fail(err, WV_ERR_NOMEM, "out of memory for the default descriptor");
    }
    /* Variance 1/kk: unit-variance responses to unit-variance input. */
    float a = sqrtf(3.0f / (float)kk);
    wv_rng_fill_uniform(&rng, m->w[s], (size_t)c * kk, -a, a);
    /* Attenuate each filter's mean over every input channel (its response to a flat
     * colour) to RMF_DC of its random value: the filters become mostly band-pass, so
     * the Gram matrices follow the weave's structure rather than just its mean colour,
     * which still enters through the remaining DC part (docs/descriptor.md). */
    int k2 = rmf_k[s] * rmf_k[s];
    for (int o = 0; o < c; o++)
      for (int ci = 0; ci < 3; ci++) {
        float *f = m->w[s] + (size_t)o * kk + ci * k2, mu = 0.0f;
        for (int i = 0; i < k2; i++) mu += f[i];
        mu /= (float)k2;
        for (int i = 0; i < k2; i++) f[i] -= (1.0f - RMF_DC) * mu;
      }
  }
  wv_descriptor *d;
  wv_status rc = wv_descriptor_alloc(&d, "default", RMF_LEVELS, rmf_c, err);
  if (rc) {
    rmf_destroy(m);
    return rc;
  }
  d->impl = m;
  d->destroy = rmf_destroy;
  d->run = rmf_run;
  /* The coarsest level must still hold one filter. */
  d->min_side = rmf_k[RMF_LEVELS - 1] << (RMF_LEVELS - 1);
  *out = d;
  return WV_OK;
}

int wv_descriptor_default_filters(const wv_descriptor *d, int level, int *k, int *c,
                                  const float **w) {
  if (d->run != rmf_run || level < 0 || level >= RMF_LEVELS) return -1;
  const rmf_net *m = d->impl;
  *k = rmf_k[level], *c = rmf_c[level], *w = m->w[level];
  return RMF_LEVELS;
}
