/* Weave analysis of a photo: the spectral peaks of its luminance detail, the lattice of
 * each built-in pattern that explains them (densities and orientation), the repeat's
 * geometry, and the ranking of the built-ins by their own renders (analysis.h). */
#include "woven/analysis.h"

#include <jansson.h>
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "util/select.h"
#include "woven/metrics.h"
#include "woven/render.h"

#define Z_PEAK 3.5      /* a peak: a local maximum this many robust deviations above its ring */
#define Z_CAP 10.0      /* prominence counts up to here (one very strong peak must not decide alone) */
#define PEAK_RAD 3      /* local maximum over a (2 PEAK_RAD + 1)^2 neighbourhood: a peak split by an
                         * irregular cloth counts once */
#define COARSE_RAD 2    /* bins of tolerance in the coarse search (the grid is 1.5% apart) */
#define FINE_RAD 1      /* ... and when refining */
#define MATCH_RAD 2.5   /* bins: a render's peak matches a photo's peak this close */
#define YARN_W 0.5      /* weight of the yarn frequencies against the strongest pattern coefficient */
#define GRID_STEP 1.02  /* ratio between neighbouring densities of the coarse search */
#define N_START 4       /* coarse maxima refined per pattern */

static const double PI = 3.14159265358979323846;

/* ---- prominence and peaks ---- */

/* z: the whitened weave spectrum (wv_spectrum_whiten) clipped to [0, Z_CAP]. */
static wv_status prominence(const float *spec, int n, float *z, wv_error *err) {
  return wv_spectrum_whiten(spec, n, 0.0, Z_CAP, z, err);
}

static inline size_t bin(int n, int u, int v) {
  u = ((u + n / 2) % n + n) % n, v = ((v + n / 2) % n + n) % n; /* wrap: the spectrum is periodic */
  return (size_t)v * n + u;
}

/* Local maxima of z of at least min_z in the half plane, strongest first. */
static int find_peaks(const float *spec, const float *z, int n, double min_z, wv_spectral_peak *pk, int cap) {
  int np = 0;
  for (int v = 0; v < n / 2; v++)
    for (int u = -n / 2 + 1; u < n / 2; u++) {
      if (v == 0 && u <= 0) continue;
      float c = z[bin(n, u, v)];
      if (c < min_z) continue;
      int is_max = 1;
      for (int dv = -PEAK_RAD; dv <= PEAK_RAD && is_max; dv++)
        for (int du = -PEAK_RAD; du <= PEAK_RAD; du++) {
          if (!du && !dv) continue;
          float o = z[bin(n, u + du, v + dv)];
          /* ties: the first in scan order wins (the capped plateau of a strong peak) */
          if (o > c || (o == c && (dv < 0 || (dv == 0 && du < 0)))) {
            is_max = 0;
            break;
          }
        }
      if (!is_max) continue;
      /* sub-bin position: a parabola through the log spectrum, per axis */
      double l = spec[bin(n, u - 1, v)], m = spec[bin(n, u, v)], r = spec[bin(n, u + 1, v)];
      double t = spec[bin(n, u, v - 1)], b = spec[bin(n, u, v + 1)];
      double ex = l - 2 * m + r, ey = t - 2 * m + b;
      double du = ex < 0 ? 0.5 * (l - r) / ex : 0, dv = ey < 0 ? 0.5 * (t - b) / ey : 0;
      wv_spectral_peak p = {(u + du) / n, (v + dv) / n, c};
      /* insertion into the sorted list */
      int at = np < cap ? np : cap;
      while (at > 0 && pk[at - 1].z < p.z) {
        if (at < cap) pk[at] = pk[at - 1];
        at--;
      }
      if (at < cap) pk[at] = p;
      if (np < cap) np++;
    }
  return np;
}

int wv_spectrum_peaks(const float *spectrum, int n, double min_z, wv_spectral_peak *peaks, int cap) {
  float *z = malloc(sizeof(float) * (size_t)n * n);
  if (!z || prominence(spectrum, n, z, NULL)) {
    free(z);
    return 0;
  }
  int np = find_peaks(spectrum, z, n, min_z, peaks, cap);
  free(z);
  return np;
}

/* ---- what a spectrum offers a hypothesis ---- */

#define SINC_N 4096
#define SINC_MAX 4.0

typedef struct {
  int n;
  float sinc[SINC_N + 1]; /* |sinc| on [0, SINC_MAX] cycles per pixel: a pixel's response */
  float *z;         /* prominence */
  float *zc;        /* its maximum over the coarse radius */
  signed char *idc, *idf; /* the peak within the coarse / fine radius of a bin (-1: none) */
  int np;
  wv_spectral_peak pk[WV_LATTICE_PEAKS];
  double pk_total;  /* sum of the peaks' z */
} smap;

static void smap_free(smap *m) {
  free(m->z), free(m->zc), free(m->idc), free(m->idf);
  memset(m, 0, sizeof *m);
}

static void stamp_peaks(smap *m, double rad, signed char *id) {
  int n = m->n, r = (int)ceil(rad);
  memset(id, -1, (size_t)n * n);
  for (int k = 0; k < m->np; k++) /* strongest first: a bin near two peaks belongs to the stronger */
    for (int s = -1; s <= 1; s += 2) {
      double cu = s * m->pk[k].u * n, cv = s * m->pk[k].v * n;
      for (int dv = -r - 1; dv <= r + 1; dv++)
        for (int du = -r - 1; du <= r + 1; du++) {
          int u = (int)floor(cu + 0.5) + du, v = (int)floor(cv + 0.5) + dv;
          if ((u - cu) * (u - cu) + (v - cv) * (v - cv) > rad * rad) continue;
          size_t i = bin(n, u, v);
          if (id[i] < 0) id[i] = (signed char)k;
        }
    }
}

