/* Equirectangular environment maps: lookup, importance sampling by luminance
 * times sin(theta) (piecewise constant over pixels, uniform in solid angle within
 * each, so the pdf and the lookup agree exactly), and the built-in environments
 * generated in code. A direction's pixel is found by comparisons with tables of
 * the pixels' edges, and a drawn direction is built from a table of the columns'
 * centres: no trigonometry per sample. */
#define _DEFAULT_SOURCE /* madvise's MADV_HUGEPAGE */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>

#include "util/colour.h"
#include "woven/emitters.h"

#define PI_F 3.14159265358979f
#define PI 3.14159265358979323846

/* The batched sampler and the lookup (the path tracer's inner loop) in versions for
 * AVX-512, AVX2 and plain x86-64, chosen when the program loads, as the shading
 * kernel's (kernel/lanes.h, WV_SIMD_CLONES; this floor does not include it): the
 * same operations, so the same results. */
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && __GNUC__ >= 11
#define ENV_CLONES __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define ENV_CLONES
#endif

void wv_envmap_free(wv_envmap *e) {
  if (!e) return;
  free(e->rgb), free(e->cdf_row), free(e->cdf_col);
  free(e->texel), free(e->guide_row), free(e->guide_col);
  free(e->edge_y), free(e->edge_x), free(e->centre_x), free(e->guide_y), free(e->guide_x);
  memset(e, 0, sizeof *e);
}

size_t wv_envmap_bytes(int w, int h) {
  if (w < 0 || h < 0) return (size_t)-1;
  /* colours, the CDFs, the packed texels (rounded up to the 2 MB pages they may take)
   * and the guide tables */
  size_t texel = (size_t)w * h * 4 * sizeof(float), huge = (size_t)1 << 21;
  if (texel >= huge / 2) texel = (texel + huge - 1) / huge * huge;
  return ((size_t)w * h * 3 + (size_t)(h + 1) + (size_t)h * (w + 1)) * sizeof(float) + (size_t)(h + 1) * sizeof(double) +
         texel + (size_t)(h + 1) * (WV_ENV_GUIDE + 1) * sizeof(int) +
         ((size_t)(h + 1) + (size_t)(w + 1) + 2 * (size_t)w) * sizeof(float) + ((size_t)(2 * h + 1) + (size_t)(2 * w + 1)) * sizeof(int);
}

static float pixel_prob(const wv_envmap *e, int x, int y) {
  const float *row = e->cdf_col + (size_t)y * (e->w + 1);
  return (e->cdf_row[y + 1] - e->cdf_row[y]) * (row[x + 1] - row[x]);
}

/* guide[g] = the last interval i < n with cdf[i] <= g / WV_ENV_GUIDE. */
static void make_guide(const float *cdf, int n, int *guide) {
  int i = 0;
  for (int g = 0; g <= WV_ENV_GUIDE; g++) {
    float t = (float)g / WV_ENV_GUIDE;
    while (i + 1 < n && cdf[i + 1] <= t) i++;
    guide[g] = i;
  }
}

/* Memory for a table read at random: on 2 MB pages where the system offers them
 * (one TLB entry for what would take 512), else ordinary. */
static void *table_alloc(size_t bytes) {
  const size_t huge = (size_t)1 << 21;
  if (bytes < huge / 2) return malloc(bytes);
  void *p = aligned_alloc(huge, (bytes + huge - 1) / huge * huge);
#ifdef MADV_HUGEPAGE
  if (p) madvise(p, (bytes + huge - 1) / huge * huge, MADV_HUGEPAGE);
#endif
  return p;
}

/* The pseudo-angle of the horizontal direction (a, b), not both 0: from 0 to 4 as
 * atan2(b, a) goes round from 0 to 2 pi, and monotone in it (the quadrant, plus
 * where the direction meets the square |a| + |b| = 1); one division. In float for
 * the lookups, in double for the table of the columns' edges. */
static inline float pseudo_angle(float a, float b) {
  float s = fabsf(a) + fabsf(b);
  int same = (a >= 0.0f) == (b >= 0.0f), q = 2 * (b < 0.0f) + !same; /* the quadrant */
  float t = (same ? fabsf(b) : fabsf(a)) / (s > 0.0f ? s : 1.0f);   /* b / s, -a / s, -b / s or a / s */
  return (float)q + t;
}
static double pseudo_angle_d(double a, double b) {
  double s = fabs(a) + fabs(b);
  if (!(s > 0.0)) return 0.0;
  if (b >= 0.0) return a >= 0.0 ? b / s : 1.0 - a / s;
  return a < 0.0 ? 2.0 - b / s : 3.0 + a / s;
}

