/* Registration of the fit to the photo: the densities to a tenth of a yarn per
 * inch and the weave's phase (a fabric offset), by phase correlation. See
 * wv_fit_register in fit.h for why. */
#include <fftw3.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "fit/fit_internal.h"
#include "woven/fit.h"
#include "woven/metrics.h"
#include "woven/render.h"

/* Everything one window's correlation needs, allocated once per registration. */
typedef struct {
  int w, h, nc;           /* window, complex row length w/2+1 */
  float *a;               /* w*h: the luminance detail (wv_image_detail) */
  float *corr;            /* w*h: correlation over all circular shifts */
  fftwf_complex *ref, *spec; /* h*nc: the photo's spectrum, the render's */
  fftwf_plan fwd, inv;
  double win_energy;      /* sum of win^2 */
} phasecorr;

static void pc_free(phasecorr *p) {
#pragma omp critical(wv_fftw_planner)
  {
    if (p->fwd) fftwf_destroy_plan(p->fwd);
    if (p->inv) fftwf_destroy_plan(p->inv);
  }
  fftwf_free(p->a), fftwf_free(p->corr), fftwf_free(p->ref), fftwf_free(p->spec);
  memset(p, 0, sizeof *p);
}

static wv_status pc_init(phasecorr *p, int w, int h, wv_error *err) {
  memset(p, 0, sizeof *p);
  p->w = w, p->h = h, p->nc = w / 2 + 1;
  size_t n = (size_t)w * h, nc = (size_t)h * p->nc;
  p->a = fftwf_alloc_real(n), p->corr = fftwf_alloc_real(n);
  p->ref = fftwf_alloc_complex(nc), p->spec = fftwf_alloc_complex(nc);
  if (!p->a || !p->corr || !p->ref || !p->spec) {
    pc_free(p);
    return wv_fail(err, WV_ERR_NOMEM, "out of memory for the registration (%d x %d window)", w, h);
  }
  /* FFTW_ESTIMATE: no timing-dependent planning, so results are reproducible. The
   * planner is not thread-safe (the same critical section as wv_weave_spectrum). */
#pragma omp critical(wv_fftw_planner)
  {
    p->fwd = fftwf_plan_dft_r2c_2d(h, w, p->a, p->spec, FFTW_ESTIMATE);
    p->inv = fftwf_plan_dft_c2r_2d(h, w, p->spec, p->corr, FFTW_ESTIMATE);
  }
  if (!p->fwd || !p->inv) {
    pc_free(p);
    return wv_fail(err, WV_ERR_NOMEM, "cannot plan the registration FFT (%d x %d)", w, h);
  }
  p->win_energy = 0; /* of wv_image_detail's Hann window */
  for (int y = 0; y < h; y++)
    for (int x = 0; x < w; x++) {
      double v = (0.5 - 0.5 * cos(2 * 3.14159265358979323846 * (x + 0.5) / w)) * (0.5 - 0.5 * cos(2 * 3.14159265358979323846 * (y + 0.5) / h));
      p->win_energy += v * v;
    }
  return WV_OK;
}

/* Correlation of the photo (p->ref) with img over shifts |s| <= max_shift: the best
 * normalised value and the shift s (sub-pixel) with photo(x) ~ img(x - s). */
