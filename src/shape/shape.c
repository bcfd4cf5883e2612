/* A scene's shape in the form the intersection code reads (shape/shape.h). */
#include "shape/shape.h"

#include <math.h>
#include <string.h>

void wv_shape_prepare(const wv_scene *s, wv_shape *sh) {
  memset(sh, 0, sizeof *sh);
  sh->type = s->shape;
  sh->warp_along_axis = s->warp_along_axis;
  sh->radius = (float)s->radius;
  const double deg = 3.14159265358979323846 / 180.0;
  double r = s->rotation_deg * deg, wa = r - s->skew_deg * deg / 2, fa = r + s->skew_deg * deg / 2;
  sh->rot_c = (float)cos(r), sh->rot_s = (float)sin(r);
  /* the warp yarns run along (-sin wa, cos wa): their across direction is (cos wa, sin wa);
   * the weft yarns run along (cos fa, sin fa): theirs is (-sin fa, cos fa) */
  sh->across[0][0] = (float)cos(wa), sh->across[0][1] = (float)sin(wa);
  sh->across[1][0] = (float)-sin(fa), sh->across[1][1] = (float)cos(fa);
  sh->off[0] = (float)s->fabric_offset[0], sh->off[1] = (float)s->fabric_offset[1];
  sh->scale = (float)s->mm_per_unit;
  sh->distorted = s->shape == WV_SHAPE_PLANE && wv_scene_distorted(s);
  if (sh->distorted) {
    sh->dist_k = (float)(s->mm_per_unit / s->distort_extent_mm);
    for (int k = 0; k < 2; k++)
      for (int t = 0; t < WV_DISTORT_TERMS; t++) sh->dist[k][t] = (float)s->distort[k][t];
  }
}
