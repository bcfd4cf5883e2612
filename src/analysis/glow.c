/* The open area of a back-lit photo, measured on its gap glow (analysis.h,
 * wv_open_area_measure). The rig adds to the radiance of each pixel the glow's radiance
 * times a Gaussian centred on the image times the pixel's open fraction; averaged over
 * blocks of a few yarns, that is the open area times a known bump, on top of the light
 * the yarns pass, which varies slowly. So the photo's linear radiance, block by block,
 * is fitted by least squares as a quadratic in x and y plus an amplitude times the bump,
 * and the amplitude over the glow's radiance is the open area. */
#include <math.h>

#include "sensor/sensor.h"
#include "util/linalg.h"
#include "woven/analysis.h"

#define GLOW_TERMS 7           /* 1, x, y, x^2, xy, y^2 and the bump */
#define GLOW_REACH 5.0         /* the fit's disc: this many glow sigmas from the centre */
#define GLOW_BLOCK_DIV 2.5     /* blocks of sigma / this pixels (8 at sigma 20): several yarns */
#define GLOW_CLIP_MARGIN 0.995 /* a block with a value this close to the clip is left out */
#define GLOW_MIN_BUMP 0.1      /* blocks where the bump is at least this much of its peak ... */
#define GLOW_MIN_BUMP_BLOCKS 4 /* ... must be this many, or the amplitude is not measured */

wv_status wv_open_area_measure(const wv_scene *s, const wv_image *photo, wv_open_area *out, wv_error *err) {
  *out = (wv_open_area){0};
  if (!(s->glow_radiance > 0 && s->glow_sigma > 0))
    return wv_fail(err, WV_ERR_INVALID, "the scene '%s' has no gap glow to measure the open area by", s->name);
  if (photo->w != s->width || photo->h != s->height || photo->c < 3)
    return wv_fail(err, WV_ERR_INVALID, "the photo is %d x %d (%d channels) but the scene renders %d x %d in RGB",
                   photo->w, photo->h, photo->c, s->width, s->height);
  int b = (int)lround(s->glow_sigma / GLOW_BLOCK_DIV);
  b = b < 1 ? 1 : b;
  double reach = GLOW_REACH * s->glow_sigma;
  float top = s->clip > 0 ? (float)(GLOW_CLIP_MARGIN * wv_encode(s, (float)s->clip)) : INFINITY;
  double m[GLOW_TERMS * GLOW_TERMS] = {0}, r[GLOW_TERMS] = {0};
  int nb = photo->w / b, mb = photo->h / b, bump_blocks = 0;
  for (int by = 0; by < mb; by++)
    for (int bx = 0; bx < nb; bx++) {
      /* the block's centre, in pixels from the image's centre (wv_pixel_gaussian's) */
      double cx = (bx + 0.5) * b - 0.5 * photo->w, cy = (by + 0.5) * b - 0.5 * photo->h;
      if (cx * cx + cy * cy > reach * reach) continue;
      double lin = 0, bump = 0;
      int clipped = 0;
      for (int y = by * b; y < (by + 1) * b && !clipped; y++)
        for (int x = bx * b; x < (bx + 1) * b; x++) {
          double mask = wv_response_mask(s, x, y);
          const float *p = wv_image_px(photo, x, y);
          for (int c = 0; c < 3; c++) {
            float e = (float)(p[c] / mask);
            if (e >= top) clipped = 1;
            lin += wv_decode(s, e) / s->exposure;
          }
          bump += wv_pixel_gaussian(photo->w, photo->h, x, y, s->glow_sigma);
        }
      if (clipped) {
        out->clipped++;
        continue;
      }
      lin /= 3.0 * b * b, bump /= (double)b * b;
      double X = cx / reach, Y = cy / reach, t[GLOW_TERMS] = {1, X, Y, X * X, X * Y, Y * Y, bump};
      for (int i = 0; i < GLOW_TERMS; i++) {
        r[i] += t[i] * lin;
        for (int j = 0; j < GLOW_TERMS; j++) m[i * GLOW_TERMS + j] += t[i] * t[j];
      }
      out->blocks++;
      bump_blocks += bump >= GLOW_MIN_BUMP;
    }
  if (bump_blocks < GLOW_MIN_BUMP_BLOCKS || !wv_solve_spd(m, r, GLOW_TERMS)) return WV_OK; /* not measured */
  out->found = 1;
  out->amplitude = r[GLOW_TERMS - 1];
  out->open_area = out->amplitude / s->glow_radiance;
  return WV_OK;
}
