/* Registration of the fit to the photo: the densities to a tenth of a yarn per
 * inch and the weave's phase (a fabric offset), by phase correlation. See
 * wv_fit_register in fit.h for why. */
#include <fftw3.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "fit/fit_internal.h"
#include "woven/fit.h"
#include "woven/metrics.h"
#include "woven/render.h"

#define HP_SIGMA 4.0 /* pixels: keeps the weave and rib frequencies, drops shading and falloff */
#define HP_RAD 12

/* Everything one window's correlation needs, allocated once per registration. */
typedef struct {
  int w, h, nc;           /* window, complex row length w/2+1 */
  float *a, *tmp, *win;   /* w*h: the high-passed image, a blur scratch, the Hann window */
  float *corr;            /* w*h: correlation over all circular shifts */
  fftwf_complex *ref, *spec; /* h*nc: the photo's spectrum, the render's */
  fftwf_plan fwd, inv;
  double win_energy;      /* sum of win^2 */
} phasecorr;

static void pc_free(phasecorr *p) {
  if (p->fwd) fftwf_destroy_plan(p->fwd);
  if (p->inv) fftwf_destroy_plan(p->inv);
  fftwf_free(p->a), fftwf_free(p->corr), fftwf_free(p->ref), fftwf_free(p->spec);
  free(p->tmp), free(p->win);
  memset(p, 0, sizeof *p);
}

static wv_status pc_init(phasecorr *p, int w, int h, wv_error *err) {
  memset(p, 0, sizeof *p);
  p->w = w, p->h = h, p->nc = w / 2 + 1;
  size_t n = (size_t)w * h, nc = (size_t)h * p->nc;
  p->a = fftwf_alloc_real(n), p->corr = fftwf_alloc_real(n);
  p->ref = fftwf_alloc_complex(nc), p->spec = fftwf_alloc_complex(nc);
  p->tmp = malloc(sizeof(float) * n), p->win = malloc(sizeof(float) * n);
  if (!p->a || !p->corr || !p->ref || !p->spec || !p->tmp || !p->win) {
    pc_free(p);
    return wv_fail(err, WV_ERR_NOMEM, "out of memory for the registration (%d x %d window)", w, h);
  }
  /* FFTW_ESTIMATE: no timing-dependent planning, so results are reproducible. */
  p->fwd = fftwf_plan_dft_r2c_2d(h, w, p->a, p->spec, FFTW_ESTIMATE);
  p->inv = fftwf_plan_dft_c2r_2d(h, w, p->spec, p->corr, FFTW_ESTIMATE);
  if (!p->fwd || !p->inv) {
    pc_free(p);
    return wv_fail(err, WV_ERR_NOMEM, "cannot plan the registration FFT (%d x %d)", w, h);
  }
  p->win_energy = 0;
  for (int y = 0; y < h; y++)
    for (int x = 0; x < w; x++) {
      double v = (0.5 - 0.5 * cos(2 * 3.14159265358979323846 * (x + 0.5) / w)) * (0.5 - 0.5 * cos(2 * 3.14159265358979323846 * (y + 0.5) / h));
      p->win[(size_t)y * w + x] = (float)v;
      p->win_energy += v * v;
    }
  return WV_OK;
}