static wv_status pc_best(phasecorr *p, const wv_image *img, int max_shift, double shift[2], double *out,
                         wv_error *err) {
  wv_status rc = wv_image_detail(img, 0, 0, p->w, p->h, p->a, err);
  if (rc) return rc;
  fftwf_execute(p->fwd);
  size_t nc = (size_t)p->h * p->nc;
  for (size_t i = 0; i < nc; i++) { /* ref * conj(spec) */
    float ar = p->ref[i][0], ai = p->ref[i][1], br = p->spec[i][0], bi = p->spec[i][1];
    p->spec[i][0] = ar * br + ai * bi;
    p->spec[i][1] = ai * br - ar * bi;
  }
  fftwf_execute(p->inv);
  int w = p->w, h = p->h;
  double norm = 1.0 / ((double)w * h * p->win_energy);
#define CORR(dx, dy) (p->corr[(size_t)(((dy) % h + h) % h) * w + (size_t)(((dx) % w + w) % w)] * norm)
  double best = -2;
  int bx = 0, by = 0;
  for (int dy = -max_shift; dy <= max_shift; dy++)
    for (int dx = -max_shift; dx <= max_shift; dx++) {
      double v = CORR(dx, dy);
      if (v > best) best = v, bx = dx, by = dy;
    }
  if (shift) { /* parabola through the peak and its neighbours, per axis */
    double l = CORR(bx - 1, by), r = CORR(bx + 1, by), u = CORR(bx, by - 1), d = CORR(bx, by + 1);
    double ex = l - 2 * best + r, ey = u - 2 * best + d;
    shift[0] = bx + (ex < 0 ? 0.5 * (l - r) / ex : 0.0);
    shift[1] = by + (ey < 0 ? 0.5 * (u - d) / ey : 0.0);
  }
#undef CORR
  *out = best;
  return WV_OK;
}

/* One window size: its scene, the photo's pixels there and their spectrum. */
typedef struct {
  phasecorr pc;
  wv_scene win;
  wv_image ref;
  int max_shift;
  wv_render_opts ro;
} level;

static void level_free(level *l) {
  pc_free(&l->pc);
  wv_image_free(&l->ref);
}

static wv_status level_init(level *l, const wv_scene *full, const wv_image *photo, int size, const wv_fit_opts *o,
                            wv_error *err) {
  memset(l, 0, sizeof *l);
  int w = full->width < size ? full->width : size, h = full->height < size ? full->height : size;
  w -= (full->width - w) % 2, h -= (full->height - h) % 2; /* centred on whole pixels */
  wv_scene_centre_window(full, w, h, &l->win);
  l->win.spp = o->iter_spp;
  l->max_shift = (w < h ? w : h) / 4;
  l->ro = (wv_render_opts){.spp = l->win.spp, .threads = o->threads};
  wv_status rc = wv_image_centre_crop(photo, w, h, &l->ref, err);
  if (!rc) rc = pc_init(&l->pc, w, h, err);
  if (rc) {
    wv_image_free(&l->ref);
    return rc;
  }
  if ((rc = wv_image_detail(&l->ref, 0, 0, w, h, l->pc.a, err))) {
    level_free(l);
    return rc;
  }
  fftwf_execute(l->pc.fwd);
  memcpy(l->pc.ref, l->pc.spec, sizeof(fftwf_complex) * (size_t)h * l->pc.nc);
  return WV_OK;
}

/* Renders the level's window with the given densities and scores it (shifts
 * up to the level's limit). */
static wv_status score(level *l, const wv_params *base, const double dens[2], double *out, double shift[2],
                       wv_error *err) {
  wv_params p = *base;
  p.density[0] = dens[0], p.density[1] = dens[1];
  wv_image img;
  wv_status rc = wv_render(&l->win, &p, &l->ro, &img, NULL, err);
  if (rc) return rc;
  rc = pc_best(&l->pc, &img, l->max_shift, shift, out, err);
  wv_image_free(&img);
  return rc;
}

/* Correlation at zero shift and SSIM of one render of win against the level's photo. */
static wv_status measure(level *l, const wv_scene *win, const wv_params *p, const wv_render_opts *ro, double *ncc,
                         double *ssim, wv_error *err) {
  wv_image img;
  wv_status rc = wv_render(win, p, ro, &img, NULL, err);
  if (rc) return rc;
  rc = pc_best(&l->pc, &img, 0, NULL, ncc, err);
  if (!rc) rc = wv_ssim(&l->ref, &img, WV_SSIM_RGB, ssim, err);
  wv_image_free(&img);
  return rc;
}

/* The fabric offset that moves a render by shift pixels, through the local map pixel ->
 * fabric at the centre: photo(x) ~ render(x - shift) means fabric(x) must become
 * fabric(x - shift). {0, 0} where the centre misses the cloth. */
