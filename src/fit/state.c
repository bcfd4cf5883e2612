/* The fit's state (include/woven/fit.h): making and freeing it, and the scene it
 * settles on (the registration's offset, the camera blur, the distortion). The
 * optimiser, the registration, the distortion and the checkpoints all use these;
 * nothing here calls them back. */
#include "woven/fit.h"

void wv_fit_scene(const wv_fit_state *st, const wv_scene *s, wv_scene *out) {
  *out = *s;
  out->fabric_offset[0] += st->offset_mm[0];
  out->fabric_offset[1] += st->offset_mm[1];
  if (st->psf_done) out->psf_sigma = st->psf_sigma;
  if (st->distort_extent_mm > 0) {
    out->distort_extent_mm = st->distort_extent_mm;
    for (int k = 0; k < 2; k++)
      for (int t = 0; t < WV_DISTORT_TERMS; t++) out->distort[k][t] += st->distort[k][t];
  }
}
