/* The cloth's distortion: a smooth displacement of the fabric coordinates that keeps a
 * registered render in register across the whole photo of a plane sample. See
 * wv_fit_distort in fit.h for why; docs/fit.md for what it measured. */
#include <fftw3.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "util/linalg.h"
#include "woven/fit.h"
#include "woven/metrics.h"
#include "woven/render.h"

static const double PI = 3.14159265358979323846;

#define N_FREQ 10       /* the weave frequencies the photo and the render share most */
#define DC_BINS 6.0     /* ... farther than this from DC (bins of the whole image) */
#define LP_SIGMA 16.0   /* px: the low-pass that reads each frequency's local phase */
#define STEP 8          /* px between the points read */
#define EPS_MM 0.01     /* the offset whose renders give each frequency's fabric frequency */
#define SPP 16          /* the renders' samples per pixel (the low-pass averages their noise) */
#define ITERS 8         /* Gauss-Newton steps per degree */
#define PASSES 2        /* estimates, each from the render of the one before */
#define N_COEF (WV_DISTORT_TERMS + 1) /* with the constant (an offset) */

/* The luminance detail of a whole image, standardised, without a window (the corners
 * count as much as the centre here). */
static wv_status detail(const wv_image *img, float *out, wv_error *err) {
  return wv_image_detail_window(img, 0, 0, img->w, img->h, 0, out, err);
}

/* One frequency (cycles per pixel) read at every point of the grid: the detail times
 * exp(-2 pi i k . x), low-passed (a Gaussian of LP_SIGMA, its weights renormalised at
 * the edges), the vertical pass on the grid's rows only. z: gw * gh complex (re, im). */
static void demodulate(const float *d, int w, int h, const double k[2], const double *g, int r, int gw, int gh,
                       double *col, double *ex, double *z) {
  for (int x = 0; x < w; x++) ex[2 * x] = cos(-2 * PI * k[0] * x), ex[2 * x + 1] = sin(-2 * PI * k[0] * x);
  for (int j = 0; j < gh; j++) {
    int yc = STEP / 2 + j * STEP;
    for (int x = 0; x < w; x++) col[2 * x] = col[2 * x + 1] = 0;
    for (int y = yc - r; y <= yc + r; y++) {
      if (y < 0 || y >= h) continue;
      /* exp(-2 pi i k . x) = ex(x) ey(y), ey(y) with the tap's weight */
      double ph = -2 * PI * k[1] * y, wy = g[y - yc + r], er = wy * cos(ph), ei = wy * sin(ph);
      const float *row = d + (size_t)y * w;
      for (int x = 0; x < w; x++) {
        double v = row[x];
        col[2 * x] += v * (ex[2 * x] * er - ex[2 * x + 1] * ei);
        col[2 * x + 1] += v * (ex[2 * x] * ei + ex[2 * x + 1] * er);
      }
    }
    for (int i = 0; i < gw; i++) {
      int xc = STEP / 2 + i * STEP;
      double re = 0, im = 0;
      for (int x = xc - r; x <= xc + r; x++) {
        if (x < 0 || x >= w) continue;
        re += g[x - xc + r] * col[2 * x], im += g[x - xc + r] * col[2 * x + 1];
      }
      z[2 * ((size_t)j * gw + i)] = re, z[2 * ((size_t)j * gw + i) + 1] = im;
    }
  }
}

/* The N_FREQ strongest local maxima (7 x 7 bins) of |P conj(R)|, the cross power of the
 * windowed details of photo and render, in the half plane u >= 0; returns how many (-1:
 * out of memory, err filled). */