static wv_status smap_init(smap *m, const float *spec, int n, wv_error *err) {
  memset(m, 0, sizeof *m);
  m->n = n;
  size_t nn = (size_t)n * n;
  m->z = malloc(sizeof(float) * nn), m->zc = malloc(sizeof(float) * nn);
  m->idc = malloc(nn), m->idf = malloc(nn);
  if (!m->z || !m->zc || !m->idc || !m->idf) {
    smap_free(m);
    return wv_fail(err, WV_ERR_NOMEM, "out of memory for the weave analysis");
  }
  wv_status st = prominence(spec, n, m->z, err);
  if (st) {
    smap_free(m);
    return st;
  }
  for (int v = -n / 2; v < n / 2; v++)
    for (int u = -n / 2; u < n / 2; u++) {
      float best = 0;
      for (int dv = -COARSE_RAD; dv <= COARSE_RAD; dv++)
        for (int du = -COARSE_RAD; du <= COARSE_RAD; du++) {
          float o = m->z[bin(n, u + du, v + dv)];
          if (o > best) best = o;
        }
      m->zc[bin(n, u, v)] = best;
    }
  for (int i = 0; i <= SINC_N; i++) {
    double x = SINC_MAX * i / SINC_N;
    m->sinc[i] = i ? (float)fabs(sin(PI * x) / (PI * x)) : 1.0f;
  }
  m->np = find_peaks(spec, m->z, n, Z_PEAK, m->pk, WV_LATTICE_PEAKS);
  for (int k = 0; k < m->np; k++) m->pk_total += m->pk[k].z;
  stamp_peaks(m, COARSE_RAD + 0.5, m->idc);
  stamp_peaks(m, FINE_RAD + 0.5, m->idf);
  return WV_OK;
}

/* Bilinear z at a fractional bin. */
static inline double z_at(const smap *m, double bu, double bv) {
  int u = (int)floor(bu), v = (int)floor(bv);
  double fu = bu - u, fv = bv - v;
  int n = m->n;
  return (1 - fv) * ((1 - fu) * m->z[bin(n, u, v)] + fu * m->z[bin(n, u + 1, v)]) +
         fv * ((1 - fu) * m->z[bin(n, u, v + 1)] + fu * m->z[bin(n, u + 1, v + 1)]);
}

/* ---- a pattern's lattice ---- */

#define HARMONIC_REACH 2 /* cycles per yarn: the harmonics up to twice the yarn frequency */
#define MAX_POINTS 1024
typedef struct {
  int n;
  float u[MAX_POINTS], v[MAX_POINTS], w[MAX_POINTS]; /* cycles per yarn (u across columns, v down rows), weight */
  int n_base; /* the points up to the yarn frequency come first; the harmonics beyond follow */
} lmodel;

/* The reciprocal lattice of a weave up to twice the yarn frequency, in the half plane: the
 * repeat's Fourier coefficients |c(p, q)| of the 0/1 matrix (minus its mean) at
 * (p / cols + a, q / rows + b), and the yarn frequencies themselves, which every weave
 * shows through the yarns' shading. Weights fall off with frequency (the yarn's profile
 * is smooth); the strongest coefficient weighs 1. The points up to the yarn frequency come
 * first (n_base): they place the lattice and make its precision. The harmonics beyond
 * count for its recall only: at 1 to 2.5 pixels a yarn the pixel grid folds them back into
 * the band, where they are peaks of the weave (docs/analysis.md), but a camera's blur may
 * as well have taken them out. */
static void build_model(const wv_weave *w, lmodel *m) {
  int R = w->rows, C = w->cols;
  double mean = 0, amp[WV_WEAVE_MAX][WV_WEAVE_MAX], amax = 0;
  for (int i = 0; i < R; i++)
    for (int j = 0; j < C; j++) mean += w->p[i][j];
  mean /= R * C;
  for (int q = 0; q < R; q++)
    for (int p = 0; p < C; p++) {
      double re = 0, im = 0;
      for (int i = 0; i < R; i++)
        for (int j = 0; j < C; j++) {
          double ph = -2 * PI * ((double)p * j / C + (double)q * i / R);
          re += (w->p[i][j] - mean) * cos(ph), im += (w->p[i][j] - mean) * sin(ph);
        }
      amp[q][p] = sqrt(re * re + im * im);
      if (amp[q][p] > amax) amax = amp[q][p];
    }
  m->n = 0;
  for (int pass = 0; pass < 2; pass++) {
    for (int q = 0; q < R; q++)
      for (int p = 0; p < C; p++)
        for (int b = -HARMONIC_REACH; b <= HARMONIC_REACH; b++)
          for (int a = -HARMONIC_REACH; a <= HARMONIC_REACH; a++) {
            double u = (double)p / C + a, v = (double)q / R + b;
            if (fabs(u) > HARMONIC_REACH + 1e-9 || fabs(v) > HARMONIC_REACH + 1e-9) continue;
            if ((fabs(u) > 1 + 1e-9 || fabs(v) > 1 + 1e-9) != pass) continue;
            if (!(u > 1e-9 || (fabs(u) < 1e-9 && v > 1e-9))) continue; /* half plane, no DC */
            double wt;
            if (p == 0 && q == 0) /* a yarn frequency: (1, 0), (0, 1) and the diagonals */
              wt = YARN_W * (fabs(u) + fabs(v) < 1.5 ? 1.0 : 0.5);
            else
              wt = amax > 0 ? amp[q][p] / amax : 0;
            wt *= exp(-0.5 * (u * u + v * v));
            if (wt < 0.02 || m->n >= MAX_POINTS) continue;
            m->u[m->n] = (float)u, m->v[m->n] = (float)v, m->w[m->n] = (float)wt;
            m->n++;
          }
    if (!pass) m->n_base = m->n;
  }
}

/* Cells a row moves the pattern (row i + 1 = row i shifted right by s), the smallest in
 * magnitude; 0 when no shift does it or the shift has no direction (plain). */
static int row_shear(const wv_weave *w) {
  int R = w->rows, C = w->cols;
  for (int s = 1; s < C; s++) {
    int ok = 1;
    for (int i = 0; i < R && ok; i++)
      for (int j = 0; j < C && ok; j++) ok = w->p[(i + 1) % R][(j + s) % C] == w->p[i][j];
    if (ok) return 2 * s == C ? 0 : s <= C / 2 ? s : s - C;
  }
  return 0;
}

/* ---- scoring a hypothesis ---- */

typedef struct {
  double jt[2][2]; /* J^T: fabric mm per pixel, transposed (pixel frequency = J^T fabric frequency) */
} frame;

typedef struct {
  unsigned stamp;
  unsigned seen[WV_LATTICE_PEAKS];
} scratch;

/* A hypothesis: densities, the fabric's rotation rho and its skew sigma (radians): the
 * warp yarns turn by rho - sigma / 2, the weft yarns by rho + sigma / 2, so a cloth
 * laid slightly out of square still fits. */
typedef struct {
  double dw, df, rho, sigma;
} hyp;

static inline double sinc_abs(const smap *sm, double x) {
  x = fabs(x) * (SINC_N / SINC_MAX);
  return x >= SINC_N ? 0.0 : sm->sinc[(int)x];
}