/* The row of cos theta = cy and the column of pseudo-angle p, by walking the edge
 * tables from a nearby row or column: row y holds edge_y[y] >= cy > edge_y[y + 1]
 * (theta in [pi y / h, pi (y + 1) / h)), column x edge_x[x] <= p < edge_x[x + 1]. */
static inline int walk_row(const wv_envmap *e, float cy, int y) {
  while (y > 0 && cy > e->edge_y[y]) y--;
  while (y + 1 < e->h && cy <= e->edge_y[y + 1]) y++;
  return y;
}
static inline int walk_col(const wv_envmap *e, float p, int x) {
  while (x > 0 && p < e->edge_x[x]) x--;
  while (x + 1 < e->w && p >= e->edge_x[x + 1]) x++;
  return x;
}

/* World direction -> cos theta and the pseudo-angle of the longitude in the map
 * (turned by -rotation about +y; longitude phi from -z toward +x, measured from
 * phi = -pi, the map's left edge). */
static inline void to_map(const wv_envmap *e, const float d[3], float *cy, float *p) {
  float mx = e->rot_c * d[0] - e->rot_s * d[2], mz = e->rot_s * d[0] + e->rot_c * d[2];
  *cy = d[1] < -1.0f ? -1.0f : d[1] > 1.0f ? 1.0f : d[1];
  *p = pseudo_angle(mz, -mx); /* phi + pi is the angle of (mz, -mx) */
}

/* The tables the lookups and the sampler read (emitters.h): texel, the guides,
 * the edges and the columns' centres. */
static wv_status build_lookup(wv_envmap *e, double rot, const char *name, wv_error *err) {
  int w = e->w, h = e->h;
  e->texel = table_alloc((size_t)w * h * 4 * sizeof(float));
  e->guide_row = malloc((WV_ENV_GUIDE + 1) * sizeof(int));
  e->guide_col = malloc((size_t)h * (WV_ENV_GUIDE + 1) * sizeof(int));
  e->edge_y = malloc((size_t)(h + 1) * sizeof(float));
  e->edge_x = malloc((size_t)(w + 1) * sizeof(float));
  e->centre_x = malloc((size_t)w * 2 * sizeof(float));
  e->guide_y = malloc((size_t)(2 * h + 1) * sizeof(int));
  e->guide_x = malloc((size_t)(2 * w + 1) * sizeof(int));
  if (!e->texel || !e->guide_row || !e->guide_col || !e->edge_y || !e->edge_x || !e->centre_x || !e->guide_y ||
      !e->guide_x) {
    wv_envmap_free(e);
    return wv_fail(err, WV_ERR_NOMEM, "%s: out of memory for the environment's tables", name);
  }
  for (int y = 0; y <= h; y++) e->edge_y[y] = (float)cos(PI * y / h);
  e->edge_y[0] = 1.0f, e->edge_y[h] = -1.0f;
  for (int x = 0; x <= w; x++) e->edge_x[x] = (float)pseudo_angle_d(cos(2 * PI * x / w), sin(2 * PI * x / w));
  e->edge_x[0] = 0.0f, e->edge_x[w] = 4.0f;
  for (int x = 0; x < w; x++) { /* (mx, mz) = (-sin, cos) of phi + pi, turned to the world */
    double a = 2 * PI * (x + 0.5) / w, mx = -sin(a), mz = cos(a), rc = cos(rot), rs = sin(rot);
    e->centre_x[2 * x] = (float)(rc * mx + rs * mz), e->centre_x[2 * x + 1] = (float)(-rs * mx + rc * mz);
  }
  for (int g = 0, y = 0; g <= 2 * h; g++) { /* cell g: guide_t(cy) in [g / h, (g + 1) / h) */
    double t = (double)g / h, cy = t <= 1 ? 1 - t * t : (2 - t) * (2 - t) - 1;
    e->guide_y[g] = y = walk_row(e, (float)cy, y);
  }
  for (int g = 0, x = 0; g <= 2 * w; g++) e->guide_x[g] = x = walk_col(e, (float)(2.0 * g / w), x);
  for (int y = 0; y < h; y++) {
    /* the pixels' solid angle: the band between the rows' edges, over one column */
    double omega = (cos(PI * y / h) - cos(PI * (y + 1) / h)) * 2 * PI / w;
    for (int x = 0; x < w; x++) {
      float *t = e->texel + ((size_t)y * w + x) * 4;
      const float *c = e->rgb + ((size_t)y * w + x) * 3;
      t[0] = c[0], t[1] = c[1], t[2] = c[2];
      t[3] = (float)(pixel_prob(e, x, y) / omega); /* the density within the pixel */
    }
  }
  make_guide(e->cdf_row, h, e->guide_row);
  for (int y = 0; y < h; y++) make_guide(e->cdf_col + (size_t)y * (w + 1), w, e->guide_col + (size_t)y * (WV_ENV_GUIDE + 1));
  return WV_OK;
}