static void shift_offset(const wv_scene *full, const double shift[2], double off[2]) {
  double f0[2], fx[2], fy[2];
  double cx = 0.5 * full->width, cy = 0.5 * full->height;
  off[0] = off[1] = 0;
  if (wv_render_fabric_at(full, cx, cy, f0) && wv_render_fabric_at(full, cx + 1, cy, fx) &&
      wv_render_fabric_at(full, cx, cy + 1, fy))
    for (int i = 0; i < 2; i++) off[i] = -((fx[i] - f0[i]) * shift[0] + (fy[i] - f0[i]) * shift[1]);
}

static int in_range(const double d[2]) {
  return d[0] >= WV_DENSITY_MIN && d[0] <= WV_DENSITY_MAX && d[1] >= WV_DENSITY_MIN && d[1] <= WV_DENSITY_MAX;
}

#define MAX_THREADS 16

/* One window size, one copy per thread (renders and FFTs run one per thread:
 * the windows are too small to split across threads). */
typedef struct {
  double d[2], score, shift[2];
} scored;

typedef struct {
  level lv[MAX_THREADS];
  int n;
  wv_footprints *fp; /* the window's camera geometry, shared */
  scored *seen;      /* every density pair scored in this window: a climb's neighbourhoods overlap */
  int nseen, capseen;
  int renders;       /* density pairs rendered in this window */
} level_set;

static void set_free(level_set *ls) {
  for (int i = 0; i < ls->n; i++) level_free(&ls->lv[i]);
  free(ls->seen);
  ls->seen = NULL, ls->nseen = ls->capseen = 0;
  ls->n = 0, ls->renders = 0;
  wv_footprints_free(ls->fp);
  ls->fp = NULL;
}

static wv_status set_init(level_set *ls, const wv_scene *full, const wv_image *photo, int size, int threads,
                          const wv_fit_opts *o, wv_error *err) {
  ls->n = 0, ls->renders = 0;
  for (int i = 0; i < threads; i++) {
    wv_status rc = level_init(&ls->lv[i], full, photo, size, o, err);
    if (rc) {
      set_free(ls);
      return rc;
    }
    ls->lv[i].ro.threads = 1;
    ls->n++;
  }
  wv_status rc = wv_footprints_create(&ls->lv[0].win, threads, &ls->fp, err);
  if (rc) {
    set_free(ls);
    return rc;
  }
  for (int i = 0; i < ls->n; i++) ls->lv[i].ro.footprints = ls->fp;
  return WV_OK;
}

/* The score of d scored before in this window, or NULL. A score depends on the densities
 * alone (the same render, the same photo window), so it is never made twice. */
static const scored *seen_find(const level_set *ls, const double d[2]) {
  for (int i = 0; i < ls->nseen; i++)
    if (ls->seen[i].d[0] == d[0] && ls->seen[i].d[1] == d[1]) return &ls->seen[i];
  return NULL;
}

/* Scores of count density pairs (out of range: -3), in parallel; those scored before are
 * taken from ls->seen. */
static wv_status eval_many(level_set *ls, const wv_params *base, const double (*d)[2], int count, double *out,
                           wv_error *err) {
  wv_status rc = WV_OK;
  char *todo = malloc((size_t)count + 1);
  double(*sh)[2] = malloc(sizeof *sh * ((size_t)count + 1));
  if (!todo || !sh) free(todo), free(sh), todo = NULL;
  if (!todo) return wv_fail(err, WV_ERR_NOMEM, "out of memory for the registration");
  int fresh = 0;
  for (int i = 0; i < count; i++) {
    const scored *sc = count <= 64 ? seen_find(ls, d[i]) : NULL; /* the climbs' few, not the grids */
    todo[i] = !sc;
    fresh += !sc;
    ls->renders += !sc && in_range(d[i]);
    if (sc) out[i] = sc->score;
  }
  if (count <= 64 && ls->nseen + fresh > ls->capseen) {
    int cap = 2 * (ls->nseen + fresh) + 64;
    scored *ns = realloc(ls->seen, sizeof *ns * (size_t)cap);
    if (!ns) {
      free(todo), free(sh);
      return wv_fail(err, WV_ERR_NOMEM, "out of memory for the registration");
    }
    ls->seen = ns, ls->capseen = cap;
  }
#pragma omp parallel for schedule(dynamic, 1) num_threads(ls->n)
  for (int i = 0; i < count; i++) {
    if (!todo[i]) continue;
    level *l = &ls->lv[omp_get_thread_num()];
    out[i] = -3;
    if (!in_range(d[i])) continue;
    wv_error e = {0};
    wv_status r = score(l, base, d[i], &out[i], sh[i], &e);
    if (r) {
#pragma omp critical(wv_register_error)
      if (!rc) {
        rc = r;
        if (err) *err = e;
      }
    }
  }
  if (!rc && count <= 64)
    for (int i = 0; i < count; i++)
      if (todo[i]) ls->seen[ls->nseen++] = (scored){{d[i][0], d[i][1]}, out[i], {sh[i][0], sh[i][1]}};
  free(todo), free(sh);
  return rc;
}