/* The pixel frequency (cycles per pixel, not folded) of one cycle per yarn across the warp
 * (px) and down the rows (py) under hypothesis h: lattice point (u, v) lies at u px + v py. */
static void axes(const frame *fr, const hyp *h, double px[2], double py[2]) {
  double a = h->rho - 0.5 * h->sigma, b = h->rho + 0.5 * h->sigma;
  /* fabric frequencies (cycles per mm); rows run toward -y */
  double ex[2] = {cos(a) * h->dw / 25.4, sin(a) * h->dw / 25.4};
  double ey[2] = {sin(b) * h->df / 25.4, -cos(b) * h->df / 25.4};
  px[0] = fr->jt[0][0] * ex[0] + fr->jt[0][1] * ex[1], px[1] = fr->jt[1][0] * ex[0] + fr->jt[1][1] * ex[1];
  py[0] = fr->jt[0][0] * ey[0] + fr->jt[0][1] * ey[1], py[1] = fr->jt[1][0] * ey[0] + fr->jt[1][1] * ey[1];
}

/* F score of the lattice of m under hypothesis h against the spectrum map: precision =
 * weighted mean prominence (coarse: the dilated map; fine: bilinear) at the predicted
 * peaks up to the yarn frequency, recall = share of the photo's peak prominence within
 * reach of a predicted peak (with harm: of the harmonics too). */
static double evaluate(const lmodel *m, const smap *sm, const frame *fr, const hyp *h, int fine, int harm, scratch *sc,
                       double *prec, double *rec) {
  int n = sm->n;
  double px[2], py[2];
  axes(fr, h, px, py);
  double pw = 0, pz = 0, rz = 0;
  sc->stamp++;
  const signed char *id = fine ? sm->idf : sm->idc;
  for (int k = 0; k < (harm ? m->n : m->n_base); k++) {
    double kx = m->u[k] * px[0] + m->v[k] * py[0], ky = m->u[k] * px[1] + m->v[k] * py[1];
    /* a pixel integrates over its square: the yarns' contrast falls with frequency */
    double w = k < m->n_base ? m->w[k] * sinc_abs(sm, kx) * sinc_abs(sm, ky) : 0;
    kx -= floor(kx + 0.5), ky -= floor(ky + 0.5); /* folded into the pixel grid's band */
    double bu = kx * n, bv = ky * n;
    if (bu * bu + bv * bv <= WV_WSC_DC_RADIUS * WV_WSC_DC_RADIUS) continue; /* unobservable */
    int iu = (int)floor(bu + 0.5), iv = (int)floor(bv + 0.5);
    if (k < m->n_base) { /* the harmonics count for the recall alone */
      double z = fine ? z_at(sm, bu, bv) : sm->zc[bin(n, iu, iv)];
      pw += w, pz += w * z;
    }
    int p = id[bin(n, iu, iv)];
    if (p >= 0 && sc->seen[p] != sc->stamp) sc->seen[p] = sc->stamp, rz += sm->pk[p].z;
  }
  double P = pw > 0 ? pz / (pw * Z_CAP) : 0, R = sm->pk_total > 0 ? rz / sm->pk_total : 0;
  if (prec) *prec = P;
  if (rec) *rec = R;
  return P + R > 0 ? 2 * P * R / (P + R) : 0;
}

#define RHO_MAX (10 * PI / 180)
#define SIGMA_MAX (6 * PI / 180)

/* What a pattern search maximises over hypotheses. */
typedef struct {
  const lmodel *m;
  const frame *fr;
  const smap *sm;      /* the F score on the fine map (with sc) ... */
  scratch *sc;
  const float *logp;   /* ... or, when set, the mean log power at the points (n x n spectrum) */
  int n;
} objective;

/* Catmull-Rom weights of the four samples around fraction t. */
static inline void cubic_weights(double t, double w[4]) {
  double t2 = t * t, t3 = t2 * t;
  w[0] = 0.5 * (-t3 + 2 * t2 - t), w[1] = 0.5 * (3 * t3 - 5 * t2 + 2);
  w[2] = 0.5 * (-3 * t3 + 4 * t2 + t), w[3] = 0.5 * (t3 - t2);
}

/* The weighted mean of the log power spectrum, bicubic, at the lattice points of h: its
 * maximum puts the points on the peaks' tops within a fraction of a bin, where the F
 * score, whose prominence is capped, is flat (and a bilinear map peaks on the bins). */
static double lattice_power(const objective *o, const hyp *h) {
  const lmodel *m = o->m;
  int n = o->n;
  double px[2], py[2], sw = 0, s = 0;
  axes(o->fr, h, px, py);
  for (int k = 0; k < m->n_base; k++) {
    double kx = m->u[k] * px[0] + m->v[k] * py[0], ky = m->u[k] * px[1] + m->v[k] * py[1];
    kx -= floor(kx + 0.5), ky -= floor(ky + 0.5);
    double bu = kx * n, bv = ky * n;
    if (bu * bu + bv * bv <= WV_WSC_DC_RADIUS * WV_WSC_DC_RADIUS) continue;
    int u = (int)floor(bu), v = (int)floor(bv);
    double wu[4], wv[4], p = 0;
    cubic_weights(bu - u, wu), cubic_weights(bv - v, wv);
    for (int j = 0; j < 4; j++)
      for (int i = 0; i < 4; i++) p += wv[j] * wu[i] * o->logp[bin(n, u - 1 + i, v - 1 + j)];
    sw += m->w[k], s += m->w[k] * p;
  }
  return sw > 0 ? s / sw : 0;
}

static double objective_at(const objective *o, const hyp *h) {
  return o->logp ? lattice_power(o, h) : evaluate(o->m, o->sm, o->fr, h, 1, 0, o->sc, NULL, NULL);
}