wv_status wv_envmap_init(wv_envmap *e, const wv_image *img, double strength, double rot_deg, const char *name,
                         wv_error *err) {
  memset(e, 0, sizeof *e);
  if (!img || img->c != 3 || img->w < 2 || img->h < 1)
    return wv_fail(err, WV_ERR_FORMAT, "%s: an environment map must be an RGB image of at least 2 x 1", name);
  if (!(strength >= 0 && isfinite(strength)) || !isfinite(rot_deg))
    return wv_fail(err, WV_ERR_INVALID, "%s: strength must be >= 0 and rotation finite", name);
  int w = img->w, h = img->h;
  e->w = w, e->h = h;
  e->rgb = malloc((size_t)w * h * 3 * sizeof(float));
  e->cdf_row = malloc((size_t)(h + 1) * sizeof(float));
  e->cdf_col = malloc((size_t)h * (w + 1) * sizeof(float));
  if (!e->rgb || !e->cdf_row || !e->cdf_col) {
    wv_envmap_free(e);
    return wv_fail(err, WV_ERR_NOMEM, "%s: out of memory for the environment's tables", name);
  }
  for (size_t i = 0; i < (size_t)w * h * 3; i++) {
    float v = img->data[i];
    if (!isfinite(v) || v < 0) {
      wv_envmap_free(e);
      return wv_fail(err, WV_ERR_FORMAT, "%s: pixel %zu has a negative, NaN or infinite value", name, i / 3);
    }
    e->rgb[i] = (float)(v * strength);
    /* after the scaling: a finite value times the strength can overflow */
    if (!(e->rgb[i] <= WV_ENV_MAX_RADIANCE)) {
      wv_envmap_free(e);
      return wv_fail(err, WV_ERR_FORMAT, "%s: pixel %zu's radiance %g times the strength %g is above %g", name, i / 3,
                     (double)v, strength, WV_ENV_MAX_RADIANCE);
    }
  }
  double total = 0;
  e->cdf_row[0] = 0;
  double *row = malloc(sizeof(double) * (size_t)(h + 1));
  if (!row) {
    wv_envmap_free(e);
    return wv_fail(err, WV_ERR_NOMEM, "%s: out of memory", name);
  }
  row[0] = 0;
  for (int y = 0; y < h; y++) {
    double s = sin(PI * (y + 0.5) / h), acc = 0;
    float *cdf = e->cdf_col + (size_t)y * (w + 1);
    cdf[0] = 0;
    for (int x = 0; x < w; x++) {
      const float *c = e->rgb + ((size_t)y * w + x) * 3;
      acc += wv_luminance_f(c[0], c[1], c[2]) * s;
      cdf[x + 1] = (float)acc;
    }
    for (int x = 1; x <= w; x++) cdf[x] = acc > 0 ? (float)(cdf[x] / acc) : (float)x / w;
    cdf[w] = 1.0f;
    total += acc;
    row[y + 1] = total;
  }
  for (int y = 0; y <= h; y++) e->cdf_row[y] = total > 0 ? (float)(row[y] / total) : (float)y / h;
  e->cdf_row[h] = 1.0f;
  free(row);
  e->total = total;
  double r = rot_deg * PI / 180.0;
  e->rot_c = (float)cos(r), e->rot_s = (float)sin(r);
  return build_lookup(e, r, name, err);
}