/* Moves cur to the best of its 8 neighbours while that raises the score, for
 * each step size in turn. */
static wv_status hill_climb(level_set *ls, const wv_params *base, const double *steps, int nsteps, double cur[2],
                            double *best, wv_error *err) {
  wv_status rc = WV_OK;
  for (int k = 0; k < nsteps && !rc; k++)
    for (int moves = 0; moves < 8 && !rc; moves++) {
      double d[8][2], v[8];
      int m = 0;
      for (int a = -1; a <= 1; a++)
        for (int b = -1; b <= 1; b++)
          if (a || b) d[m][0] = cur[0] + a * steps[k], d[m][1] = cur[1] + b * steps[k], m++;
      if ((rc = eval_many(ls, base, (const double(*)[2])d, 8, v, err))) break;
      int bi = -1;
      double bv = *best;
      for (int i = 0; i < 8; i++)
        if (v[i] > bv) bv = v[i], bi = i;
      if (bi < 0) break;
      *best = bv, cur[0] = d[bi][0], cur[1] = d[bi][1];
    }
  return rc;
}

#define GLOBAL_STEP 1.05 /* ratio between neighbouring densities of the coarse grid */
#define WV_REGISTER_MIN_NCC 0.2 /* phase correlation that counts as the weave lining up */
#define N_CAND 4         /* candidates from it refined in the larger window */
#define GLOBAL_WINDOW 64 /* its window's side */
#define GLOBAL_COARSE 2  /* the grid's first pass: every second density of each */
#define N_SEED 24        /* coarse points whose neighbourhoods climb on the whole grid */
#define GLOBAL_CLEAR 0.4 /* below this best coarse score the step gives no candidates */

/* Step 1 of the registration: the N_CAND best density pairs of the ratio grid (GLOBAL_STEP
 * apart over the whole range), each at least 4 grid steps from those before it. The grid is
 * not rendered whole: every GLOBAL_COARSE-th density of each first, then from the N_SEED best
 * of those (kept apart), an 8-neighbour climb on the grid itself to its local peak. A peak
 * of a weave that lines up is wider than a coarse step in this window, so the coarse grid
 * lands on its slope and the climb finds the grid's own best: the candidates are those of
 * the whole grid (as measured: docs/fit.md), from a third of its renders. Unrendered grid
 * points are not chosen. When no coarse score reaches GLOBAL_CLEAR (a photo whose weave
 * lines up nowhere in this window: satin1_R.png's best is 0.22, the twills' 0.7), there are
 * no candidates: the registration goes on from the fitted densities alone. whole renders
 * the whole grid (the reference the tests compare with). *renders: how many were rendered. */
