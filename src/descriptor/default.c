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
 * the OpenMP threads; a chunk pads its input rows and runs the fused kernel of
 * default_kernel.inc (conv, ReLU, Gram sums and, for the gradient,
 * dF = (dG + dG^T) F / HW, the ReLU mask, W^T dF and col2im) with its data in the
 * thread's cache, so the feature maps are never stored whole. Forward and backward
 * take one pass, since dF needs dG and F but not G; without a Gram output the
 * backward skips the Gram sums. Each chunk keeps its own Gram sums and writes the
 * input gradient of the two rows it shares with the next chunk to a halo; both are
 * added in chunk order at the end, so the result does not depend on the thread count
 * or on which thread ran what. A call is one parallel region with one barrier (after
 * the chunks): on a busy machine a thread that loses its core holds the others up
 * once, not at every level. The kernel is compiled for AVX-512, AVX2 and the
 * baseline and chosen when the descriptor is created. */
#include <math.h>
#include <omp.h>
#include <sched.h>
#include <stdatomic.h>
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
  const float *x; /* 3 padded planes of input rows from xy0 on: rows of xs floats, zeros
                   * past the image */
  float *dx;      /* the gradient, all rows, rows of xs floats */
  int xy0, xs, ow, npv, fs; /* x's first row, row stride, outputs per row, vectors per
                             * row, F's row stride */
  size_t plane, dplane;     /* plane strides of x and dx (floats) */
  const float *w, *wt; /* filters (64 x 27) and their transpose (27 x 64) */
  const float *S;      /* (dG + dG^T) / (H W), or NULL for no gradient */
} rmf_level;

/* One thread's working set. */
typedef struct {
  float *f, *df, *gv, *carry;
  float *strip; /* the chunk's input rows, padded (rmf_level.x) */
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
  float *lev[RMF_LEVELS], *dlev[RMF_LEVELS]; /* lev[0], dlev[0] are the caller's */
  float *dpad[RMF_LEVELS];                   /* the gradient in the padded layout */
  int lw[RMF_LEVELS], lh[RMF_LEVELS], xs[RMF_LEVELS], npv[RMF_LEVELS], rows[RMF_LEVELS];
  rmf_chunk_t *chunks;
  int nchunks, first[RMF_LEVELS + 1]; /* chunks of level s: first[s] .. first[s + 1] */
  float *gch;                         /* per chunk: 64 x 64 Gram sums (upper triangle) */
  float *halo;                        /* per chunk: 3 planes x 2 rows x halo_stride */
  size_t halo_stride;
  float *scratch;
  size_t per_thread, f_floats, df_floats, gv_floats, strip_floats;
} rmf_net;

/* Rows of level 0 per band of the gradient's final pass: a band of every level
 * pools into the same band of the level below. */
#define RMF_BAND (1 << (RMF_LEVELS - 1))