/* The guide's coordinate of cos theta = cy: sqrt(1 - cy) on the upper half, 2 -
 * sqrt(1 + cy) on the lower, from 0 to 2 and nearly proportional to theta (within a
 * factor sqrt 2), so that a cell of 1 / h holds at most one row's edge. */
static inline float guide_t(float cy) { return cy >= 0.0f ? sqrtf(1.0f - cy) : 2.0f - sqrtf(1.0f + cy); }

ENV_CLONES wv_env_at wv_envmap_at(const wv_envmap *e, const float d[3]) {
  float cy, p;
  to_map(e, d, &cy, &p);
  /* the guides' cells hold at most one edge each (a column spans pi / w of the
   * pseudo-angle or more, a row 1 / (sqrt 2 h) or more of guide_t): one step from
   * the cell's row and column, the walk only to undo rounding at a cell's edge */
  int gy = (int)(guide_t(cy) * (float)e->h), gx = (int)(p * (float)e->w * 0.5f);
  gy = gy < 0 ? 0 : gy > 2 * e->h ? 2 * e->h : gy;
  gx = gx < 0 ? 0 : gx > 2 * e->w ? 2 * e->w : gx;
  int y = e->guide_y[gy], x = e->guide_x[gx];
  y += y + 1 < e->h && cy <= e->edge_y[y + 1];
  x += x + 1 < e->w && p >= e->edge_x[x + 1];
  y = walk_row(e, cy, y), x = walk_col(e, p, x);
  wv_env_at a = {(size_t)y * e->w + x};
  __builtin_prefetch(e->texel + 4 * a.texel);
  return a;
}

float wv_envmap_read(const wv_envmap *e, wv_env_at a, float rgb[3]) {
  const float *c = e->texel + 4 * a.texel;
  /* one block (8 + 4 bytes): a caller reading rgb back as a vector then finds it
   * stored as it reads it (three separate stores stall such a load) */
  memcpy(rgb, c, 3 * sizeof *rgb);
  return e->total > 0 ? c[3] : 0.0f;
}

void wv_envmap_eval(const wv_envmap *e, const float d[3], float rgb[3]) { wv_envmap_read(e, wv_envmap_at(e, d), rgb); }

float wv_envmap_lookup(const wv_envmap *e, const float d[3], float rgb[3]) {
  return wv_envmap_read(e, wv_envmap_at(e, d), rgb);
}

float wv_envmap_pdf(const wv_envmap *e, const float d[3]) {
  float rgb[3];
  return wv_envmap_lookup(e, d, rgb);
}

static int guide_cell(float u) {
  int g = (int)(u * WV_ENV_GUIDE);
  return g < 0 ? 0 : g >= WV_ENV_GUIDE ? WV_ENV_GUIDE - 1 : g;
}

/* Search bounds for u in cdf (n intervals) from its guide: cdf[*lo] <= u < cdf[*hi]
 * (checked, in two steps: the batch reads the tables in between). */
static void guide_read(const int *guide, float u, int *lo, int *hi) {
  int g = guide_cell(u);
  *lo = guide[g], *hi = guide[g + 1] + 1;
}
static void guide_check(const float *cdf, int n, float u, int *lo, int *hi) {
  if (!(cdf[*lo] <= u)) *lo = 0;
  if (*hi > n || !(u < cdf[*hi])) *hi = n;
}

/* Index i with cdf[i] <= u < cdf[i + 1] (skipping empty intervals), between lo and hi
 * (cdf[lo] <= u < cdf[hi]): the last i in [lo, hi) with cdf[i] <= u, by halving the
 * range with a select instead of a branch (the comparisons are not predictable). */
static int bisect(const float *cdf, int lo, int hi, float u) {
  for (int n = hi - lo; n > 1;) { /* the answer lies in [lo, lo + n) */
    int half = n / 2;
    lo = cdf[lo + half] <= u ? lo + half : lo;
    n -= half;
  }
  return lo;
}

static int find(const float *cdf, const int *guide, int n, float u) {
  int lo, hi;
  guide_read(guide, u, &lo, &hi);
  guide_check(cdf, n, u, &lo, &hi);
  return bisect(cdf, lo, hi, u);
}

static const int *row_guide(const wv_envmap *e, int y) { return e->guide_col + (size_t)y * (WV_ENV_GUIDE + 1); }
static const float *row_cdf(const wv_envmap *e, int y) { return e->cdf_col + (size_t)y * (e->w + 1); }

