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
 * Speed: all levels' output rows are cut into chunks of a few rows, shared out to
 * the OpenMP threads; a chunk runs the fused kernel of default_kernel.inc (conv,
 * ReLU, Gram sums and, for the gradient, dF = (dG + dG^T) F / HW, the ReLU mask,
 * W^T dF and col2im) with its data in the thread's cache, so the feature maps are
 * never stored whole. Forward and backward take one pass, since dF needs dG and F
 * but not G; without a Gram output the backward skips the Gram sums. Each chunk
 * keeps its own Gram sums and writes the input gradient of the two rows it shares
 * with the next chunk to a halo; both are added in chunk order at the end, so the
 * result does not depend on the thread count or on which thread ran what. The
 * kernel is compiled for AVX-512, AVX2 and the baseline and chosen when the
 * descriptor is created. */
#include <math.h>
#include <omp.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "descriptor/internal.h"
#include "woven/nn.h"

#define RMF_LEVELS 5
#define RMF_C 64 /* filters per level */
#define RMF_K 3  /* filter size */
static const int rmf_c[RMF_LEVELS] = {RMF_C, RMF_C, RMF_C, RMF_C, RMF_C};
#define RMF_DC 0.1f /* kept fraction of each filter's mean (see create) */
/* Fixed seed: the weights are part of the descriptor's definition. */
#define RMF_SEED 0x776f76656e524d46ULL /* "wovenRMF" */
#define RMF_TAPS (3 * RMF_K * RMF_K)

/* One pyramid level as the kernel sees it (default_kernel.inc). */
typedef struct {
  const float *x; /* 3 padded planes: rows of xs floats, zeros past the image */
  float *dx;      /* the gradient, same layout */
  int xs, ow, npv, fs; /* row stride, outputs per row, vectors per row, F's row stride */
  size_t plane;        /* plane stride (floats) */
  const float *w, *wt; /* filters (64 x 27) and their transpose (27 x 64) */
  const float *S;      /* (dG + dG^T) / (H W), or NULL for no gradient */
} rmf_level;

/* One thread's working set. */
typedef struct {
  float *f, *df, *gv, *carry;
} rmf_scratch;

typedef struct {
  void (*chunk)(const rmf_level *L, const rmf_scratch *sc, int y0, int y1, float *gsum,
                float *halo);
  int kv;  /* floats per vector */
  int sub; /* vectors per gradient sub-block */
  int id;  /* WV_DESC_KERNEL_* */
} rmf_isa;

/* The kernel compiled for AVX-512, AVX2 + FMA and the baseline; the multiply-adds
 * may contract into FMAs (a rounding difference only). */
/* Kernel helpers pass vectors by value but are always inlined, so the note that
 * such an ABI differs between targets does not apply. */
#pragma GCC diagnostic ignored "-Wpsabi"
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#define RMF_X86 1
#pragma GCC push_options
#pragma GCC optimize("fp-contract=fast")
#pragma GCC target("avx512f,avx512vl,avx512bw,avx512dq,avx2,fma")
#define KV 16
#define KN(n) n##_avx512
#define KID WV_DESC_KERNEL_AVX512
#define KA_O 8
#define KA_P 3
#define KB_I 4
#define KB_J 4
#define KC_O 8
#define KC_P 3
#define KD_R 2
#include "descriptor/default_kernel.inc"
#pragma GCC pop_options
#pragma GCC push_options
#pragma GCC optimize("fp-contract=fast")
#pragma GCC target("avx2,fma")
#define KV 8
#define KN(n) n##_avx2
#define KID WV_DESC_KERNEL_AVX2
#define KA_O 4
#define KA_P 3
#define KB_I 2
#define KB_J 4
#define KC_O 4
#define KC_P 3
#define KD_R 1
#include "descriptor/default_kernel.inc"
#pragma GCC pop_options
#endif
#define KV 4
#define KN(n) n##_base
#define KID WV_DESC_KERNEL_BASE
#define KA_O 4
#define KA_P 2
#define KB_I 2
#define KB_J 4
#define KC_O 4
#define KC_P 2
#define KD_R 1
#include "descriptor/default_kernel.inc"