/* Pattern search on (log dw, log df, rho, sigma) from h. */
static double refine(const objective *o, hyp *h) {
  const double lo = log(WV_DENSITY_MIN), hi = log(WV_DENSITY_MAX);
  double x[4] = {log(h->dw), log(h->df), h->rho, h->sigma};
  double step[4] = {0.006, 0.006, 0.6 * PI / 180, 0.6 * PI / 180};
  double best = objective_at(o, h);
  for (int it = 0; it < 400; it++) {
    int moved = 0;
    for (int d = 0; d < 4; d++)
      for (int sg = -1; sg <= 1; sg += 2) {
        double y[4] = {x[0], x[1], x[2], x[3]};
        y[d] += sg * step[d];
        if (y[0] < lo || y[0] > hi || y[1] < lo || y[1] > hi || fabs(y[2]) > RHO_MAX || fabs(y[3]) > SIGMA_MAX)
          continue;
        hyp t = {exp(y[0]), exp(y[1]), y[2], y[3]};
        double v = objective_at(o, &t);
        if (v > best + 1e-9) best = v, memcpy(x, y, sizeof x), moved = 1;
      }
    if (!moved) {
      if (step[0] < 0.0005) break;
      for (int d = 0; d < 4; d++) step[d] *= 0.5;
    }
  }
  *h = (hyp){exp(x[0]), exp(x[1]), x[2], x[3]};
  return best;
}

/* The coarse grid's orientations (rotation, skew): square and turned by 3 degrees, and
 * out of square by 3 degrees either way. */
#define N_ORIENT 5
static const double COARSE_ANG[N_ORIENT][2] = {
    {0, 0}, {-3 * PI / 180, 0}, {3 * PI / 180, 0}, {0, -3 * PI / 180}, {0, 3 * PI / 180}};

/* The best lattice of one pattern: a coarse grid over both densities (and N_ORIENT
 * orientations), its N_START best local maxima refined. */
static void fit_pattern(const lmodel *m, const smap *sm, const frame *fr, double *grid, int ng, wv_lattice_fit *out) {
  scratch sc;
  memset(&sc, 0, sizeof sc);
  double lstep = log(GRID_STEP), l0 = log(WV_DENSITY_MIN);
  for (int i = 0; i < ng; i++)
    for (int j = 0; j < ng; j++) {
      double best = 0;
      for (int r = 0; r < N_ORIENT; r++) {
        hyp h = {exp(l0 + i * lstep), exp(l0 + j * lstep), COARSE_ANG[r][0], COARSE_ANG[r][1]};
        double v = evaluate(m, sm, fr, &h, 0, 0, &sc, NULL, NULL);
        if (v > best) best = v;
      }
      grid[(size_t)i * ng + j] = best;
    }
  memset(out, 0, sizeof *out);
  double best_f = -1;
  for (int s = 0; s < N_START; s++) {
    int bi = -1, bj = -1;
    double bv = 1e-9;
    for (int i = 0; i < ng; i++)
      for (int j = 0; j < ng; j++)
        if (grid[(size_t)i * ng + j] > bv) bv = grid[(size_t)i * ng + j], bi = i, bj = j;
    if (bi < 0) break;
    for (int i = bi - 3; i <= bi + 3; i++) /* the next start lies elsewhere */
      for (int j = bj - 3; j <= bj + 3; j++)
        if (i >= 0 && j >= 0 && i < ng && j < ng) grid[(size_t)i * ng + j] = 0;
    hyp h = {exp(l0 + bi * lstep), exp(l0 + bj * lstep), 0, 0}, hb = h;
    double r0 = -1;
    for (int r = 0; r < N_ORIENT; r++) { /* the orientation the grid point scored best with */
      h.rho = COARSE_ANG[r][0], h.sigma = COARSE_ANG[r][1];
      double v = evaluate(m, sm, fr, &h, 0, 0, &sc, NULL, NULL);
      if (v > r0) r0 = v, hb = h;
    }
    /* placed and compared by the points up to the yarn frequency: with the harmonics an
     * irregular cloth's density drifts, and the lattice at half a density, whose harmonics
     * hold the whole lattice, can win; the score reported counts the harmonics */
    objective ob = {m, fr, sm, &sc, NULL, 0};
    double f = refine(&ob, &hb);
    if (f > best_f) {
      best_f = f;
      out->density[WV_WARP] = hb.dw, out->density[WV_WEFT] = hb.df;
      out->angle_deg = hb.rho * 180 / PI, out->skew_deg = hb.sigma * 180 / PI;
      out->score = evaluate(m, sm, fr, &hb, 1, 1, &sc, &out->precision, &out->recall);
    }
  }
}

/* A built-in whose yarns lie in groups (a basket) and its twin that weaves as the groups
 * (plain, wv_weave_builtin_twin) have one lattice when the first's densities are the
 * groups' times the twin's: they differ only in which of its points each counts up to its
 * yarn frequency, so which fits better tells the camera's blur, not the weave. Left to
 * itself the weaker one's search can settle elsewhere, and its render, ranked against the
 * photo, then shows a cloth the photo is not; it takes the stronger one's lattice, scaled
 * by the groups, and its own score there (the family step weighs both alike). */
static void share_twins(const lmodel *models, const smap *sm, const frame *fr, wv_lattice *out) {
  scratch sc;
  memset(&sc, 0, sizeof sc);
  int g[2];
  for (int k = 0; k < wv_weave_builtin_count(); k++) {
    int t = wv_weave_builtin_twin(k, g);
    if (t < 0 || out->fit[k].score == out->fit[t].score) continue;
    int weak = out->fit[k].score < out->fit[t].score ? k : t;
    const wv_lattice_fit *strong = &out->fit[weak == k ? t : k];
    double s = weak == k ? 1.0 : -1.0; /* the groups' factor, toward the weaker */
    hyp h = {strong->density[WV_WARP] * pow(g[0], s), strong->density[WV_WEFT] * pow(g[1], s),
             strong->angle_deg * PI / 180, strong->skew_deg * PI / 180};
    wv_lattice_fit f = {.density = {h.dw, h.df}, .angle_deg = strong->angle_deg, .skew_deg = strong->skew_deg};
    f.score = evaluate(&models[weak], sm, fr, &h, 1, 1, &sc, &f.precision, &f.recall);
    out->fit[weak] = f;
  }
}

/* The scene's map pixel -> fabric mm at the image centre, transposed. */
static int centre_frame(const wv_scene *s, frame *fr, double *mm_per_px) {
  return wv_render_centre_scale(s, fr->jt, mm_per_px);
}

static int window_side(const wv_image *img) {
  int n = img->w < img->h ? img->w : img->h;
  if (n > WV_LATTICE_WINDOW) n = WV_LATTICE_WINDOW;
  return n - n % 2;
}