/* sin and cos of x, |x| <= pi / 2, by their Taylor series (error below 1e-7): the
 * offset from a column's centre, at most pi / w. Up to x^7 and x^8 for |x| <= pi / 8
 * (w >= 8; the next terms below 2e-8 of the result), else to x^11 and x^12. */
static inline void sincos_small(float x, int short_series, float *s, float *c) {
  float x2 = x * x;
  if (short_series) {
    *s = x * (1.0f + x2 * (-1.0f / 6 + x2 * (1.0f / 120 + x2 * (-1.0f / 5040))));
    *c = 1.0f + x2 * (-0.5f + x2 * (1.0f / 24 + x2 * (-1.0f / 720 + x2 * (1.0f / 40320))));
    return;
  }
  *s = x * (1.0f + x2 * (-1.0f / 6 + x2 * (1.0f / 120 + x2 * (-1.0f / 5040 + x2 * (1.0f / 362880 + x2 * (-1.0f / 39916800))))));
  *c = 1.0f + x2 * (-0.5f + x2 * (1.0f / 24 + x2 * (-1.0f / 720 + x2 * (1.0f / 40320 + x2 * (-1.0f / 3628800 +
       x2 * (1.0f / 479001600))))));
}

/* The direction through pixel (x, y) of the draw: where inside it, the leftover
 * of each uniform number, rescaled: cos theta linear across the row and the
 * longitude across the column (uniform in solid angle), the longitude as a turn
 * of the column's centre. Returns the texel d looks up (rounding at a pixel's edge
 * can move d to its neighbour, and the estimator must use the values of d): the
 * row by its edges; the column is x itself when the drawn longitude is more than
 * WV_ENV_MARGIN radians inside its edges, ten times the error of the turn and the
 * lookup's rounding together (below 2e-6; test_env_pixels), else by its edges. */
#define WV_ENV_MARGIN 2e-5f
/* drawn_dir's arithmetic on the tables' values at the draw's row y and column x (r0,
 * r1: cdf_row at y and y + 1; c0, c1: the row's CDF at x and x + 1; e0, e1: edge_y at
 * y and y + 1; k0, k1: the column's centre), as env_dirs_8 does it on eight lanes: the
 * direction into d, and the column's fraction fx and sin theta st that texel_of reads. */
static inline __attribute__((always_inline)) void dir_in_pixel(float u1, float u2, float r0, float r1, float c0,
                                                               float c1, float e0, float e1, float k0, float k1,
                                                               float dphi, int short_series, float d[3], float *fxo,
                                                               float *sto) {
  float fy = (u1 - r0) / (r1 - r0);
  float fx = (u2 - c0) / (c1 - c0);
  fy = fy < 0 ? 0 : fy > 0.999999f ? 0.999999f : fy;
  fx = fx < 0 ? 0 : fx > 0.999999f ? 0.999999f : fx;
  float cy = e0 + fy * (e1 - e0), st = sqrtf((1.0f - cy) * (1.0f + cy)), sd, cd;
  sincos_small((fx - 0.5f) * dphi, short_series, &sd, &cd);
  d[0] = st * (cd * k0 - sd * k1), d[1] = cy, d[2] = st * (cd * k1 + sd * k0);
  *fxo = fx, *sto = st;
}
/* The texel of drawn direction d of row y and column x (fx, st from dir_in_pixel). */
static inline size_t texel_of(const wv_envmap *e, const float d[3], float fx, float st, int x, int y) {
  y = walk_row(e, d[1], y);
  float m = WV_ENV_MARGIN * (float)e->w * (1.0f / (2 * PI_F)); /* the margin as a fraction of the column */
  if (!(fx > m && fx < 1.0f - m && st > 0.0f)) { /* (at a pole, d has no longitude) */
    float my, p;
    to_map(e, d, &my, &p);
    x = walk_col(e, p, x);
  }
  return (size_t)y * e->w + x;
}
static inline __attribute__((always_inline)) size_t drawn_dir(const wv_envmap *e, float u1, float u2, int x, int y,
                                                              float d[3]) {
  const float *row = row_cdf(e, y);
  float fx, st;
  dir_in_pixel(u1, u2, e->cdf_row[y], e->cdf_row[y + 1], row[x], row[x + 1], e->edge_y[y], e->edge_y[y + 1],
               e->centre_x[2 * x], e->centre_x[2 * x + 1], 2 * PI_F / (float)e->w, e->w >= 8, d, &fx, &st);
  return texel_of(e, d, fx, st, x, y);
}