static int shared_peaks(const float *wp, const float *wr, int w, int h, double (*k)[2], wv_error *err) {
  int nc = w / 2 + 1, n = 0;
  float *a = fftwf_alloc_real((size_t)w * h);
  fftwf_complex *fp = fftwf_alloc_complex((size_t)h * nc), *fr = fftwf_alloc_complex((size_t)h * nc);
  float *cp = malloc(sizeof(float) * (size_t)h * nc);
  fftwf_plan plan = NULL;
  if (a && fp && fr && cp) {
#pragma omp critical(wv_fftw_planner)
    plan = fftwf_plan_dft_r2c_2d(h, w, a, fp, FFTW_ESTIMATE);
  }
  if (!plan) {
    n = -1;
    wv_fail(err, WV_ERR_NOMEM, "out of memory for the distortion's spectrum (%d x %d)", w, h);
  } else {
    memcpy(a, wp, sizeof(float) * (size_t)w * h);
    fftwf_execute_dft_r2c(plan, a, fp);
    memcpy(a, wr, sizeof(float) * (size_t)w * h);
    fftwf_execute_dft_r2c(plan, a, fr);
    for (size_t i = 0; i < (size_t)h * nc; i++)
      cp[i] = hypotf(fp[i][0], fp[i][1]) * hypotf(fr[i][0], fr[i][1]);
    double best[N_FREQ];
    for (int v = 0; v < h; v++)
      for (int u = 0; u < nc; u++) {
        int vs = v < h / 2 ? v : v - h;
        if (u == 0 && vs < 0) continue; /* the mirror of u = 0, v > 0 */
        double fu = (double)u / w, fv = (double)vs / h, m = w < h ? w : h;
        if (hypot(fu, fv) * m <= DC_BINS) continue;
        float c = cp[(size_t)v * nc + u];
        int is_max = 1;
        for (int dv = -3; dv <= 3 && is_max; dv++)
          for (int du = -3; du <= 3; du++) {
            int uu = u + du, vv = ((v + dv) % h + h) % h;
            if ((du || dv) && uu >= 0 && uu < nc && cp[(size_t)vv * nc + uu] > c) {
              is_max = 0;
              break;
            }
          }
        if (!is_max) continue;
        int at = n < N_FREQ ? n++ : N_FREQ; /* insertion into the sorted list */
        while (at > 0 && best[at - 1] < c) {
          if (at < N_FREQ) best[at] = best[at - 1], k[at][0] = k[at - 1][0], k[at][1] = k[at - 1][1];
          at--;
        }
        if (at < N_FREQ) best[at] = c, k[at][0] = fu, k[at][1] = fv;
      }
  }
#pragma omp critical(wv_fftw_planner)
  if (plan) fftwf_destroy_plan(plan);
  fftwf_free(a), fftwf_free(fp), fftwf_free(fr), free(cp);
  return n;
}

/* Everything one estimate reads: per frequency its fabric frequency g (cycles per mm of
 * fabric x and y) and, at each grid point, c = photo conj(render) (its phase is how far
 * the render's weave is behind the photo's there), and the points' terms. */
typedef struct {
  int nf, np;
  double g[N_FREQ][2];
  double *c;     /* nf * np complex */
  const double *basis; /* np * N_COEF: 1 and the distortion's terms */
} phase_data;

/* The displacement's Gauss-Newton fit: theta[k][0..n-1] (k = fabric x, y) maximising
 * sum over frequencies and points of Re(c exp(-2 pi i g . delta)), delta = basis . theta:
 * each step solves the weighted least squares of the phases left over, wrapped into
 * half a cycle, so the fit follows the weave from where it lines up. */