/* a = Hann * normalise(Y - gauss(Y)): luminance detail, zero mean, unit variance. */
static void pc_prepare(phasecorr *p, const wv_image *img) {
  int w = p->w, h = p->h;
  double g[2 * HP_RAD + 1], gs = 0;
  for (int k = -HP_RAD; k <= HP_RAD; k++) gs += g[k + HP_RAD] = exp(-0.5 * k * k / (HP_SIGMA * HP_SIGMA));
  for (int k = 0; k <= 2 * HP_RAD; k++) g[k] /= gs;
  for (int y = 0; y < h; y++)
    for (int x = 0; x < w; x++) {
      const float *c = wv_image_px(img, x, y);
      p->a[(size_t)y * w + x] = 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2];
    }
  /* separable blur with clamped edges into corr (scratch), then detail = a - blur */
  for (int y = 0; y < h; y++)
    for (int x = 0; x < w; x++) {
      double s = 0;
      for (int k = -HP_RAD; k <= HP_RAD; k++) {
        int xx = x + k < 0 ? 0 : x + k >= w ? w - 1 : x + k;
        s += g[k + HP_RAD] * p->a[(size_t)y * w + xx];
      }
      p->tmp[(size_t)y * w + x] = (float)s;
    }
  for (int y = 0; y < h; y++)
    for (int x = 0; x < w; x++) {
      double s = 0;
      for (int k = -HP_RAD; k <= HP_RAD; k++) {
        int yy = y + k < 0 ? 0 : y + k >= h ? h - 1 : y + k;
        s += g[k + HP_RAD] * p->tmp[(size_t)yy * w + x];
      }
      p->corr[(size_t)y * w + x] = (float)s;
    }
  size_t n = (size_t)w * h;
  double m = 0, v = 0;
  for (size_t i = 0; i < n; i++) m += p->a[i] -= p->corr[i];
  m /= (double)n;
  for (size_t i = 0; i < n; i++) v += (p->a[i] - m) * (p->a[i] - m);
  double is = v > 1e-20 ? 1.0 / sqrt(v / (double)n) : 0.0; /* a flat image correlates with nothing */
  for (size_t i = 0; i < n; i++) p->a[i] = (float)((p->a[i] - m) * is) * p->win[i];
}

/* Correlation of the photo (p->ref) with img over shifts |s| <= max_shift: the best
 * normalised value and the shift s (sub-pixel) with photo(x) ~ img(x - s). */
static double pc_best(phasecorr *p, const wv_image *img, int max_shift, double shift[2]) {
  pc_prepare(p, img);
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
  return best;
}

/* Renders the window with the given densities and scores it. */
static wv_status score(phasecorr *pc, const wv_scene *win, const wv_params *base, const double dens[2],
                       const wv_render_opts *ro, int max_shift, double *out, double shift[2], wv_error *err) {
  wv_params p = *base;
  p.density[0] = dens[0], p.density[1] = dens[1];
  wv_image img;
  wv_status rc = wv_render(win, &p, ro, &img, NULL, err);
  if (rc) return rc;
  *out = pc_best(pc, &img, max_shift, shift);
  wv_image_free(&img);
  return WV_OK;
}

static int in_range(const double d[2]) { return d[0] >= 20 && d[0] <= 250 && d[1] >= 20 && d[1] <= 250; }

static wv_status window_ssim(const wv_scene *win, const wv_params *p, const wv_image *ref, const wv_render_opts *ro,
                             double *out, wv_error *err) {
  wv_image img;
  wv_status rc = wv_render(win, p, ro, &img, NULL, err);
  if (rc) return rc;
  rc = wv_ssim(ref, &img, WV_SSIM_LUMA, out, err);
  wv_image_free(&img);
  return rc;
}

void wv_fit_scene(const wv_fit_state *st, const wv_scene *s, wv_scene *out) {
  *out = *s;
  out->fabric_offset[0] += st->offset_mm[0];
  out->fabric_offset[1] += st->offset_mm[1];
}