static float no_sample(float d[3], float rgb[3]) {
  d[0] = 0, d[1] = 1, d[2] = 0, rgb[0] = rgb[1] = rgb[2] = 0;
  return 0.0f;
}

float wv_envmap_sample(const wv_envmap *e, float u1, float u2, float d[3], float rgb[3]) {
  if (!(e->total > 0)) return no_sample(d, rgb);
  int y = find(e->cdf_row, e->guide_row, e->h, u1);
  int x = find(row_cdf(e, y), row_guide(e, y), e->w, u2);
  wv_env_at a = {drawn_dir(e, u1, u2, x, y, d)};
  return wv_envmap_read(e, a, rgb);
}

/* dir_in_pixel on nb blocks of eight lanes (in[k][j]: lane j's u1, u2, r0, r1, c0,
 * c1, k0, k1, e0, e1): the lanes' directions into d[.][j], their fx and st. Eight
 * lanes to a vector register: the same operations in the same order, so the same
 * results. */
#define ENV_BLOCK 32 /* draws to a stage of wv_envmap_sample_n */
/* (the vectors never cross a call: the helpers are inlined, so no ABI question) */
#pragma GCC diagnostic ignored "-Wpsabi"
typedef float env_v8 __attribute__((vector_size(32)));
typedef int env_i8 __attribute__((vector_size(32)));
static inline __attribute__((always_inline)) env_v8 env_sel(env_i8 m, env_v8 a, env_v8 b) { return (env_v8)((m & (env_i8)a) | (~m & (env_i8)b)); }
/* sincos_small on eight lanes */
static inline __attribute__((always_inline)) void env_sincos_8(env_v8 x, int short_series, env_v8 *s, env_v8 *c) {
  env_v8 x2 = x * x;
  if (short_series) {
    *s = x * (1.0f + x2 * (-1.0f / 6 + x2 * (1.0f / 120 + x2 * (-1.0f / 5040))));
    *c = 1.0f + x2 * (-0.5f + x2 * (1.0f / 24 + x2 * (-1.0f / 720 + x2 * (1.0f / 40320))));
    return;
  }
  *s = x * (1.0f + x2 * (-1.0f / 6 + x2 * (1.0f / 120 + x2 * (-1.0f / 5040 + x2 * (1.0f / 362880 + x2 * (-1.0f / 39916800))))));
  *c = 1.0f + x2 * (-0.5f + x2 * (1.0f / 24 + x2 * (-1.0f / 720 + x2 * (1.0f / 40320 + x2 * (-1.0f / 3628800 +
       x2 * (1.0f / 479001600))))));
}
static inline __attribute__((always_inline)) void env_dirs_8(float (*in)[ENV_BLOCK], int nb, float dphi, int short_series,
                                                             float (*d)[ENV_BLOCK], float *fxo, float *sto) {
  const env_v8 zero = {0}, top = zero + 0.999999f;
  for (int b = 0; b < nb; b++) {
    env_v8 a[10], fy, fx, cy, st, q, sd, cd;
    for (int k = 0; k < 10; k++) memcpy(&a[k], in[k] + 8 * b, sizeof a[k]);
    fy = (a[0] - a[2]) / (a[3] - a[2]);
    fx = (a[1] - a[4]) / (a[5] - a[4]);
    fy = env_sel(fy < zero, zero, env_sel(fy > top, top, fy));
    fx = env_sel(fx < zero, zero, env_sel(fx > top, top, fx));
    cy = a[8] + fy * (a[9] - a[8]);
    q = (1.0f - cy) * (1.0f + cy);
    for (int l = 0; l < 8; l++) st[l] = sqrtf(q[l]);
    env_sincos_8((fx - 0.5f) * dphi, short_series, &sd, &cd);
    env_v8 d0 = st * (cd * a[6] - sd * a[7]), d2 = st * (cd * a[7] + sd * a[6]);
    memcpy(d[0] + 8 * b, &d0, sizeof d0), memcpy(d[1] + 8 * b, &cy, sizeof cy), memcpy(d[2] + 8 * b, &d2, sizeof d2);
    memcpy(fxo + 8 * b, &fx, sizeof fx), memcpy(sto + 8 * b, &st, sizeof st);
  }
}