static void fit_phases(const phase_data *pd, int n, double theta[2][N_COEF]) {
  int m = 2 * n;
  double M[4 * N_COEF * N_COEF], rhs[2 * N_COEF];
  for (int it = 0; it < ITERS; it++) {
    memset(M, 0, sizeof(double) * (size_t)m * m), memset(rhs, 0, sizeof(double) * (size_t)m);
    for (int f = 0; f < pd->nf; f++)
      for (int p = 0; p < pd->np; p++) {
        const double *b = pd->basis + (size_t)p * N_COEF, *c = pd->c + 2 * ((size_t)f * pd->np + p);
        double dx = 0, dy = 0;
        for (int t = 0; t < n; t++) dx += b[t] * theta[0][t], dy += b[t] * theta[1][t];
        double ph = -2 * PI * (pd->g[f][0] * dx + pd->g[f][1] * dy), cr = cos(ph), ci = sin(ph);
        double re = c[0] * cr - c[1] * ci, im = c[0] * ci + c[1] * cr, w = hypot(re, im);
        if (!(w > 0)) continue;
        double psi = atan2(im, re) / (2 * PI); /* cycles still to go */
        double J[2 * N_COEF];
        for (int t = 0; t < n; t++) J[t] = pd->g[f][0] * b[t], J[n + t] = pd->g[f][1] * b[t];
        for (int i = 0; i < m; i++) {
          rhs[i] += w * J[i] * psi;
          for (int j = 0; j <= i; j++) M[i * m + j] += w * J[i] * J[j];
        }
      }
    double tr = 0;
    for (int i = 0; i < m; i++) tr += M[i * m + i];
    for (int i = 0; i < m; i++) {
      M[i * m + i] += 1e-9 * tr + 1e-300; /* a ridge: terms the data cannot see stay put */
      for (int j = i + 1; j < m; j++) M[i * m + j] = M[j * m + i];
    }
    if (!wv_solve_spd(M, rhs, m)) break;
    for (int t = 0; t < n; t++) theta[0][t] += rhs[t], theta[1][t] += rhs[n + t];
  }
}

/* Renders p in scene sc at SPP. */
static wv_status render(const wv_scene *sc, const wv_params *p, int threads, wv_image *img, wv_error *err) {
  wv_render_opts ro = {.spp = SPP, .threads = threads};
  return wv_render(sc, p, &ro, img, NULL, err);
}

/* The scene cur with the fabric square, unmoved and undistorted: its fabric coordinates
 * are the plane's, in mm. */
static void square_scene(const wv_scene *cur, wv_scene *out) {
  *out = *cur;
  out->rotation_deg = out->skew_deg = 0;
  out->fabric_offset[0] = out->fabric_offset[1] = 0;
  memset(out->distort, 0, sizeof out->distort);
}

/* The terms (1 and the distortion's) at every grid point of cur, from its plane
 * coordinates divided by extent; a point off the sample gets zeros (no data). basis:
 * (w / STEP) * (h / STEP) * N_COEF. */
static void grid_basis(const wv_scene *cur, double extent, double *basis) {
  wv_scene sq;
  square_scene(cur, &sq);
  int gw = cur->width / STEP, np = gw * (cur->height / STEP);
  for (int q = 0; q < np; q++) {
    double f[2], *b = basis + (size_t)q * N_COEF;
    memset(b, 0, sizeof(double) * N_COEF);
    if (!wv_render_fabric_at(&sq, STEP / 2 + (q % gw) * STEP + 0.5, STEP / 2 + (q / gw) * STEP + 0.5, f)) continue;
    b[0] = 1;
    WV_DISTORT_EVAL(f[0] / extent, f[1] / extent, b + 1);
  }
}

/* One estimate from scene cur: the coefficients to add (theta, with the constant). basis
 * from grid_basis. */