wv_status wv_lattice_analyse(const wv_scene *s, const wv_image *photo, wv_lattice *out, wv_error *err) {
  double t0 = omp_get_wtime();
  memset(out, 0, sizeof *out);
  out->best = -1;
  int n = window_side(photo);
  out->window = n;
  if (n < WV_LATTICE_MIN_WINDOW) {
    snprintf(out->reason, sizeof out->reason, "the image (%d x %d) is too small for the weave analysis (at least %d x %d)",
             photo->w, photo->h, WV_LATTICE_MIN_WINDOW, WV_LATTICE_MIN_WINDOW);
    return WV_OK;
  }
  frame fr;
  if (!centre_frame(s, &fr, &out->mm_per_px)) {
    snprintf(out->reason, sizeof out->reason, "the scene's image centre does not see the sample");
    return WV_OK;
  }
  float *spec = malloc(sizeof(float) * (size_t)n * n);
  if (!spec) return wv_fail(err, WV_ERR_NOMEM, "out of memory for the weave analysis");
  wv_status st = wv_weave_spectrum(photo, (photo->w - n) / 2, (photo->h - n) / 2, n, spec, err);
  smap sm = {0};
  if (!st) st = smap_init(&sm, spec, n, err);
  free(spec);
  if (st) return st;
  out->n_peaks = sm.np;
  memcpy(out->peaks, sm.pk, sizeof(wv_spectral_peak) * (size_t)sm.np);
  if (sm.np < 2) {
    snprintf(out->reason, sizeof out->reason,
             "no weave lattice: %s in the spectrum of the image's detail (a weave shows at least two)",
             sm.np ? "one peak" : "no peak");
    smap_free(&sm);
    out->seconds = omp_get_wtime() - t0;
    return WV_OK;
  }
  int nb = wv_weave_builtin_count();
  const int ng = (int)floor(log(WV_DENSITY_MAX / WV_DENSITY_MIN) / log(GRID_STEP)) + 1;
  int threads = omp_get_max_threads();
  double *grids = malloc(sizeof(double) * (size_t)ng * ng * (size_t)threads);
  if (!grids) {
    smap_free(&sm);
    return wv_fail(err, WV_ERR_NOMEM, "out of memory for the weave analysis");
  }
  /* A pattern and its 90-degree variant often have the same lattice and weights (a
   * twill's transpose is a twill of the same direction): such a model is fitted once. */
  lmodel *models = malloc(sizeof(lmodel) * (size_t)nb);
  int same[WV_WEAVE_BUILTINS];
  if (!models) {
    free(grids), smap_free(&sm);
    return wv_fail(err, WV_ERR_NOMEM, "out of memory for the weave analysis");
  }
  for (int i = 0; i < nb; i++) {
    wv_weave w;
    wv_weave_builtin(wv_weave_builtin_name(i), &w, NULL);
    build_model(&w, &models[i]);
    same[i] = i;
    for (int j = 0; j < i && same[i] == i; j++)
      if (models[j].n == models[i].n && !memcmp(models[j].u, models[i].u, sizeof(float) * (size_t)models[i].n) &&
          !memcmp(models[j].v, models[i].v, sizeof(float) * (size_t)models[i].n) &&
          !memcmp(models[j].w, models[i].w, sizeof(float) * (size_t)models[i].n))
        same[i] = j;
  }
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
  for (int i = 0; i < nb; i++)
    if (same[i] == i)
      fit_pattern(&models[i], &sm, &fr, grids + (size_t)ng * ng * (size_t)omp_get_thread_num(), ng, &out->fit[i]);
  for (int i = 0; i < nb; i++) out->fit[i] = out->fit[same[i]];
  share_twins(models, &sm, &fr, out);
  free(grids), free(models);
  smap_free(&sm);
  int best = 0;
  for (int i = 1; i < nb; i++)
    if (out->fit[i].score > out->fit[best].score) best = i;
  if (out->fit[best].score < WV_LATTICE_MIN_SCORE) {
    snprintf(out->reason, sizeof out->reason,
             "no weave lattice: the best built-in lattice (%s) explains the spectrum's %d peaks with score %.2f, "
             "below %.2f", wv_weave_builtin_name(best), out->n_peaks, out->fit[best].score, WV_LATTICE_MIN_SCORE);
  } else {
    out->found = 1, out->best = best;
    wv_weave w;
    wv_weave_builtin(wv_weave_builtin_name(best), &w, NULL);
    out->repeat = w.rows > w.cols ? w.rows : w.cols;
    out->shear = row_shear(&w);
    for (int y = 0; y < 2; y++) out->spacing_px[y] = 25.4 / (out->fit[best].density[y] * out->mm_per_px);
  }
  out->seconds = omp_get_wtime() - t0;
  return WV_OK;
}

/* ---- the chosen lattice over the whole image ---- */

/* Pattern i's lattice power climbed from h over the photo's n x n centre window; *before
 * and *after the power at h and at the climbed hypothesis (which h becomes). */
static wv_status climb(const wv_image *photo, int n, int i, const frame *fr, hyp *h, double *before, double *after,
                       wv_error *err) {
  float *spec = malloc(sizeof(float) * (size_t)n * n);
  if (!spec) return wv_fail(err, WV_ERR_NOMEM, "out of memory for the weave analysis");
  wv_status st = wv_weave_spectrum(photo, (photo->w - n) / 2, (photo->h - n) / 2, n, spec, err);
  if (!st) {
    wv_weave w;
    lmodel m;
    wv_weave_builtin(wv_weave_builtin_name(i), &w, NULL);
    build_model(&w, &m);
    objective ob = {&m, fr, NULL, NULL, spec, n};
    *before = objective_at(&ob, h), *after = refine(&ob, h);
  }
  free(spec);
  return st;
}

static int refine_side(const wv_image *photo) {
  int n = photo->w < photo->h ? photo->w : photo->h;
  return n > WV_LATTICE_REFINE_WINDOW ? WV_LATTICE_REFINE_WINDOW : n - n % 2;
}

wv_status wv_lattice_refine(const wv_scene *s, const wv_image *photo, wv_lattice *lat, int i, wv_error *err) {
  int n = refine_side(photo);
  frame fr;
  double mmpp, before = 0, after = 0;
  if (!lat->found || i < 0 || i >= wv_weave_builtin_count() || n <= lat->window || !centre_frame(s, &fr, &mmpp))
    return WV_OK;
  wv_lattice_fit *f = &lat->fit[i];
  hyp h = {f->density[WV_WARP], f->density[WV_WEFT], f->angle_deg * PI / 180, f->skew_deg * PI / 180}, r = h;
  wv_status st = climb(photo, n, i, &fr, &r, &before, &after, err);
  if (st) return st;
  lat->refined_window = n;
  /* a step to a neighbouring alias is not a refinement: the densities may move by 2% */
  if (after > before && fabs(log(r.dw / h.dw)) < 0.02 && fabs(log(r.df / h.df)) < 0.02) {
    f->density[WV_WARP] = r.dw, f->density[WV_WEFT] = r.df;
    f->angle_deg = r.rho * 180 / PI, f->skew_deg = r.sigma * 180 / PI;
    if (i == lat->best)
      for (int y = 0; y < 2; y++) lat->spacing_px[y] = 25.4 / (f->density[y] * lat->mm_per_px);
  }
  return WV_OK;
}