/* The widest kernel the CPU runs, at most `limit` (WV_DESC_KERNEL_*). */
static const rmf_isa *pick_isa(int limit) {
#ifdef RMF_X86
  __builtin_cpu_init();
  if (limit >= WV_DESC_KERNEL_AVX512 && __builtin_cpu_supports("avx512f") &&
      __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx512bw") &&
      __builtin_cpu_supports("avx512dq"))
    return &isa_avx512;
  if (limit >= WV_DESC_KERNEL_AVX2 && __builtin_cpu_supports("avx2") &&
      __builtin_cpu_supports("fma"))
    return &isa_avx2;
#endif
  (void)limit;
  return &isa_base;
}

/* A chunk: rows [y0, y1) of one level. */
typedef struct {
  int level, y0, y1, last; /* last: the level's last chunk (no halo) */
} rmf_chunk_t;

typedef struct {
  float *w[RMF_LEVELS];  /* (c, 3, k, k) per level */
  float *wt[RMF_LEVELS]; /* transposed (3 k k, c) */
  const rmf_isa *isa;
  int w_img, h_img, nthreads;
  float *lev[RMF_LEVELS], *dlev[RMF_LEVELS]; /* unpadded; lev[0], dlev[0] are the caller's */
  float *pad[RMF_LEVELS], *dpad[RMF_LEVELS]; /* padded copies (rmf_level) */
  int lw[RMF_LEVELS], lh[RMF_LEVELS], xs[RMF_LEVELS], npv[RMF_LEVELS];
  rmf_chunk_t *chunks;
  int nchunks, first[RMF_LEVELS + 1]; /* chunks of level s: first[s] .. first[s + 1] */
  float *gch;                         /* per chunk: 64 x 64 Gram sums (upper triangle) */
  float *halo;                        /* per chunk: 3 planes x 2 rows x halo_stride */
  size_t halo_stride;
  float *scratch;
  size_t per_thread, f_floats, df_floats, gv_floats;
} rmf_net;

static void free_buffers(rmf_net *m) {
  for (int s = 0; s < RMF_LEVELS; s++) {
    if (s) free(m->lev[s]), free(m->dlev[s]);
    free(m->pad[s]), free(m->dpad[s]);
    m->lev[s] = m->dlev[s] = m->pad[s] = m->dpad[s] = NULL;
  }
  free(m->chunks), free(m->gch), free(m->halo), free(m->scratch);
  m->chunks = NULL, m->gch = m->halo = m->scratch = NULL;
  m->w_img = m->h_img = 0;
}

static void rmf_destroy(void *impl) {
  rmf_net *m = impl;
  if (!m) return;
  free_buffers(m);
  for (int s = 0; s < RMF_LEVELS; s++) free(m->w[s]), free(m->wt[s]);
  free(m);
}

static float *falloc(size_t n) { /* vector-aligned */
  return aligned_alloc(64, ((n * sizeof(float) + 63) / 64) * 64);
}

static wv_status ensure_buffers(rmf_net *m, int w, int h, wv_error *err) {
  int nt = omp_get_max_threads();
  if (nt < 1) nt = 1;
  if (m->w_img == w && m->h_img == h && m->nthreads == nt) return WV_OK;
  free_buffers(m);
  m->nthreads = nt;
  int kv = m->isa->kv, nch = 0, rows[RMF_LEVELS];
  for (int s = 0; s < RMF_LEVELS; s++) {
    m->lw[s] = s ? m->lw[s - 1] / 2 : w;
    m->lh[s] = s ? m->lh[s - 1] / 2 : h;
    int oh = m->lh[s] - RMF_K + 1, ow = m->lw[s] - RMF_K + 1;
    m->npv[s] = (ow + kv - 1) / kv;
    m->xs[s] = (m->npv[s] + 1) * kv; /* the taps of the last vector and its spill */
    /* At least 16 chunks for balance, 2 to 8 rows each (a halo is 2 rows). The split
     * does not depend on the thread count, nor then do the results. */
    int r = (oh + 15) / 16;
    rows[s] = r < 2 ? 2 : r > 8 ? 8 : r;
    nch += (oh + rows[s] - 1) / rows[s];
    size_t n = (size_t)3 * m->xs[s] * m->lh[s];
    if (!(m->pad[s] = falloc(n)) || !(m->dpad[s] = falloc(n))) goto oom;
    memset(m->pad[s], 0, sizeof(float) * n);
    if (s) {
      n = (size_t)3 * m->lw[s] * m->lh[s];
      if (!(m->lev[s] = malloc(sizeof(float) * n)) || !(m->dlev[s] = malloc(sizeof(float) * n)))
        goto oom;
    }
  }
  m->halo_stride = (size_t)6 * m->xs[0];
  if (!(m->chunks = malloc(sizeof *m->chunks * nch)) ||
      !(m->gch = falloc((size_t)nch * RMF_C * RMF_C)) || !(m->halo = falloc(m->halo_stride * nch)))
    goto oom;
  m->nchunks = 0;
  for (int s = 0; s < RMF_LEVELS; s++) {
    int oh = m->lh[s] - RMF_K + 1;
    m->first[s] = m->nchunks;
    for (int y = 0; y < oh; y += rows[s]) {
      rmf_chunk_t *c = &m->chunks[m->nchunks++];
      c->level = s, c->y0 = y, c->y1 = y + rows[s] < oh ? y + rows[s] : oh;
      c->last = c->y1 == oh;
    }
  }
  m->first[RMF_LEVELS] = m->nchunks;
  /* Per thread: F for a row, dF for a sub-block, the Gram lane sums, the carries. */
  m->f_floats = (size_t)RMF_C * m->npv[0] * kv;
  m->df_floats = (size_t)RMF_C * m->isa->sub * kv;
  m->gv_floats = (size_t)RMF_C * RMF_C * kv;
  m->per_thread = m->f_floats + m->df_floats + m->gv_floats + (size_t)18 * kv;
  if (!(m->scratch = falloc(m->per_thread * nt))) goto oom;
  m->w_img = w, m->h_img = h;
  return WV_OK;
oom:
  free_buffers(m);
  return wv_fail(err, WV_ERR_NOMEM, "out of memory for the default descriptor on a %d x %d image",
                 w, h);
}