static wv_status estimate(const wv_scene *cur, const wv_image *photo, const float *dp, const float *wp,
                          const double *basis, const wv_params *p, int degree, int threads,
                          double theta[2][N_COEF], double *ssim_cur, wv_error *err) {
  int w = cur->width, h = cur->height, gw = w / STEP, gh = h / STEP, np = gw * gh;
  size_t npx = (size_t)w * h;
  wv_image img[3] = {{0}};
  float *d = malloc(sizeof(float) * npx * 4), *wr = d + npx * 3;
  phase_data pd = {0};
  pd.np = np;
  pd.c = malloc(sizeof(double) * 2 * N_FREQ * (size_t)np);
  pd.basis = basis;
  double *z = malloc(sizeof(double) * 2 * 4 * (size_t)np * N_FREQ);
  wv_status rc = (!d || !pd.c || !z)
                     ? wv_fail(err, WV_ERR_NOMEM, "out of memory for the distortion (%d x %d)", w, h)
                     : WV_OK;
  for (int i = 0; i < 3 && !rc; i++) { /* at the scene, and moved by EPS_MM in fabric x and y */
    wv_scene sc = *cur;
    if (i) sc.fabric_offset[i - 1] += EPS_MM;
    if (!(rc = render(&sc, p, threads, &img[i], err))) rc = detail(&img[i], d + npx * i, err);
  }
  if (!rc) rc = wv_ssim(photo, &img[0], WV_SSIM_RGB, ssim_cur, err);
  if (!rc) rc = wv_image_detail(&img[0], 0, 0, w, h, wr, err);
  double k[N_FREQ][2];
  if (!rc && (pd.nf = shared_peaks(wp, wr, w, h, k, err)) < 0) rc = WV_ERR_NOMEM;
  int fail = 0;
  if (!rc) {
    int r = wv_gaussian_radius(LP_SIGMA);
    double *g = malloc(sizeof(double) * (size_t)(2 * r + 1));
    if (!g) rc = wv_fail(err, WV_ERR_NOMEM, "out of memory for the distortion");
    else {
      wv_gaussian_taps(LP_SIGMA, g);
      const float *src[4] = {dp, d, d + npx, d + 2 * npx};
      int jobs = 4 * pd.nf;
#pragma omp parallel num_threads(threads)
      {
        double *col = malloc(sizeof(double) * 4 * (size_t)w);
#pragma omp for schedule(dynamic, 1)
        for (int jb = 0; jb < jobs; jb++)
          if (col) demodulate(src[jb % 4], w, h, k[jb / 4], g, r, gw, gh, col, col + 2 * w, z + 2 * (size_t)np * jb);
        if (!col) { /* a thread without memory leaves its jobs undone: refuse the estimate */
#pragma omp atomic write
          fail = 1;
        }
        free(col);
      }
      free(g);
      if (fail) rc = wv_fail(err, WV_ERR_NOMEM, "out of memory for the distortion");
    }
  }
  for (int f = 0; f < pd.nf && !rc; f++) {
    const double *zp = z + 2 * (size_t)np * (4 * f), *z0 = zp + 2 * (size_t)np, *zx = z0 + 2 * (size_t)np,
                 *zy = zx + 2 * (size_t)np;
    double sx[2] = {0, 0}, sy[2] = {0, 0};
    for (int q = 0; q < np; q++) { /* sum of moved conj(unmoved): the phase per EPS_MM */
      sx[0] += zx[2 * q] * z0[2 * q] + zx[2 * q + 1] * z0[2 * q + 1];
      sx[1] += zx[2 * q + 1] * z0[2 * q] - zx[2 * q] * z0[2 * q + 1];
      sy[0] += zy[2 * q] * z0[2 * q] + zy[2 * q + 1] * z0[2 * q + 1];
      sy[1] += zy[2 * q + 1] * z0[2 * q] - zy[2 * q] * z0[2 * q + 1];
      double *c = pd.c + 2 * ((size_t)f * np + q); /* photo conj(render) */
      c[0] = zp[2 * q] * z0[2 * q] + zp[2 * q + 1] * z0[2 * q + 1];
      c[1] = zp[2 * q + 1] * z0[2 * q] - zp[2 * q] * z0[2 * q + 1];
      if (pd.basis[(size_t)q * N_COEF] == 0) c[0] = c[1] = 0;
    }
    pd.g[f][0] = atan2(sx[1], sx[0]) / (2 * PI * EPS_MM);
    pd.g[f][1] = atan2(sy[1], sy[0]) / (2 * PI * EPS_MM);
  }
  if (!rc) {
    memset(theta, 0, sizeof(double) * 2 * N_COEF);
    static const int terms[4] = {1, 3, 6, 10}; /* constant, affine, quadratic, cubic */
    for (int dg = 0; dg <= degree; dg++) fit_phases(&pd, terms[dg], theta);
  }
  for (int i = 0; i < 3; i++) wv_image_free(&img[i]);
  free(d), free(pd.c), free(z);
  return rc;
}