static wv_status global_candidates(level_set *ls, const wv_params *base, int whole, double cand[][2], int *nc,
                                   int *renders, wv_error *err) {
  const int n = (int)floor(log(WV_DENSITY_MAX / WV_DENSITY_MIN) / log(GLOBAL_STEP)) + 1;
  const int step = whole ? 1 : GLOBAL_COARSE, nco = (n + step - 1) / step;
  *renders = 0;
  size_t nn = (size_t)n * n;
  double(*gd)[2] = malloc(sizeof *gd * nn), *grid = malloc(sizeof(double) * nn);
  double(*q)[2] = malloc(sizeof *q * (nn > 8 * N_SEED ? nn : 8 * N_SEED));
  int *qk = malloc(sizeof(int) * (nn > 8 * N_SEED ? nn : 8 * N_SEED));
  double *qv = malloc(sizeof(double) * (nn > 8 * N_SEED ? nn : 8 * N_SEED));
  char *done = calloc(nn, 1);
  wv_status rc = WV_OK;
  if (!gd || !grid || !q || !qk || !qv || !done) rc = wv_fail(err, WV_ERR_NOMEM, "out of memory for the registration grid");
  for (int i = 0; i < n && !rc; i++)
    for (int j = 0; j < n; j++) {
      gd[i * n + j][0] = WV_DENSITY_MIN * pow(GLOBAL_STEP, i), gd[i * n + j][1] = WV_DENSITY_MIN * pow(GLOBAL_STEP, j);
      grid[i * n + j] = -3;
    }
  /* the coarse grid */
  int m = 0;
  for (int a = 0; a < nco && !rc; a++)
    for (int b = 0; b < nco; b++) {
      int k = a * step * n + b * step;
      q[m][0] = gd[k][0], q[m][1] = gd[k][1], qk[m++] = k;
    }
  if (!rc) rc = eval_many(ls, base, (const double(*)[2])q, m, qv, err);
  for (int t = 0; t < m && !rc; t++) grid[qk[t]] = qv[t], done[qk[t]] = 1, *renders += in_range(q[t]);
  /* no clear peak: the scores are noise with many maxima of about one height, and a
   * candidate taken from them is one of those maxima, not a density the weave lines up at */
  double top = -2;
  for (int t = 0; t < m && !rc; t++) top = qv[t] > top ? qv[t] : top;
  if (!rc && !whole && top < GLOBAL_CLEAR) {
    free(gd), free(grid), free(q), free(qk), free(qv), free(done);
    return rc;
  }
  /* the seeds: the best coarse points, each blanking its coarse neighbours */
  int seed[N_SEED], ns = 0;
  if (!rc) {
    double *cg = malloc(sizeof(double) * (size_t)m);
    if (!cg) rc = wv_fail(err, WV_ERR_NOMEM, "out of memory for the registration grid");
    for (int t = 0; t < m && cg; t++) cg[t] = qv[t];
    for (; cg && !whole && ns < N_SEED; ns++) {
      int bt = -1;
      double bv = -2.5;
      for (int t = 0; t < m; t++)
        if (cg[t] > bv) bv = cg[t], bt = t;
      if (bt < 0) break;
      seed[ns] = qk[bt];
      int a0 = bt / nco, b0 = bt % nco;
      for (int a = a0 - 1; a <= a0 + 1; a++)
        for (int b = b0 - 1; b <= b0 + 1; b++)
          if (a >= 0 && b >= 0 && a < nco && b < nco) cg[a * nco + b] = -3;
    }
    free(cg);
  }
  /* each seed climbs on the grid; all the seeds' neighbourhoods render in one batch */
  int cur[N_SEED], live[N_SEED];
  for (int t = 0; t < ns; t++) cur[t] = seed[t], live[t] = 1;
  for (int round = 0; round < n && !rc; round++) {
    m = 0;
    for (int t = 0; t < ns; t++) {
      if (!live[t]) continue;
      int i0 = cur[t] / n, j0 = cur[t] % n;
      for (int a = i0 - 1; a <= i0 + 1; a++)
        for (int b = j0 - 1; b <= j0 + 1; b++) {
          int k = a * n + b;
          if (a < 0 || b < 0 || a >= n || b >= n || done[k]) continue;
          done[k] = 2; /* queued */
          q[m][0] = gd[k][0], q[m][1] = gd[k][1], qk[m++] = k;
        }
    }
    if (!m) break;
    if ((rc = eval_many(ls, base, (const double(*)[2])q, m, qv, err))) break;
    for (int t = 0; t < m; t++) grid[qk[t]] = qv[t], done[qk[t]] = 1, *renders += in_range(q[t]);
    int moved = 0;
    for (int t = 0; t < ns; t++) {
      if (!live[t]) continue;
      int i0 = cur[t] / n, j0 = cur[t] % n, bk = cur[t];
      for (int a = i0 - 1; a <= i0 + 1; a++)
        for (int b = j0 - 1; b <= j0 + 1; b++)
          if (a >= 0 && b >= 0 && a < n && b < n && grid[a * n + b] > grid[bk]) bk = a * n + b;
      live[t] = bk != cur[t];
      cur[t] = bk, moved |= live[t];
    }
    if (!moved) break;
  }
  /* best remaining, then blank its neighbourhood; the ring just outside the blank is
   * rendered before the next choice: the slope of a peak there can outscore a weaker peak */
  for (int c = 0; c < N_CAND && !rc; c++) {
    int bi = -1, bj = -1;
    double bv = -2.5;
    for (int i = 0; i < n; i++)
      for (int j = 0; j < n; j++)
        if (done[(size_t)i * n + j] == 1 && grid[(size_t)i * n + j] > bv) bv = grid[(size_t)i * n + j], bi = i, bj = j;
    if (bi < 0) break;
    cand[*nc][0] = gd[bi * n + bj][0], cand[*nc][1] = gd[bi * n + bj][1], (*nc)++;
    for (int i = bi - 3; i <= bi + 3; i++)
      for (int j = bj - 3; j <= bj + 3; j++)
        if (i >= 0 && j >= 0 && i < n && j < n) grid[(size_t)i * n + j] = -3, done[(size_t)i * n + j] = 3;
    if (c == N_CAND - 1) break;
    m = 0;
    for (int i = bi - 4; i <= bi + 4; i++)
      for (int j = bj - 4; j <= bj + 4; j++) {
        int k = i * n + j;
        if (i < 0 || j < 0 || i >= n || j >= n || done[k] || (abs(i - bi) < 4 && abs(j - bj) < 4)) continue;
        q[m][0] = gd[k][0], q[m][1] = gd[k][1], qk[m++] = k;
      }
    if (m && (rc = eval_many(ls, base, (const double(*)[2])q, m, qv, err))) break;
    for (int t = 0; t < m; t++) grid[qk[t]] = qv[t], done[qk[t]] = 1, *renders += in_range(q[t]);
  }
  free(gd), free(grid), free(q), free(qk), free(qv), free(done);
  return rc;
}