/* The search's neighbourhood of a start: densities within WV_LATTICE_NEAR in NEAR_STEPS
 * steps either way, rotation and skew within NEAR_ANG degrees in NEAR_ANG_STEPS steps. */
#define NEAR_STEPS 10
#define NEAR_ANG 3.0
#define NEAR_ANG_STEPS 3

wv_status wv_lattice_refine_from(const wv_scene *s, const wv_image *photo, int i, const double density[2],
                                 wv_lattice_fit *out, int *moved, wv_error *err) {
  *moved = 0;
  memset(out, 0, sizeof *out);
  out->density[WV_WARP] = density[WV_WARP], out->density[WV_WEFT] = density[WV_WEFT];
  int side[2] = {window_side(photo), refine_side(photo)};
  frame fr;
  double mmpp;
  if (i < 0 || i >= wv_weave_builtin_count() || side[0] < WV_LATTICE_MIN_WINDOW || !centre_frame(s, &fr, &mmpp) ||
      !(density[0] > 0) || !(density[1] > 0))
    return WV_OK;
  const hyp h = {density[WV_WARP], density[WV_WEFT], 0, 0};
  hyp r = h;
  wv_weave w;
  lmodel m;
  wv_weave_builtin(wv_weave_builtin_name(i), &w, NULL);
  build_model(&w, &m);
  float *spec = malloc(sizeof(float) * (size_t)side[1] * side[1]);
  if (!spec) return wv_fail(err, WV_ERR_NOMEM, "out of memory for the weave analysis");
  /* A start a few percent off lies beyond the reach of a climb (the peaks are a bin or two
   * wide): the neighbourhood is searched on a grid over the analysis window first, then
   * climbed over it and over the refinement window, which judges. */
  wv_status st = wv_weave_spectrum(photo, (photo->w - side[0]) / 2, (photo->h - side[0]) / 2, side[0], spec, err);
  double before = 0, after = 0;
  if (!st) {
    objective ob = {&m, &fr, NULL, NULL, spec, side[0]};
    double best = -1e300, ld = WV_LATTICE_NEAR / NEAR_STEPS, la = NEAR_ANG / NEAR_ANG_STEPS * PI / 180;
    for (int a = -NEAR_STEPS; a <= NEAR_STEPS; a++)
      for (int c = -NEAR_STEPS; c <= NEAR_STEPS; c++)
        for (int q = -NEAR_ANG_STEPS; q <= NEAR_ANG_STEPS; q++)
          for (int k = -NEAR_ANG_STEPS; k <= NEAR_ANG_STEPS; k++) {
            hyp t = {h.dw * exp(a * ld), h.df * exp(c * ld), q * la, k * la};
            double v = lattice_power(&ob, &t);
            if (v > best) best = v, r = t;
          }
    refine(&ob, &r);
    if (side[1] > side[0]) /* the refinement window is never the smaller */
      st = wv_weave_spectrum(photo, (photo->w - side[1]) / 2, (photo->h - side[1]) / 2, side[1], spec, err);
    if (!st) {
      objective ob1 = {&m, &fr, NULL, NULL, spec, side[1]};
      before = objective_at(&ob1, &h), after = refine(&ob1, &r);
    }
  }
  free(spec);
  if (st) return st;
  /* a move this far is an alias or a walk among weak peaks, not a refinement */
  if (!(after > before) || fabs(log(r.dw / h.dw)) >= WV_LATTICE_NEAR || fabs(log(r.df / h.df)) >= WV_LATTICE_NEAR)
    return WV_OK;
  out->density[WV_WARP] = r.dw, out->density[WV_WEFT] = r.df;
  out->angle_deg = r.rho * 180 / PI, out->skew_deg = r.sigma * 180 / PI;
  *moved = 1;
  return WV_OK;
}

/* ---- ranking by the candidates' own renders ---- */

void wv_rank_opts_default(wv_rank_opts *o) {
  memset(o, 0, sizeof *o);
  o->spp = WV_RANK_SPP;
  o->rotate = 1;
  o->w_prob = 0.25;
}

void wv_lattice_fit_apply(const wv_lattice_fit *f, const wv_params *base, const wv_scene *s, int rotate, wv_params *p,
                          wv_scene *ps) {
  *p = *base;
  for (int y = 0; y < 2; y++) {
    double d = f->density[y];
    p->density[y] = d < WV_DENSITY_MIN ? WV_DENSITY_MIN : d > WV_DENSITY_MAX ? WV_DENSITY_MAX : d;
  }
  *ps = *s;
  if (!rotate || s->shape != WV_SHAPE_PLANE) return;
  double r = s->rotation_deg + f->angle_deg, k = s->skew_deg + f->skew_deg;
  ps->rotation_deg = r > 360 ? r - 360 : r < -360 ? r + 360 : r;
  ps->skew_deg = k > WV_SCENE_MAX_SKEW ? WV_SCENE_MAX_SKEW : k < -WV_SCENE_MAX_SKEW ? -WV_SCENE_MAX_SKEW : k;
}

void wv_lattice_candidate(const wv_lattice *lat, int i, const wv_params *base, const wv_scene *s, int rotate,
                          wv_params *p, wv_scene *ps) {
  wv_lattice_fit_apply(&lat->fit[i], base, s, rotate, p, ps);
  snprintf(p->pattern, sizeof p->pattern, "%s", wv_weave_builtin_name(i));
  p->custom_rows = 0;
}