/* Makes cur (s plus the offset and distortion found) the fit's scene. */
static void adopt(wv_fit_state *st, const wv_scene *s, const wv_scene *cur, double ssim) {
  st->offset_mm[0] = cur->fabric_offset[0] - s->fabric_offset[0];
  st->offset_mm[1] = cur->fabric_offset[1] - s->fabric_offset[1];
  st->distort_extent_mm = cur->distort_extent_mm;
  for (int k = 0; k < 2; k++)
    for (int t = 0; t < WV_DISTORT_TERMS; t++) st->distort[k][t] = cur->distort[k][t] - s->distort[k][t];
  st->dist_ssim_after = ssim;
}

wv_status wv_fit_distort(wv_fit_state *st, const wv_scene *s, const wv_image *photo, const wv_fit_opts *o,
                         wv_error *err) {
  if (o->distort_degree < 0 || o->distort_degree > 3)
    return wv_fail(err, WV_ERR_INVALID, "fit option 'distort_degree' = %d is outside 0..3", o->distort_degree);
  wv_scene cur;
  wv_fit_scene(st, s, &cur);
  st->distorted = 1;
  if (cur.shape != WV_SHAPE_PLANE || o->distort_degree == 0 || cur.width < 8 * STEP || cur.height < 8 * STEP ||
      photo->w != cur.width || photo->h != cur.height)
    return WV_OK;
  int threads = o->threads > 0 ? o->threads : omp_get_max_threads();
  /* the terms' unit: the scene's own, or half the image's width on the plane */
  double extent = cur.distort_extent_mm;
  if (!wv_scene_distorted(&cur)) {
    wv_scene sq;
    square_scene(&cur, &sq);
    double a[2], b[2];
    extent = 0;
    if (wv_render_fabric_at(&sq, 0, 0.5 * cur.height, a) && wv_render_fabric_at(&sq, cur.width, 0.5 * cur.height, b))
      extent = 0.5 * hypot(b[0] - a[0], b[1] - a[1]);
    if (!(extent > 1e-6)) return WV_OK;
  }
  size_t npx = (size_t)cur.width * cur.height;
  float *dp = malloc(sizeof(float) * npx * 2), *wp = dp + npx;
  double *basis = malloc(sizeof(double) * N_COEF * (size_t)(cur.width / STEP) * (cur.height / STEP));
  if (!dp || !basis) {
    free(dp), free(basis);
    return wv_fail(err, WV_ERR_NOMEM, "out of memory for the distortion");
  }
  grid_basis(&cur, extent, basis);
  wv_status rc = detail(photo, dp, err);
  if (!rc) rc = wv_image_detail(photo, 0, 0, cur.width, cur.height, wp, err);
  /* Each pass estimates from the render of cur (measuring it on the way) and moves cur;
   * a scene is kept only where it raised the whole image's SSIM. */
  double best = -2, now = -2;
  for (int pass = 0; pass <= PASSES && !rc; pass++) {
    double theta[2][N_COEF];
    if (pass < PASSES)
      rc = estimate(&cur, photo, dp, wp, basis, &st->params, o->distort_degree, threads, theta, &now, err);
    else { /* the last estimate: measured alone */
      wv_image img = {0};
      wv_render_opts ro = {.spp = SPP, .threads = threads};
      if (!(rc = wv_render(&cur, &st->params, &ro, &img, NULL, err))) rc = wv_ssim(photo, &img, WV_SSIM_RGB, &now, err);
      wv_image_free(&img);
    }
    if (rc) break;
    if (pass == 0) st->dist_ssim_before = st->dist_ssim_after = best = now;
    else if (now > best) adopt(st, s, &cur, best = now);
    else break;
    if (pass == PASSES) break;
    cur.distort_extent_mm = extent;
    for (int k = 0; k < 2; k++) {
      cur.fabric_offset[k] += theta[k][0];
      for (int t = 0; t < WV_DISTORT_TERMS; t++) cur.distort[k][t] += theta[k][t + 1];
    }
    if (wv_scene_validate(&cur, NULL)) break; /* a displacement out of range is not one to keep */
  }
  free(dp), free(basis);
  return rc;
}