wv_status wv_fit_register_candidates(const wv_fit_state *st, const wv_scene *s, const wv_image *photo,
                                     const wv_fit_opts *o, int whole, double cand[4][2], int *nc, int *renders,
                                     wv_error *err) {
  wv_scene full;
  wv_fit_scene(st, s, &full);
  int threads = o->threads > 0 ? o->threads : omp_get_max_threads();
  threads = threads < 1 ? 1 : threads > MAX_THREADS ? MAX_THREADS : threads;
  level_set *ls = calloc(1, sizeof *ls);
  if (!ls) return wv_fail(err, WV_ERR_NOMEM, "out of memory for the registration");
  *nc = 0;
  wv_status rc = set_init(ls, &full, photo, GLOBAL_WINDOW, threads, o, err);
  if (!rc) rc = global_candidates(ls, &st->params, whole, cand, nc, renders, err);
  set_free(ls);
  free(ls);
  return rc;
}

static wv_status register_run(wv_fit_state *st, const wv_scene *s, const wv_image *photo, const wv_fit_opts *o,
                              int global, int whole_climb, wv_error *err);

wv_status wv_fit_register(wv_fit_state *st, const wv_scene *s, const wv_image *photo, const wv_fit_opts *o,
                          wv_error *err) {
  return register_run(st, s, photo, o, 1, 1, err);
}

wv_status wv_fit_register_near(wv_fit_state *st, const wv_scene *s, const wv_image *photo, const wv_fit_opts *o,
                               wv_error *err) {
  return register_run(st, s, photo, o, 0, 1, err);
}