/* wv_envmap_sample on many numbers, in stages over blocks of draws so that the
 * table reads of different draws (random rows, random texels) overlap. */
ENV_CLONES void wv_envmap_sample_n(const wv_envmap *e, int n, const float (*u)[2], wv_env_sample *out) {
  enum { B = ENV_BLOCK, S = 4 * ENV_BLOCK };
  if (!(e->total > 0)) {
    for (int j = 0; j < n; j++) out[j].pdf = no_sample(out[j].d, out[j].rgb);
    return;
  }
  /* the texels read after all the blocks of up to S draws: while a block's texels
   * come, the next block is drawn */
  for (int s0 = 0; s0 < n; s0 += S) {
    int ns = n - s0 < S ? n - s0 : S;
    wv_env_at at[S];
    for (int j0 = s0; j0 < s0 + ns; j0 += B) {
      int m = s0 + ns - j0 < B ? s0 + ns - j0 : B, y[B], lo[B], hi[B];
      const float(*v)[2] = u + j0;
      wv_env_sample *o = out + j0;
      wv_env_at *a = at + (j0 - s0);
      for (int j = 0; j < m; j++) {
        y[j] = find(e->cdf_row, e->guide_row, e->h, v[j][0]); /* the row CDF: small, cached */
        __builtin_prefetch(row_guide(e, y[j]) + guide_cell(v[j][1]));
      }
      for (int j = 0; j < m; j++) {
        guide_read(row_guide(e, y[j]), v[j][1], &lo[j], &hi[j]);
        __builtin_prefetch(row_cdf(e, y[j]) + lo[j]);
        __builtin_prefetch(row_cdf(e, y[j]) + (hi[j] < e->w ? hi[j] : e->w));
      }
      /* the columns, then the directions eight at a time (the same operations as
       * drawn_dir's, lane by lane), then their texels */
      _Alignas(32) float in[10][B], fx[B], st[B], dd[3][B];
      int x[B];
      for (int j = 0; j < m; j++) {
        const float *cdf = row_cdf(e, y[j]);
        guide_check(cdf, e->w, v[j][1], &lo[j], &hi[j]);
        x[j] = bisect(cdf, lo[j], hi[j], v[j][1]);
        in[0][j] = v[j][0], in[1][j] = v[j][1], in[2][j] = e->cdf_row[y[j]], in[3][j] = e->cdf_row[y[j] + 1];
        in[4][j] = cdf[x[j]], in[5][j] = cdf[x[j] + 1], in[6][j] = e->centre_x[2 * x[j]];
        in[7][j] = e->centre_x[2 * x[j] + 1], in[8][j] = e->edge_y[y[j]], in[9][j] = e->edge_y[y[j] + 1];
      }
      for (int j = m; j < (m + 7) / 8 * 8; j++) /* lanes past the end: a copy of the first, dropped */
        for (int k = 0; k < 10; k++) in[k][j] = in[k][0];
      env_dirs_8(in, (m + 7) / 8, 2 * PI_F / (float)e->w, e->w >= 8, dd, fx, st);
      for (int j = 0; j < m; j++) {
        o[j].d[0] = dd[0][j], o[j].d[1] = dd[1][j], o[j].d[2] = dd[2][j];
        a[j].texel = texel_of(e, o[j].d, fx[j], st[j], x[j], y[j]);
        __builtin_prefetch(e->texel + 4 * a[j].texel);
      }
    }
    for (int j = 0; j < ns; j++) out[s0 + j].pdf = wv_envmap_read(e, at[j], out[s0 + j].rgb);
  }
}

/* ---- built-in environments ---- */

static double smoothstep(double a, double b, double x) {
  double t = (x - a) / (b - a);
  t = t < 0 ? 0 : t > 1 ? 1 : t;
  return t * t * (3 - 2 * t);
}

/* A soft box: a rectangle of angular half-size (hw, hh) degrees around the
 * direction (azimuth az, elevation el), edges softened over 'soft' degrees. */