/* How well two peak lists agree: recall over a's prominence, precision over b's, their F. */
static double peak_match(const wv_spectral_peak *a, int na, const wv_spectral_peak *b, int nb, int n) {
  double ra = 0, ta = 0, pb = 0, tb = 0, r2 = MATCH_RAD * MATCH_RAD / ((double)n * n);
  for (int pass = 0; pass < 2; pass++) {
    const wv_spectral_peak *x = pass ? b : a, *y = pass ? a : b;
    int nx = pass ? nb : na, ny = pass ? na : nb;
    for (int i = 0; i < nx; i++) {
      int hit = 0;
      for (int j = 0; j < ny && !hit; j++)
        for (int sg = -1; sg <= 1 && !hit; sg += 2) {
          double du = x[i].u - sg * y[j].u, dv = x[i].v - sg * y[j].v;
          du -= floor(du + 0.5), dv -= floor(dv + 0.5);
          hit = du * du + dv * dv <= r2;
        }
      if (pass) pb += hit * x[i].z, tb += x[i].z;
      else ra += hit * x[i].z, ta += x[i].z;
    }
  }
  double R = ta > 0 ? ra / ta : 0, P = tb > 0 ? pb / tb : 0;
  return P + R > 0 ? 2 * P * R / (P + R) : 0;
}

/* The photo's peaks as the square cloth of fit i (its skew taken out, which a cylinder
 * scene cannot draw) would show them: a peak near a predicted lattice point moves with it to
 * where that point lies without the skew. */
static void deskew_peaks(const wv_lattice *lat, int i, const frame *fr, wv_spectral_peak *out) {
  const wv_lattice_fit *f = &lat->fit[i];
  hyp h = {f->density[0], f->density[1], f->angle_deg * PI / 180, f->skew_deg * PI / 180}, h0 = h;
  h0.sigma = 0;
  double px[2], py[2], qx[2], qy[2], tol = (MATCH_RAD / lat->window) * (MATCH_RAD / lat->window);
  axes(fr, &h, px, py);
  axes(fr, &h0, qx, qy);
  wv_weave w;
  lmodel m;
  wv_weave_builtin(wv_weave_builtin_name(i), &w, NULL);
  build_model(&w, &m);
  for (int p = 0; p < lat->n_peaks; p++) {
    out[p] = lat->peaks[p];
    double best = tol;
    for (int k = 0; k < m.n_base; k++)
      for (int sg = -1; sg <= 1; sg += 2) {
        double kx = sg * (m.u[k] * px[0] + m.v[k] * py[0]), ky = sg * (m.u[k] * px[1] + m.v[k] * py[1]);
        double dx = lat->peaks[p].u - kx, dy = lat->peaks[p].v - ky;
        dx -= floor(dx + 0.5), dy -= floor(dy + 0.5);
        if (dx * dx + dy * dy >= best) continue;
        best = dx * dx + dy * dy;
        double nx = sg * (m.u[k] * qx[0] + m.v[k] * qy[0]) + dx, ny = sg * (m.u[k] * qx[1] + m.v[k] * qy[1]) + dy;
        out[p].u = nx - floor(nx + 0.5), out[p].v = ny - floor(ny + 0.5);
      }
  }
}

/* p rendered in the n x n centre window of s at spp (0: WV_RANK_SPP): its weave spectrum sr,
 * whitened zr (n x n each), and its peaks pk (*np of them, at most WV_LATTICE_PEAKS). */
static wv_status render_peaks(const wv_scene *s, const wv_params *p, int n, int spp, int threads, float *sr,
                              float *zr, wv_spectral_peak *pk, int *np, wv_error *err) {
  wv_scene win;
  wv_scene_centre_window(s, n, n, &win);
  win.spp = spp > 0 ? spp : WV_RANK_SPP;
  wv_render_opts ro = {.spp = win.spp, .threads = threads};
  wv_image img = {0};
  wv_status st = wv_render(&win, p, &ro, &img, NULL, err);
  if (!st) st = wv_weave_spectrum(&img, 0, 0, n, sr, err);
  if (!st) st = wv_spectrum_whiten(sr, n, WV_WSC_Z_FLOOR, WV_WSC_Z_CAP, zr, err);
  wv_image_free(&img);
  if (!st) *np = wv_spectrum_peaks(sr, n, Z_PEAK, pk, WV_LATTICE_PEAKS);
  return st;
}

wv_status wv_lattice_match(const wv_scene *s, const wv_lattice *lat, const wv_params *p, int spp, int threads,
                           double *match, wv_error *err) {
  *match = 0;
  int n = lat->window;
  if (n < 1) return wv_fail(err, WV_ERR_INVALID, "the weave analysis has no window to match a render in");
  size_t nn = (size_t)n * n;
  float *sr = malloc(sizeof(float) * nn * 2);
  if (!sr) return wv_fail(err, WV_ERR_NOMEM, "out of memory for the peak match");
  wv_spectral_peak pk[WV_LATTICE_PEAKS];
  int np = 0;
  wv_status st = render_peaks(s, p, n, spp, threads, sr, sr + nn, pk, &np, err);
  if (!st) *match = peak_match(lat->peaks, lat->n_peaks, pk, np, n);
  free(sr);
  return st;
}

wv_status wv_lattice_rank(const wv_scene *s, const wv_image *photo, const wv_lattice *lat, const wv_params *base,
                          const wv_rank_opts *o, wv_lattice_ranking *out, wv_error *err) {
  double t0 = omp_get_wtime();
  memset(out, 0, sizeof *out);
  wv_rank_opts def;
  wv_rank_opts_default(&def);
  if (!o) o = &def;
  if (!lat->found) return wv_fail(err, WV_ERR_INVALID, "the weave analysis found no lattice to rank patterns by");
  if (photo->w != s->width || photo->h != s->height)
    return wv_fail(err, WV_ERR_INVALID, "the photo is %d x %d but the scene renders %d x %d", photo->w, photo->h,
                   s->width, s->height);
  int n = lat->window, nb = wv_weave_builtin_count();
  frame fr;
  double mmpp;
  if (!centre_frame(s, &fr, &mmpp))
    return wv_fail(err, WV_ERR_INVALID, "the scene's image centre does not see the sample");
  size_t nn = (size_t)n * n;
  float *sp = malloc(sizeof(float) * nn * 4), *sr = sp ? sp + nn : NULL, *zp = sp ? sp + 2 * nn : NULL,
        *zr = sp ? sp + 3 * nn : NULL;
  if (!sp) return wv_fail(err, WV_ERR_NOMEM, "out of memory for the pattern ranking");
  wv_status st = wv_weave_spectrum(photo, (photo->w - n) / 2, (photo->h - n) / 2, n, sp, err);
  if (!st) st = wv_spectrum_whiten(sp, n, WV_WSC_Z_FLOOR, WV_WSC_Z_CAP, zp, err);
  for (int i = 0; i < nb && !st; i++) {
    wv_params p;
    wv_scene ps;
    wv_lattice_candidate(lat, i, base, s, o->rotate, &p, &ps);
    wv_spectral_peak pk[WV_LATTICE_PEAKS];
    int np = 0;
    if ((st = render_peaks(&ps, &p, n, o->spp, o->threads, sr, zr, pk, &np, err))) break;
    /* a render without the lattice's skew is compared with the photo's peaks as its
     * square cloth would show them */
    wv_spectral_peak square[WV_LATTICE_PEAKS];
    const wv_spectral_peak *ref = lat->peaks;
    if (!(ps.shape == WV_SHAPE_PLANE && o->rotate)) deskew_peaks(lat, i, &fr, square), ref = square;
    out->match[i] = peak_match(ref, lat->n_peaks, pk, np, n);
    out->wsc[i] = wv_wsc_spectra(sp, sr, n);
    out->wsc_whitened[i] = wv_wsc_spectra(zp, zr, n);
    out->score[i] = out->match[i];
    if (o->prob) out->score[i] = (1 - o->w_prob) * out->score[i] + o->w_prob * o->prob[i];
  }
  free(sp);
  if (st) return st;
  for (int i = 0; i < nb; i++) out->order[i] = i;
  for (int i = 1; i < nb; i++) /* insertion sort, best first; ties keep the library order */
    for (int j = i; j > 0 && out->score[out->order[j]] > out->score[out->order[j - 1]]; j--) {
      int t = out->order[j];
      out->order[j] = out->order[j - 1], out->order[j - 1] = t;
    }
  out->best = out->order[0];
  out->seconds = omp_get_wtime() - t0;
  return WV_OK;
}