wv_status wv_fit_register_view(wv_fit_state *st, const wv_scene *s, const wv_image *photo, const wv_fit_opts *o,
                               wv_error *err) {
  return register_run(st, s, photo, o, 0, 0, err);
}

static wv_status register_run(wv_fit_state *st, const wv_scene *s, const wv_image *photo, const wv_fit_opts *o,
                              int global, int whole_climb, wv_error *err) {
  if (o->register_radius < 0 || o->register_radius > WV_FIT_MAX_REGISTER_RADIUS)
    return wv_fail(err, WV_ERR_INVALID, "fit option 'register_radius' = %d is outside 0..%d", o->register_radius,
                   WV_FIT_MAX_REGISTER_RADIUS);
  wv_scene full;
  wv_fit_scene(st, s, &full);
  int threads = o->threads > 0 ? o->threads : omp_get_max_threads();
  threads = threads < 1 ? 1 : threads > MAX_THREADS ? MAX_THREADS : threads;
  /* Four window sizes, the last the whole image: the narrow density peak of a
   * large window is found from the wide one of a small window. */
  level_set *S = calloc(4, sizeof *S);
  if (!S) return wv_fail(err, WV_ERR_NOMEM, "out of memory for the registration");
  const int sizes[4] = {GLOBAL_WINDOW, 128, 256, 1 << 30};
  wv_status rc = WV_OK;
  for (int i = 0; i < 4 && !rc; i++) rc = set_init(&S[i], &full, photo, sizes[i], threads, o, err);
  const wv_params *base = &st->params;
  double cur[2] = {base->density[0], base->density[1]}, best = -2, shift[2] = {0, 0};
  level *top = &S[3].lv[0];
  wv_render_opts top_ro = top->ro; /* the whole image, on every thread */
  top_ro.threads = threads;
  double ssim_before = 0;
  if (!rc) rc = measure(top, &top->win, base, &top_ro, &st->reg_ncc_before, &ssim_before, err);

  /* 1. The whole density range on a ratio grid in the small window: a density far
   * from the fitted one (another aliasing of the same texture: twill2_R.png's
   * weft went from 227 to 75) is found here. The best few, kept apart, go on. */
  double cand[N_CAND + 1][2];
  int nc = 0;
  int renders = 0;
  if (!rc && global) rc = global_candidates(&S[0], base, 0, cand, &nc, &renders, err);
  /* 2. In the middle window: the grid of whole yarns/inch +-register_radius around
   * the fitted densities (the peak is narrow: a one-at-a-time search walks off
   * it) gives one more candidate; each climbs with steps of 2, 1, 0.5. */
  int R = o->register_radius, m = (2 * R + 1) * (2 * R + 1);
  double(*ld)[2] = rc ? NULL : malloc(sizeof *ld * (size_t)m);
  double *lv = rc ? NULL : malloc(sizeof(double) * (size_t)m);
  if (!rc && (!ld || !lv)) rc = wv_fail(err, WV_ERR_NOMEM, "out of memory for the registration grid");
  for (int k = 0; k < m && !rc; k++) ld[k][0] = cur[0] + (k / (2 * R + 1) - R), ld[k][1] = cur[1] + (k % (2 * R + 1) - R);
  if (!rc) rc = eval_many(&S[1], base, (const double(*)[2])ld, m, lv, err);
  if (!rc) {
    int bk = 0;
    for (int k = 1; k < m; k++)
      if (lv[k] > lv[bk]) bk = k;
    cand[nc][0] = ld[bk][0], cand[nc][1] = ld[bk][1], nc++;
  }
  free(ld), free(lv);
  static const double mid_steps[] = {2, 1, 0.5}, fine_steps[] = {0.5, 0.25, 0.1};
  double mid_best = -2, mid[2] = {cur[0], cur[1]};
  for (int c = 0; c < nc && !rc; c++) {
    double d[2] = {cand[c][0], cand[c][1]}, v;
    if ((rc = eval_many(&S[1], base, (const double(*)[2])d, 1, &v, err))) break;
    if ((rc = hill_climb(&S[1], base, mid_steps, 3, d, &v, err))) break;
    if (v > mid_best) mid_best = v, mid[0] = d[0], mid[1] = d[1];
  }
  /* No candidate lines up in the middle window either: the larger windows would only refine
   * a density the keep rule below turns down (a correlation under WV_REGISTER_MIN_NCC), so
   * they are skipped and the fit stays where it was. */
  int keep = 0;
  double after = ssim_before, ncc_after = st->reg_ncc_before, off[2] = {0, 0};
  wv_params cand_p = *base;
  if (!rc && mid_best >= WV_REGISTER_MIN_NCC) {
    /* 3. In the large window, then the whole image (a tenth of a yarn/inch is a
     * yarn of drift across 500 pixels): the last tenths, then the shift. */
    cur[0] = mid[0], cur[1] = mid[1];
    rc = eval_many(&S[2], base, (const double(*)[2])cur, 1, &best, err);
    if (!rc) rc = hill_climb(&S[2], base, fine_steps, 2, cur, &best, err);
    if (!rc) rc = eval_many(&S[3], base, (const double(*)[2])cur, 1, &best, err);
    if (!rc && whole_climb) rc = hill_climb(&S[3], base, fine_steps + 2, 1, cur, &best, err);
    const scored *at = rc ? NULL : seen_find(&S[3], cur); /* the best's shift, from its score */
    if (at) shift[0] = at->shift[0], shift[1] = at->shift[1], best = at->score;
    if (!rc) { /* kept only if the whole image's SSIM rises */
      shift_offset(&full, shift, off);
      cand_p.density[0] = cur[0], cand_p.density[1] = cur[1];
      wv_scene moved = top->win;
      moved.fabric_offset[0] += off[0], moved.fabric_offset[1] += off[1];
      top_ro.footprints = NULL; /* the moved fabric has other footprints */
      rc = measure(top, &moved, &cand_p, &top_ro, &ncc_after, &after, err);
      /* A rise without a correlation peak would only trade contrast for SSIM. */
      keep = !rc && after > ssim_before && ncc_after >= WV_REGISTER_MIN_NCC;
    }
  }
  if (!rc) {
    st->reg_ssim_before = ssim_before;
    if (keep) {
      st->params = cand_p;
      st->offset_mm[0] += off[0], st->offset_mm[1] += off[1];
    }
    st->reg_ssim_after = keep ? after : ssim_before, st->reg_ncc_after = keep ? ncc_after : st->reg_ncc_before;
    st->registered = 1;
  }
  for (int i = 0; i < 4; i++) st->reg_renders[i] = S[i].renders, set_free(&S[i]);
  free(S);
  return rc;
}

