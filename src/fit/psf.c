/* woven: the camera blur of a photo, measured from its spectrum. A photo's weave
 * spectrum falls toward high frequencies (optics, demosaicing) where a render's stays
 * flat; the blur whose render falls alike is the camera's. The blur itself is the
 * sensor's (wv_psf_apply, src/scene/response.c). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "woven/fit.h"
#include "woven/metrics.h"
#include "woven/render.h"

static int cmp_float(const void *a, const void *b) {
  float x = *(const float *)a, y = *(const float *)b;
  return (x > y) - (x < y);
}

/* The envelope of an n x n weave spectrum: the median of each ring of integer radius
 * (the median passes over the few bins of the weave's peaks). env: n / 2 values. */
static void envelope(const float *sp, int n, float *env, float *scratch) {
  int h = n / 2;
  for (int r = 0; r < h; r++) {
    int k = 0;
    for (int y = 0; y < n; y++)
      for (int x = 0; x < n; x++) {
        double d = hypot(x - h, y - h);
        if (d >= r && d < r + 1) scratch[k++] = sp[(size_t)y * n + x];
      }
    qsort(scratch, (size_t)k, sizeof *scratch, cmp_float);
    env[r] = k ? scratch[k / 2] : 0.0f;
  }
}

wv_status wv_psf_estimate(const wv_scene *s, const wv_image *photo, const wv_params *p, int threads,
                          double *sigma, double *distance, wv_error *err) {
  *sigma = 0;
  if (distance) *distance = 0;
  int n = photo->w < photo->h ? photo->w : photo->h;
  n = n > WV_WSC_SIZE ? WV_WSC_SIZE : n - n % 2;
  if (n < WV_PSF_MIN_SIDE) return WV_OK; /* too small to see an envelope */
  int h = n / 2, x0 = (photo->w - n) / 2, y0 = (photo->h - n) / 2;
  wv_scene sc = *s;
  sc.psf_sigma = 0;
  sc.spp = WV_PSF_SPP; /* sampling noise would flatten the render's envelope */
  wv_render_opts ro = {sc.spp, threads, NULL, NULL, NULL};
  wv_image cap = {0}, rad = {0};
  float *sp = malloc(sizeof(float) * ((size_t)n * n * 2 + 2 * (size_t)h));
  if (!sp) return wv_fail(err, WV_ERR_NOMEM, "out of memory for the camera blur's estimate");
  float *scratch = sp + (size_t)n * n, *ep = scratch + (size_t)n * n, *er = ep + h;
  wv_status st = wv_weave_spectrum(photo, x0, y0, n, sp, err);
  if (!st) envelope(sp, n, ep, scratch);
  if (!st) st = wv_render(&sc, p, &ro, &cap, &rad, err);
  double best = INFINITY;
  /* the rings from WV_WSC_DC_RADIUS out, where the detail filter passes the weave */
  int r0 = (int)WV_WSC_DC_RADIUS + 1;
  for (int k = 0; k <= WV_PSF_STEPS && !st; k++) {
    sc.psf_sigma = WV_PSF_RANGE * k / WV_PSF_STEPS;
    if ((st = wv_scene_capture(&sc, &rad, &cap, err))) break;
    if ((st = wv_weave_spectrum(&cap, x0, y0, n, sp, err))) break;
    envelope(sp, n, er, scratch);
    double d = 0;
    for (int r = r0; r < h; r++) d += (er[r] - ep[r]) * (er[r] - ep[r]);
    d /= h - r0;
    if (d < best) best = d, *sigma = sc.psf_sigma;
  }
  if (distance) *distance = best;
  wv_image_free(&cap), wv_image_free(&rad);
  free(sp);
  return st;
}
