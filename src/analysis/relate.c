/* The scale and rotation between two photos of one weave (analysis.h, wv_weave_relate): the
 * peaks of a weave spectrum sit on the weave's reciprocal lattice, so a photo taken closer
 * or turned moves every peak by the same scale and rotation about DC. The first photo's
 * peaks, carried by a candidate (scale, rotation), are scored by how near they land to the
 * second's, on a coarse grid and then a fine one around its best. */
#include <math.h>
#include <stdlib.h>

#include "woven/analysis.h"
#include "woven/metrics.h"

#define COARSE_SCALE 0.0025 /* grid steps of the first search: a peak 200 bins out moves half a bin */
#define COARSE_ROT 0.125    /* degrees */
#define FINE_STEPS 10      /* the second search: +-one coarse step in this many parts */
#define DEG (3.14159265358979323846 / 180)

typedef struct {
  int n[2];
  wv_spectral_peak pk[2][WV_LATTICE_PEAKS];
  double total[2]; /* sum of the WV_RELATE_PEAKS strongest peaks' prominence */
} peak_sets;

/* Where a's peak p lands under (scale, rotation), in bins: the nearest of b's peaks (either
 * sign: a peak and its mirror are one) and its distance. */
static double nearest(const peak_sets *ps, int from, int side, double u, double v, double *zb) {
  double best = INFINITY;
  for (int j = 0; j < ps->n[1 - from]; j++) {
    const wv_spectral_peak *b = &ps->pk[1 - from][j];
    for (int sg = -1; sg <= 1; sg += 2) {
      double du = (sg * u - b->u) * side, dv = (sg * v - b->v) * side;
      double d = sqrt(du * du + dv * dv);
      if (d < best) best = d, *zb = b->z;
    }
  }
  return best;
}

/* The soft score of (scale, rotation), both ways: each of the WV_RELATE_PEAKS strongest peaks
 * of either photo, carried to the other (the inverse map from b), counts the smaller
 * prominence of it and the nearest peak there, times 1 - distance / tolerance. *matched:
 * those within the tolerance. */
static double score_at(const peak_sets *ps, int side, double scale, double rot_deg, int *matched) {
  double sum = 0;
  int m = 0;
  for (int from = 0; from < 2; from++) {
    double sc = from ? 1 / scale : scale, r = (from ? -rot_deg : rot_deg) * DEG, c = cos(r), s = sin(r);
    int k = ps->n[from] < WV_RELATE_PEAKS ? ps->n[from] : WV_RELATE_PEAKS;
    for (int i = 0; i < k; i++) {
      const wv_spectral_peak *a = &ps->pk[from][i];
      /* counter-clockwise as seen (y up) with v pointing down the image */
      double zb = 0, d = nearest(ps, from, side, sc * (a->u * c + a->v * s), sc * (-a->u * s + a->v * c), &zb);
      if (d < WV_RELATE_TOL) {
        sum += (a->z < zb ? a->z : zb) * (1 - d / WV_RELATE_TOL);
        m++;
      }
    }
  }
  if (matched) *matched = m;
  return sum;
}

wv_status wv_weave_relate(const wv_image *a, const wv_image *b, wv_weave_relation *out, wv_error *err) {
  *out = (wv_weave_relation){.scale = 1};
  int side = a->w < a->h ? a->w : a->h;
  if (b->w < side) side = b->w;
  if (b->h < side) side = b->h;
  if (side > WV_LATTICE_REFINE_WINDOW) side = WV_LATTICE_REFINE_WINDOW;
  side &= ~1;
  if (side < WV_LATTICE_MIN_WINDOW)
    return wv_fail(err, WV_ERR_INVALID, "the photos (%d x %d, %d x %d) are too small to compare their weaves (at least %d x %d)",
                   a->w, a->h, b->w, b->h, WV_LATTICE_MIN_WINDOW, WV_LATTICE_MIN_WINDOW);
  out->window = side;
  float *spec = malloc(sizeof(float) * (size_t)side * side);
  peak_sets *ps = calloc(1, sizeof *ps);
  if (!spec || !ps) {
    free(spec), free(ps);
    return wv_fail(err, WV_ERR_NOMEM, "out of memory for the weave spectra");
  }
  const wv_image *img[2] = {a, b};
  wv_status rc = WV_OK;
  for (int k = 0; k < 2 && !rc; k++) {
    rc = wv_weave_spectrum(img[k], (img[k]->w - side) / 2, (img[k]->h - side) / 2, side, spec, err);
    if (rc) break;
    ps->n[k] = wv_spectrum_peaks(spec, side, WV_RELATE_MIN_Z, ps->pk[k], WV_LATTICE_PEAKS);
    for (int i = 0; i < ps->n[k] && i < WV_RELATE_PEAKS; i++) ps->total[k] += ps->pk[k][i].z;
  }
  free(spec);
  if (rc || !ps->n[0] || !ps->n[1]) {
    free(ps);
    return rc;
  }
  double bs = 1, br = 0;
  int ns = (int)floor((WV_RELATE_SCALE_MAX - WV_RELATE_SCALE_MIN) / COARSE_SCALE + 0.5);
  int nr = (int)floor(WV_RELATE_MAX_ROT / COARSE_ROT + 0.5);
  /* identity first: a tie keeps the photos as one camera's */
  double best = score_at(ps, side, 1, 0, NULL);
  for (int i = 0; i <= ns; i++)
    for (int j = -nr; j <= nr; j++) {
      double sc = WV_RELATE_SCALE_MIN + i * COARSE_SCALE, r = j * COARSE_ROT;
      double v = score_at(ps, side, sc, r, NULL);
      if (v > best) best = v, bs = sc, br = r;
    }
  double cs = bs, cr = br;
  for (int i = -FINE_STEPS; i <= FINE_STEPS; i++)
    for (int j = -FINE_STEPS; j <= FINE_STEPS; j++) {
      double sc = cs + i * COARSE_SCALE / FINE_STEPS, r = cr + j * COARSE_ROT / FINE_STEPS;
      if (sc < WV_RELATE_SCALE_MIN || sc > WV_RELATE_SCALE_MAX || fabs(r) > WV_RELATE_MAX_ROT) continue;
      double v = score_at(ps, side, sc, r, NULL);
      if (v > best) best = v, bs = sc, br = r;
    }
  int matched = 0;
  double v = score_at(ps, side, bs, br, &matched);
  out->score = ps->total[0] + ps->total[1] > 0 ? v / (ps->total[0] + ps->total[1]) : 0;
  out->matched = matched;
  out->found = matched >= WV_RELATE_MIN_MATCH && out->score >= WV_RELATE_MIN_SCORE;
  if (out->found) out->scale = bs, out->rotation_deg = br;
  free(ps);
  return WV_OK;
}