wv_status wv_fit_register_phase(const wv_fit_state *st, const wv_scene *s, const wv_image *photo,
                                const wv_params *p, const wv_fit_opts *o, double *ssim, wv_error *err) {
  wv_scene full;
  wv_fit_scene(st, s, &full);
  level l;
  wv_status rc = level_init(&l, &full, photo, 1 << 30, o, err);
  if (rc) return rc;
  double ncc, before = 0, shift[2], off[2];
  wv_image img;
  if (!(rc = wv_render(&l.win, p, &l.ro, &img, NULL, err))) { /* one render: its SSIM and its shift */
    rc = wv_ssim(&l.ref, &img, WV_SSIM_RGB, &before, err);
    if (!rc) rc = pc_best(&l.pc, &img, l.max_shift, shift, &ncc, err);
    wv_image_free(&img);
  }
  *ssim = before;
  if (!rc) {
    shift_offset(&full, shift, off);
    wv_scene moved = l.win;
    moved.fabric_offset[0] += off[0], moved.fabric_offset[1] += off[1];
    double after;
    /* kept as wv_fit_register keeps a registration: a higher SSIM with the weave in step */
    if (!(rc = measure(&l, &moved, p, &l.ro, &ncc, &after, err)) && after > before && ncc >= WV_REGISTER_MIN_NCC)
      *ssim = after;
  }
  level_free(&l);
  return rc;
}
