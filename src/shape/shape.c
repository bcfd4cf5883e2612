/* A scene's shape in the form the intersection code reads (shape/shape.h). */
#include "shape/shape.h"

#include <math.h>
#include <string.h>

void wv_shape_prepare(const wv_scene *s, wv_shape *sh) {
  memset(sh, 0, sizeof *sh);
  sh->type = s->shape;
  sh->warp_along_axis = s->warp_along_axis;
  sh->radius = (float)s->radius;
  sh->rot_c = (float)cos(s->rotation_deg * 3.14159265358979323846 / 180.0);
  sh->rot_s = (float)sin(s->rotation_deg * 3.14159265358979323846 / 180.0);
  sh->off[0] = (float)s->fabric_offset[0], sh->off[1] = (float)s->fabric_offset[1];
  sh->scale = (float)s->mm_per_unit;
}