wv_status wv_fit_register(wv_fit_state *st, const wv_scene *s, const wv_image *photo, const wv_fit_opts *o,
                          wv_error *err) {
  int w = s->width < 256 ? s->width : 256, h = s->height < 256 ? s->height : 256;
  w -= (s->width - w) % 2, h -= (s->height - h) % 2; /* centred on whole pixels */
  wv_scene full, win;
  wv_fit_scene(st, s, &full);
  wv_fit_centre_window(&full, w, h, &win);
  win.spp = o->iter_spp;
  int max_shift = (w < h ? w : h) / 4;
  wv_image ref;
  wv_status rc = wv_fit_centre_crop(photo, w, h, &ref, err);
  if (rc) return rc;
  phasecorr pc;
  if ((rc = pc_init(&pc, w, h, err))) {
    wv_image_free(&ref);
    return rc;
  }
  pc_prepare(&pc, &ref);
  fftwf_execute(pc.fwd);
  memcpy(pc.ref, pc.spec, sizeof(fftwf_complex) * (size_t)h * pc.nc);
  wv_render_opts ro = {win.spp, o->threads, NULL, NULL};

  double cur[2] = {st->params.density[0], st->params.density[1]}, best, shift[2];
  rc = score(&pc, &win, &st->params, cur, &ro, 0, &st->reg_ncc_before, NULL, err);
  if (!rc) rc = score(&pc, &win, &st->params, cur, &ro, max_shift, &best, NULL, err);
  /* 2-D grid on whole yarns/inch: the peak is narrow (about one yarn across the
   * window) and a one-at-a-time search walks off it. */
  double centre[2] = {cur[0], cur[1]};
  int R = o->register_radius;
  for (int a = -R; a <= R && !rc; a++)
    for (int b = -R; b <= R && !rc; b++) {
      double d[2] = {centre[0] + a, centre[1] + b}, v;
      if ((!a && !b) || !in_range(d)) continue;
      if ((rc = score(&pc, &win, &st->params, d, &ro, max_shift, &v, NULL, err))) break;
      if (v > best) best = v, cur[0] = d[0], cur[1] = d[1];
    }
  /* then finer steps around the best, 8 neighbours at a time */
  static const double steps[] = {0.5, 0.25, 0.1};
  for (int k = 0; k < 3 && !rc; k++)
    for (int moves = 0; moves < 6 && !rc; moves++) {
      double bd[2] = {cur[0], cur[1]}, bv = best;
      for (int a = -1; a <= 1 && !rc; a++)
        for (int b = -1; b <= 1 && !rc; b++) {
          double d[2] = {cur[0] + a * steps[k], cur[1] + b * steps[k]}, v;
          if ((!a && !b) || !in_range(d)) continue;
          if ((rc = score(&pc, &win, &st->params, d, &ro, max_shift, &v, NULL, err))) break;
          if (v > bv) bv = v, bd[0] = d[0], bd[1] = d[1];
        }
      if (bv <= best) break;
      best = bv, cur[0] = bd[0], cur[1] = bd[1];
    }
  if (!rc) rc = score(&pc, &win, &st->params, cur, &ro, max_shift, &best, shift, err);
  /* The shift becomes a fabric offset through the local map pixel -> fabric at
   * the centre: photo(x) ~ render(x - shift) means fabric(x) must become
   * fabric(x - shift). */
  double f0[2], fx[2], fy[2], off[2] = {0, 0};
  double cx = 0.5 * full.width, cy = 0.5 * full.height;
  if (!rc && wv_render_fabric_at(&full, cx, cy, f0) && wv_render_fabric_at(&full, cx + 1, cy, fx) &&
      wv_render_fabric_at(&full, cx, cy + 1, fy)) {
    for (int i = 0; i < 2; i++) off[i] = -((fx[i] - f0[i]) * shift[0] + (fy[i] - f0[i]) * shift[1]);
  }
  if (!rc) {
    wv_params cand = st->params;
    cand.density[0] = cur[0], cand.density[1] = cur[1];
    wv_scene moved = win;
    moved.fabric_offset[0] += off[0], moved.fabric_offset[1] += off[1];
    double before, after, ncc_after;
    if (!(rc = window_ssim(&win, &st->params, &ref, &ro, &before, err)) &&
        !(rc = window_ssim(&moved, &cand, &ref, &ro, &after, err)) &&
        !(rc = score(&pc, &moved, &cand, cur, &ro, 0, &ncc_after, NULL, err))) {
      st->reg_ssim_before = before;
      if (after > before) {
        st->params = cand;
        st->offset_mm[0] += off[0], st->offset_mm[1] += off[1];
        st->reg_ssim_after = after, st->reg_ncc_after = ncc_after;
      } else {
        st->reg_ssim_after = before, st->reg_ncc_after = st->reg_ncc_before;
      }
      st->registered = 1;
    }
  }
  pc_free(&pc);
  wv_image_free(&ref);
  return rc;
}