static void free_buffers(rmf_net *m) {
  for (int s = 0; s < RMF_LEVELS; s++) {
    if (s) free(m->lev[s]), free(m->dlev[s]);
    free(m->dpad[s]);
    m->lev[s] = m->dlev[s] = m->dpad[s] = NULL;
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
  int kv = m->isa->kv, nch = 0, maxrows = 0;
  for (int s = 0; s < RMF_LEVELS; s++) {
    m->lw[s] = s ? m->lw[s - 1] / 2 : w;
    m->lh[s] = s ? m->lh[s - 1] / 2 : h;
    int oh = m->lh[s] - RMF_K + 1, ow = m->lw[s] - RMF_K + 1;
    m->npv[s] = (ow + kv - 1) / kv;
    m->xs[s] = (m->npv[s] + 1) * kv; /* the taps of the last vector and its spill */
    /* At least 16 chunks for balance, 2 to 8 rows each (a halo is 2 rows). The split
     * does not depend on the thread count, nor then do the results. */
    int r = (oh + 15) / 16;
    m->rows[s] = r < 2 ? 2 : r > 8 ? 8 : r;
    if (m->rows[s] > maxrows) maxrows = m->rows[s];
    nch += (oh + m->rows[s] - 1) / m->rows[s];
    if (!(m->dpad[s] = falloc((size_t)3 * m->xs[s] * m->lh[s]))) goto oom;
    if (s) {
      size_t n = (size_t)3 * m->lw[s] * m->lh[s];
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
    for (int y = 0; y < oh; y += m->rows[s]) {
      rmf_chunk_t *c = &m->chunks[m->nchunks++];
      c->level = s, c->y0 = y, c->y1 = y + m->rows[s] < oh ? y + m->rows[s] : oh;
      c->last = c->y1 == oh;
    }
  }
  m->first[RMF_LEVELS] = m->nchunks;
  /* Per thread: F for a row, dF for a sub-block, the Gram lane sums, the carries, the
   * chunk's input rows. */
  m->f_floats = (size_t)RMF_C * m->npv[0] * kv;
  m->df_floats = (size_t)RMF_C * m->isa->sub * kv;
  m->gv_floats = (size_t)RMF_C * RMF_C * kv;
  m->strip_floats = (size_t)3 * (maxrows + RMF_K - 1) * m->xs[0];
  m->per_thread = m->f_floats + m->df_floats + m->gv_floats + (size_t)18 * kv + m->strip_floats;
  if (!(m->scratch = falloc(m->per_thread * nt))) goto oom;
  m->w_img = w, m->h_img = h;
  return WV_OK;
oom:
  free_buffers(m);
  return wv_fail(err, WV_ERR_NOMEM, "out of memory for the default descriptor on a %d x %d image",
                 w, h);
}

/* The input gradient of band b of every level, coarsest first: a level's rows from the
 * padded layout and the halos, plus the adjoint of the 2x2 pooling of the finished
 * level above. A band is RMF_BAND rows of level 0 and the rows they pool to. */
static void gradient_band(const rmf_net *m, int b, int nb) {
  int a_up = 0, e_up = 0;
  for (int s = RMF_LEVELS - 1; s >= 0; s--) {
    int lw = m->lw[s], lh = m->lh[s], xs = m->xs[s];
    int a = (b * RMF_BAND) >> s, e = b == nb - 1 ? lh : ((b + 1) * RMF_BAND) >> s;
    for (int c = 0; c < 3; c++) {
      for (int r = a; r < e; r++) {
        float *dst = m->dlev[s] + ((size_t)c * lh + r) * lw;
        memcpy(dst, m->dpad[s] + ((size_t)c * lh + r) * xs, sizeof(float) * lw);
        /* Rows y1 and y1 + 1 of a chunk that is not its level's last are in its halo. */
        int k = m->first[s] + r / m->rows[s] - 1, rr = r % m->rows[s];
        if (k >= m->first[s] && k < m->first[s + 1] && rr < RMF_K - 1 && !m->chunks[k].last) {
          const float *hp = m->halo + m->halo_stride * k + (size_t)(c * 2 + rr) * xs;
          for (int i = 0; i < lw; i++) dst[i] += hp[i];
        }
      }
      if (s < RMF_LEVELS - 1 && e_up > a_up) /* a plane's band of rows is itself a plane */
        wv_nn_avgpool2_backward(m->dlev[s] + ((size_t)c * lh + 2 * a_up) * lw,
                                m->dlev[s + 1] + ((size_t)c * m->lh[s + 1] + a_up) * m->lw[s + 1],
                                1, 2 * (e_up - a_up), lw);
    }
    a_up = a, e_up = e;
  }
}

static wv_status rmf_run(wv_descriptor *d, const float *x, int w, int h, const float *dgram,
                         float *gram, float *dx, wv_error *err) {
  rmf_net *m = d->impl;
  wv_status rc = ensure_buffers(m, w, h, err);
  if (rc) return rc;
  m->lev[0] = (float *)x; /* read only */
  m->dlev[0] = dx;
  float S[RMF_LEVELS][RMF_C * RMF_C];
  rmf_level L[RMF_LEVELS];
  for (int s = 0; s < RMF_LEVELS; s++) {
    int oh = m->lh[s] - RMF_K + 1, ow = m->lw[s] - RMF_K + 1;
    L[s] = (rmf_level){.dx = m->dpad[s], .xs = m->xs[s], .ow = ow, .npv = m->npv[s],
                       .fs = m->npv[s] * m->isa->kv, .dplane = (size_t)m->xs[s] * m->lh[s],
                       .w = m->w[s], .wt = m->wt[s]};
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
  atomic_int pyramid_done = 0;
  /* One parallel region with one barrier (after the chunks), so that on a busy machine
   * a thread that lost its core holds the others up once. */
#pragma omp parallel num_threads(nt)
  {
    int tid = omp_get_thread_num();
    if (tid == 0) {
      /* The pyramid, while the other threads start on level 0 (calls from inside the
       * region run on this thread alone). */
      for (int s = 1; s < RMF_LEVELS; s++)
        wv_nn_avgpool2_forward(m->lev[s], m->lev[s - 1], 3, m->lh[s - 1], m->lw[s - 1]);
      atomic_store_explicit(&pyramid_done, 1, memory_order_release);
    }
    rmf_scratch sc;
    sc.f = m->scratch + (size_t)tid * m->per_thread;
    sc.df = sc.f + m->f_floats, sc.gv = sc.df + m->df_floats, sc.carry = sc.gv + m->gv_floats;
    sc.strip = sc.carry + (size_t)18 * m->isa->kv;
    /* Largest level first: its chunks cost most. */
#pragma omp for schedule(dynamic, 1)
    for (int k = 0; k < nch; k++) {
      const rmf_chunk_t *c = &m->chunks[k];
      int s = c->level;
      if (s)
        while (!atomic_load_explicit(&pyramid_done, memory_order_acquire)) sched_yield();
      /* The chunk's input rows, padded with zeros. */
      rmf_level lv = L[s];
      int nr = c->y1 - c->y0 + RMF_K - 1, lw = m->lw[s];
      lv.x = sc.strip, lv.xy0 = c->y0, lv.plane = (size_t)nr * lv.xs;
      for (int ch = 0; ch < 3; ch++)
        for (int r = 0; r < nr; r++) {
          float *dst = sc.strip + ch * lv.plane + (size_t)r * lv.xs;
          memcpy(dst, m->lev[s] + ((size_t)ch * m->lh[s] + c->y0 + r) * lw, sizeof(float) * lw);
          memset(dst + lw, 0, sizeof(float) * (lv.xs - lw));
        }
      float *halo = NULL;
      if (dgram) {
        /* Zero the rows this chunk owns: its own, or up to the plane's end. */
        int ye = c->last ? m->lh[s] : c->y1;
        for (int ch = 0; ch < 3; ch++)
          memset(lv.dx + ch * lv.dplane + (size_t)c->y0 * lv.xs, 0,
                 sizeof(float) * lv.xs * (ye - c->y0));
        if (!c->last) {
          halo = m->halo + m->halo_stride * k;
          memset(halo, 0, sizeof(float) * 6 * lv.xs);
        }
      }
      m->isa->chunk(&lv, &sc, c->y0, c->y1, gram ? m->gch + (size_t)k * RMF_C * RMF_C : NULL,
                    halo);
    }
    if (dgram) {
      /* Bands of RMF_BAND rows of level 0 and the rows they pool to, coarsest level
       * first, so that each level adds the finished gradient of the one above. */
      int nb = (h + RMF_BAND - 1) / RMF_BAND;
#pragma omp for schedule(dynamic, 1) nowait
      for (int b = 0; b < nb; b++) gradient_band(m, b, nb);
    }
    if (gram) {
      /* Sum the chunks' Gram sums in chunk order, normalise, mirror. */
#pragma omp for schedule(static) nowait
      for (int row = 0; row < RMF_LEVELS * RMF_C; row++) {
        int s = row / RMF_C, i = row % RMF_C;
        float *g = gram + d->layer_off[s];
        float inv = 1.0f / (float)((m->lh[s] - RMF_K + 1) * (m->lw[s] - RMF_K + 1));
        for (int j = i; j < RMF_C; j++) {
          float v = 0.0f;
          for (int k = m->first[s]; k < m->first[s + 1]; k++)
            v += m->gch[(size_t)k * RMF_C * RMF_C + i * RMF_C + j];
          g[i * RMF_C + j] = g[j * RMF_C + i] = v * inv;
        }
      }
    }
  }
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
