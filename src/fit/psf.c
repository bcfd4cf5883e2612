/* woven: the camera blur of a photo, measured from its spectrum. A photo's weave
 * spectrum falls toward high frequencies (optics, demosaicing) where a render's stays
 * flat; the blur whose render's spectrum has the photo's shape is the camera's. The blur
 * itself is the sensor's (wv_psf_apply, src/sensor/response.c). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "woven/fit.h"
#include "woven/metrics.h"
#include "woven/render.h"

wv_status wv_psf_estimate(const wv_scene *s, const wv_image *photo, const wv_params *p, int threads,
                          double *sigma, double *distance, wv_error *err) {
  *sigma = 0;
  if (distance) *distance = 0;
  int n = photo->w < photo->h ? photo->w : photo->h;
  n = n > WV_WSC_SIZE ? WV_WSC_SIZE : n - n % 2;
  if (n < WV_PSF_MIN_SIDE) return WV_OK; /* too small to see an envelope */
  int x0 = (photo->w - n) / 2, y0 = (photo->h - n) / 2;
  wv_scene sc = *s;
  sc.psf_sigma = 0;
  sc.spp = WV_PSF_SPP; /* sampling noise would flatten the render's spectrum */
  wv_render_opts ro = {.spp = sc.spp, .threads = threads};
  wv_image cap = {0}, rad = {0};
  float *sp = malloc(sizeof(float) * (size_t)n * n * 2), *sr = sp ? sp + (size_t)n * n : NULL;
  if (!sp) return wv_fail(err, WV_ERR_NOMEM, "out of memory for the camera blur's estimate");
  wv_status st = wv_weave_spectrum(photo, x0, y0, n, sp, err);
  if (!st) st = wv_render(&sc, p, &ro, &cap, &rad, err);
  /* Only the centre n x n is compared: the blurs run on the centre window that holds it and
   * the widest blur's reach around it (the same values there as on the whole image). */
  int m = (int)ceil(3.0 * WV_PSF_RANGE), rx = x0, ry = y0; /* the compared square's corner */
  wv_scene sw = sc;
  if (!st && !((photo->w - n) % 2) && !((photo->h - n) % 2) && n + 2 * m <= photo->w && n + 2 * m <= photo->h) {
    wv_image win = {0};
    if (!(st = wv_image_centre_crop(&rad, n + 2 * m, n + 2 * m, &win, err))) {
      wv_image_free(&rad), wv_image_free(&cap);
      rad = win;
      wv_scene_centre_window(&sc, n + 2 * m, n + 2 * m, &sw);
      st = wv_image_alloc(&cap, rad.w, rad.h, 3, err);
      rx = ry = m;
    }
  }
  double best = INFINITY;
  for (int k = 0; k <= WV_PSF_STEPS && !st; k++) {
    sw.psf_sigma = WV_PSF_RANGE * k / WV_PSF_STEPS;
    if ((st = wv_scene_capture(&sw, &rad, &cap, err))) break;
    if ((st = wv_weave_spectrum(&cap, rx, ry, n, sr, err))) break;
    /* 1 - WSC: the shape of the whole spectrum, peaks and floor, not the level of its
     * ring medians. The squared distance of the ring medians, used before, measured 0.6 px
     * on the three real flat45 photos, where a fit with 1.0 px scores higher SSIM and WSC
     * (docs/fit.md); this criterion measures 1.0, 1.0 and 1.3 px. */
    double d = 1 - wv_wsc_spectra(sp, sr, n);
    if (d < best) best = d, *sigma = sw.psf_sigma;
  }
  if (distance) *distance = best;
  wv_image_free(&cap), wv_image_free(&rad);
  free(sp);
  return st;
}