static wv_status rmf_run(wv_descriptor *d, const float *x, int w, int h, const float *dgram,
                         float *gram, float *dx, wv_error *err) {
  rmf_net *m = d->impl;
  wv_status rc = ensure_buffers(m, w, h, err);
  if (rc) return rc;
  m->lev[0] = (float *)x; /* read only */
  m->dlev[0] = dx;
  for (int s = 1; s < RMF_LEVELS; s++)
    wv_nn_avgpool2_forward(m->lev[s], m->lev[s - 1], 3, m->lh[s - 1], m->lw[s - 1]);
  float S[RMF_LEVELS][RMF_C * RMF_C];
  rmf_level L[RMF_LEVELS];
  for (int s = 0; s < RMF_LEVELS; s++) {
    int oh = m->lh[s] - RMF_K + 1, ow = m->lw[s] - RMF_K + 1;
    L[s] = (rmf_level){m->pad[s], m->dpad[s], m->xs[s], ow, m->npv[s], m->npv[s] * m->isa->kv,
                       (size_t)m->xs[s] * m->lh[s], m->w[s], m->wt[s], NULL};
    if (dgram) {
      const float *dg = dgram + d->layer_off[s];
      float inv = 1.0f / (float)(oh * ow);
      for (int i = 0; i < RMF_C; i++)
        for (int j = 0; j < RMF_C; j++)
          S[s][i * RMF_C + j] = (dg[i * RMF_C + j] + dg[j * RMF_C + i]) * inv;
      L[s].S = S[s];
    }
  }
  int nt = m->nthreads, nch = m->nchunks;
#pragma omp parallel num_threads(nt)
  {
    /* The padded copies of the pyramid. */
    for (int s = 0; s < RMF_LEVELS; s++) {
      int lw = m->lw[s], lh = m->lh[s];
#pragma omp for schedule(static) nowait
      for (int r = 0; r < 3 * lh; r++)
        memcpy(m->pad[s] + (size_t)r * m->xs[s], m->lev[s] + (size_t)r * lw, sizeof(float) * lw);
    }
#pragma omp barrier
    rmf_scratch sc;
    sc.f = m->scratch + (size_t)omp_get_thread_num() * m->per_thread;
    sc.df = sc.f + m->f_floats, sc.gv = sc.df + m->df_floats, sc.carry = sc.gv + m->gv_floats;
    /* Larger levels first: their chunks cost most. */
#pragma omp for schedule(dynamic, 1)
    for (int k = 0; k < nch; k++) {
      const rmf_chunk_t *c = &m->chunks[k];
      const rmf_level *lv = &L[c->level];
      float *halo = NULL;
      if (dgram) {
        /* Zero the rows this chunk owns: its own, or up to the plane's end. */
        int ye = c->last ? m->lh[c->level] : c->y1;
        for (int ch = 0; ch < 3; ch++)
          memset(lv->dx + ch * lv->plane + (size_t)c->y0 * lv->xs, 0,
                 sizeof(float) * lv->xs * (ye - c->y0));
        if (!c->last) {
          halo = m->halo + m->halo_stride * k;
          memset(halo, 0, sizeof(float) * 6 * lv->xs);
        }
      }
      m->isa->chunk(lv, &sc, c->y0, c->y1, gram ? m->gch + (size_t)k * RMF_C * RMF_C : NULL, halo);
    }
    if (dgram) {
      /* Halos into the rows below their chunk (those chunks are done: the loop's barrier). */
#pragma omp for schedule(static)
      for (int k = 0; k < nch; k++) {
        const rmf_chunk_t *c = &m->chunks[k];
        if (c->last) continue;
        const rmf_level *lv = &L[c->level];
        const float *hp = m->halo + m->halo_stride * k;
        for (int ch = 0; ch < 3; ch++)
          for (int r = 0; r < 2; r++) {
            float *dst = lv->dx + ch * lv->plane + (size_t)(c->y1 + r) * lv->xs;
            const float *src = hp + (size_t)(ch * 2 + r) * lv->xs;
            for (int i = 0; i < lv->xs; i++) dst[i] += src[i];
          }
      }
      /* The padded gradients into the unpadded ones. */
      for (int s = 0; s < RMF_LEVELS; s++) {
        int lw = m->lw[s], lh = m->lh[s];
#pragma omp for schedule(static) nowait
        for (int r = 0; r < 3 * lh; r++)
          memcpy(m->dlev[s] + (size_t)r * lw, m->dpad[s] + (size_t)r * m->xs[s],
                 sizeof(float) * lw);
      }
    }
    if (gram) {
      /* Sum the chunks' Gram sums in chunk order, mirror, normalise. */
#pragma omp for schedule(static)
      for (int row = 0; row < RMF_LEVELS * RMF_C; row++) {
        int s = row / RMF_C, i = row % RMF_C;
        float *g = gram + d->layer_off[s];
        float inv = 1.0f / (float)((m->lh[s] - RMF_K + 1) * (m->lw[s] - RMF_K + 1));
        for (int j = i; j < RMF_C; j++) {
          float v = 0.0f;
          for (int k = m->first[s]; k < m->first[s + 1]; k++)
            v += m->gch[(size_t)k * RMF_C * RMF_C + i * RMF_C + j];
          g[i * RMF_C + j] = v * inv;
        }
      }
#pragma omp for schedule(static)
      for (int row = 0; row < RMF_LEVELS * RMF_C; row++) {
        int s = row / RMF_C, i = row % RMF_C;
        float *g = gram + d->layer_off[s];
        for (int j = 0; j < i; j++) g[i * RMF_C + j] = g[j * RMF_C + i];
      }
    }
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
    int kk = RMF_TAPS, c = RMF_C;
    m->w[s] = malloc(sizeof(float) * c * kk);
    m->wt[s] = malloc(sizeof(float) * c * kk);
    if (!m->w[s] || !m->wt[s]) {
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
    int k2 = RMF_K * RMF_K;
    for (int o = 0; o < c; o++)
      for (int ci = 0; ci < 3; ci++) {
        float *f = m->w[s] + (size_t)o * kk + ci * k2, mu = 0.0f;
        for (int i = 0; i < k2; i++) mu += f[i];
        mu /= (float)k2;
        for (int i = 0; i < k2; i++) f[i] -= (1.0f - RMF_DC) * mu;
      }
    for (int o = 0; o < c; o++)
      for (int r = 0; r < kk; r++) m->wt[s][r * c + o] = m->w[s][o * kk + r];
  }
  m->isa = pick_isa(WV_DESC_KERNEL_AVX512);
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
  d->min_side = RMF_K << (RMF_LEVELS - 1);
  *out = d;
  return WV_OK;
}

int wv_descriptor_default_filters(const wv_descriptor *d, int level, int *k, int *c,
                                  const float **w) {
  if (d->run != rmf_run || level < 0 || level >= RMF_LEVELS) return -1;
  const rmf_net *m = d->impl;
  *k = RMF_K, *c = rmf_c[level], *w = m->w[level];
  return RMF_LEVELS;
}

int wv_descriptor_default_kernel(wv_descriptor *d, int limit) {
  if (d->run != rmf_run) return -1;
  rmf_net *m = d->impl;
  if (limit >= 0) {
    const rmf_isa *isa = pick_isa(limit);
    if (isa != m->isa) free_buffers(m); /* the padding follows the vector width */
    m->isa = isa;
  }
  return m->isa->id;
}
