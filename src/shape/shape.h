/* The sample's shape: where a camera ray meets it and the fabric's frame
 * there. One file per shape (shape/plane_impl.h, shape/cylinder_impl.h), each
 * a lane template instantiated here in scalar (name_f) and 8-wide (name_8)
 * form, and wv_shape_hit_* dispatching on the type. Adding a shape: its
 * template, one line in each list below, its parameters in wv_shape and
 * wv_shape_prepare (and its keys in the scene reader). Internal to the library. */
#ifndef WOVEN_SHAPE_H
#define WOVEN_SHAPE_H

#include "kernel/fastmath.h"
#include "kernel/lanes.h"
#include "woven/scene.h"

/* A shape placed in the scene, with the fabric laid on it. */
typedef struct {
  int type;            /* wv_shape_type */
  float radius;        /* cylinder: radius, scene units */
  int warp_along_axis; /* cylinder: warp along the axis (else around it) */
  float rot_c, rot_s;  /* plane: cos and sin of the fabric x axis's angle from world x */
  float across[2][2];  /* plane: fabric x = p . across[0] (across the warp yarns), fabric y =
                        * p . across[1] (across the weft yarns); with a skew the two are not
                        * square, while the shading frame keeps the rotation's (a few degrees) */
  float off[2];        /* shift of the pattern on the sample, mm */
  float scale;         /* fabric mm per scene unit */
  int distorted;       /* plane: the fabric coordinates are displaced by */
  float dist_k;        /* ... the terms of (x, y) * dist_k (wv_scene.distort) */
  float dist[2][WV_DISTORT_TERMS];
} wv_shape;

void wv_shape_prepare(const wv_scene *s, wv_shape *sh);

#define WV_LANE WV_LANE_F
#include "kernel/lane_begin.h"
#include "shape/surface_impl.h"
#include "shape/plane_impl.h"
#include "shape/cylinder_impl.h"
#include "shape/dispatch_impl.h"
#include "kernel/lane_end.h"
#define WV_LANE WV_LANE_8
#include "kernel/lane_begin.h"
#include "shape/surface_impl.h"
#include "shape/plane_impl.h"
#include "shape/cylinder_impl.h"
#include "shape/dispatch_impl.h"
#include "kernel/lane_end.h"

#endif