/* ---- records ---- */

char *wv_lattice_to_json(const wv_lattice *l, const wv_lattice_ranking *r) {
  json_t *o = json_object();
  json_object_set_new(o, "found", json_boolean(l->found));
  json_object_set_new(o, "reason", l->found ? json_null() : json_string(l->reason));
  json_object_set_new(o, "window", json_integer(l->window));
  if (l->refined_window) json_object_set_new(o, "refined_window", json_integer(l->refined_window));
  json_object_set_new(o, "mm_per_px", json_real(l->mm_per_px));
  json_t *pk = json_array();
  for (int i = 0; i < l->n_peaks; i++)
    json_array_append_new(pk, json_pack("[f,f,f]", l->peaks[i].u, l->peaks[i].v, l->peaks[i].z));
  json_object_set_new(o, "peaks_cycles_per_px_and_z", pk);
  if (l->found) {
    const wv_lattice_fit *f = &l->fit[l->best];
    const char *name = wv_weave_builtin_name(l->best);
    json_object_set_new(o, "best", json_string(name));
    json_object_set_new(o, "family", json_string(wv_weave_family(name)));
    json_object_set_new(o, "density", json_pack("{s:f,s:f}", "warp", f->density[WV_WARP], "weft", f->density[WV_WEFT]));
    json_object_set_new(o, "angle_deg", json_real(f->angle_deg));
    json_object_set_new(o, "skew_deg", json_real(f->skew_deg));
    json_object_set_new(o, "spacing_px", json_pack("[f,f]", l->spacing_px[0], l->spacing_px[1]));
    json_object_set_new(o, "repeat", json_integer(l->repeat));
    json_object_set_new(o, "shear", json_integer(l->shear));
  }
  json_object_set_new(o, "seconds", json_real(l->seconds));
  json_t *fits = json_object();
  for (int i = 0; i < wv_weave_builtin_count() && l->n_peaks >= 2; i++) {
    const wv_lattice_fit *f = &l->fit[i];
    json_object_set_new(fits, wv_weave_builtin_name(i),
                        json_pack("{s:[f,f],s:f,s:f,s:f,s:f,s:f}", "density", f->density[0], f->density[1],
                                  "angle_deg", f->angle_deg, "skew_deg", f->skew_deg, "score", f->score, "precision",
                                  f->precision, "recall", f->recall));
  }
  json_object_set_new(o, "fits", fits);
  if (r) {
    json_t *rk = json_object();
    for (int k = 0; k < wv_weave_builtin_count(); k++) {
      int i = r->order[k];
      json_object_set_new(rk, wv_weave_builtin_name(i),
                          json_pack("{s:f,s:f,s:f,s:f}", "match", r->match[i], "wsc", r->wsc[i], "wsc_whitened",
                                    r->wsc_whitened[i], "score", r->score[i]));
    }
    json_object_set_new(o, "ranking", rk);
    json_object_set_new(o, "ranking_seconds", json_real(r->seconds));
  }
  char *s = json_dumps(o, JSON_PRESERVE_ORDER | JSON_REAL_PRECISION(6));
  json_decref(o);
  return s;
}

/* ---- pictures ---- */

wv_status wv_spectrum_picture(const float *const *spectra, int k, int n, int zoom, wv_image *out, wv_error *err) {
  const int gap = 4;
  if (k < 1 || n < 2 || zoom < 1) return wv_fail(err, WV_ERR_INVALID, "spectrum picture: nothing to draw");
  int side = n * zoom;
  wv_status st = wv_image_alloc(out, k * side + (k - 1) * gap, side, 3, err);
  if (st) return st;
  for (size_t i = 0; i < (size_t)out->w * out->h * 3; i++) out->data[i] = 1.0f;
  float *tmp = malloc(sizeof(float) * (size_t)n * n);
  if (!tmp) {
    wv_image_free(out);
    return wv_fail(err, WV_ERR_NOMEM, "out of memory for a spectrum picture");
  }
  for (int s = 0; s < k; s++) {
    /* each spectrum from its median (black) to its 99.9th percentile (white) */
    memcpy(tmp, spectra[s], sizeof(float) * (size_t)n * n);
    float lo = wv_select_float(tmp, (size_t)n * n, (size_t)n * n / 2);
    float hi = wv_select_float(tmp, (size_t)n * n, (size_t)((double)n * n * 0.999));
    float sc = hi > lo ? 1.0f / (hi - lo) : 0.0f;
    for (int y = 0; y < side; y++)
      for (int x = 0; x < side; x++) {
        float v = (spectra[s][(size_t)(y / zoom) * n + x / zoom] - lo) * sc;
        v = v < 0 ? 0 : v > 1 ? 1 : v;
        float *px = wv_image_px(out, s * (side + gap) + x, y);
        px[0] = px[1] = px[2] = v;
      }
  }
  free(tmp);
  return WV_OK;
}