static double softbox(const double d[3], double az, double el, double hw, double hh, double soft) {
  double a = az * PI / 180, b = el * PI / 180;
  double c[3] = {cos(b) * sin(a), sin(b), -cos(b) * cos(a)};            /* the box's centre */
  double right[3] = {cos(a), 0, sin(a)};                                /* horizontal across it */
  double up[3] = {-sin(b) * sin(a), cos(b), sin(b) * cos(a)};            /* c x right, up the box */
  double dc = d[0] * c[0] + d[1] * c[1] + d[2] * c[2];
  if (dc <= 0) return 0;
  double x = atan2(d[0] * right[0] + d[1] * right[1] + d[2] * right[2], dc) * 180 / PI;
  double y = atan2(d[0] * up[0] + d[1] * up[1] + d[2] * up[2], dc) * 180 / PI;
  return (1 - smoothstep(hw - soft, hw, fabs(x))) * (1 - smoothstep(hh - soft, hh, fabs(y)));
}

static void studio(const double d[3], float out[3]) {
  /* a dim room (a soft vertical gradient, darker floor) lit by a large warm key box
   * in front-left, a cool fill in front-right, a rim box behind and a faint top light */
  double g = d[1] > 0 ? 0.04 + 0.05 * d[1] : 0.03 + 0.02 * (1 + d[1]);
  double key = softbox(d, -135, 30, 24, 18, 6), fill = softbox(d, 120, 15, 18, 12, 5);
  double rim = softbox(d, 15, 35, 12, 22, 4), top = softbox(d, 180, 75, 30, 30, 10);
  const double kc[3] = {7.0, 6.5, 5.8}, fc[3] = {1.2, 1.35, 1.6}, rc[3] = {4.0, 4.0, 4.0}, tc[3] = {0.6, 0.6, 0.6};
  for (int i = 0; i < 3; i++) out[i] = (float)(g + key * kc[i] + fill * fc[i] + rim * rc[i] + top * tc[i]);
}

static void sky(const double d[3], float out[3]) {
  const double sun_az = -30 * PI / 180, sun_el = 40 * PI / 180;
  double s[3] = {cos(sun_el) * sin(sun_az), sin(sun_el), -cos(sun_el) * cos(sun_az)};
  double cs = d[0] * s[0] + d[1] * s[1] + d[2] * s[2];
  double sun = smoothstep(cos(1.6 * PI / 180), cos(1.2 * PI / 180), cs); /* 1 inside 1.2 deg, 0 beyond 1.6 */
  double glow = pow(cs > 0 ? cs : 0, 64) * 0.8;
  if (d[1] >= 0) {
    double t = pow(1 - d[1], 4); /* 0 at the zenith, 1 at the horizon */
    const double zen[3] = {0.12, 0.25, 0.65}, hor[3] = {0.75, 0.82, 0.95};
    for (int i = 0; i < 3; i++) out[i] = (float)(zen[i] + (hor[i] - zen[i]) * t + glow + 2000 * sun);
  } else {
    double t = 1 - pow(1 + d[1], 8);
    const double gnd[3] = {0.09, 0.08, 0.06}, hor[3] = {0.30, 0.30, 0.30};
    for (int i = 0; i < 3; i++) out[i] = (float)(hor[i] + (gnd[i] - hor[i]) * t);
  }
}

int wv_env_is_builtin(const char *name) {
  return !strcmp(name, "studio") || !strcmp(name, "sky") || !strcmp(name, "white");
}

wv_status wv_env_builtin(const char *name, int width, wv_image *out, wv_error *err) {
  if (!wv_env_is_builtin(name))
    return wv_fail(err, WV_ERR_INVALID, "unknown built-in environment '%s' (expected studio, sky or white)", name);
  if (width < 16 || width > 8192)
    return wv_fail(err, WV_ERR_INVALID, "environment width %d is outside 16..8192", width);
  int h = width / 2;
  wv_status st = wv_image_alloc(out, width, h, 3, err);
  if (st) return st;
  for (int y = 0; y < h; y++)
    for (int x = 0; x < width; x++) {
      float *px = wv_image_px(out, x, y);
      if (name[0] == 'w') {
        px[0] = px[1] = px[2] = 1.0f;
        continue;
      }
      /* at the pixel's centre: the soft edges span several pixels */
      double th = PI * (y + 0.5) / h, ph = 2 * PI * (x + 0.5) / width - PI;
      double d[3] = {sin(th) * sin(ph), cos(th), -sin(th) * cos(ph)};
      float acc[3];
      if (name[1] == 't') studio(d, acc);
      else sky(d, acc);
      px[0] = acc[0], px[1] = acc[1], px[2] = acc[2];
    }
  return WV_OK;
}
