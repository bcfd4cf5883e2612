/* woven: a small cloth simulation that drapes a UV-mapped square over an
 * obstacle (a sphere, a box: a table and its edge) onto a floor, to make the
 * draped-cloth mesh the mesh renderer shows fabrics on. Position-based dynamics
 * (Mueller et al. 2007): stretch, shear and bending distance constraints,
 * collisions with the obstacles and the floor (with friction), and a minimum
 * distance between cloth particles that are not neighbours (self-distance), so
 * folds do not pass through each other. Single-threaded and deterministic.
 * Units: mm, y up, the floor is y = floor_y. */
#ifndef WOVEN_CLOTH_H
#define WOVEN_CLOTH_H

#include <stdint.h>

#include "woven/error.h"
#include "woven/mesh.h"

typedef enum { WV_OBSTACLE_NONE, WV_OBSTACLE_SPHERE, WV_OBSTACLE_BOX } wv_obstacle;

/* A zeroed struct is not the defaults (0 is a meaningful obstacle, offset, floor and
 * seed): start from wv_cloth_defaults and change what differs. */
typedef struct {
  int res;                /* cells per side: (res + 1)^2 particles, 2 res^2 triangles */
  double size_mm;         /* side of the square */
  double drop_height_mm;  /* starting height of the (horizontal) square */
  double rotation_deg;    /* of the square about the vertical, before the drop */
  double offset_mm[2];    /* of the square's centre in x and z */
  wv_obstacle obstacle;
  double centre_mm[3];    /* sphere centre */
  double radius_mm;       /* sphere radius */
  double box_min_mm[3], box_max_mm[3]; /* box (a table: its top edge makes the fold) */
  double floor_y;
  double seconds;         /* simulated time */
  int steps_per_second;
  int iterations;         /* constraint passes per step */
  double bend_stiffness;  /* 0..1 */
  double friction;        /* 0..1 */
  uint64_t seed;          /* tiny initial jitter that breaks the symmetry of the drop */
} wv_cloth_opts;

/* The defaults: a 300 mm square, 64 x 64 cells, dropped from 200 mm over a sphere
 * of radius 80 mm resting on the floor, 3 s at 600 steps/s. */
void wv_cloth_defaults(wv_cloth_opts *o);

/* Runs the simulation; out gets the draped square (UVs from (0,0) to (1,1),
 * u along the square's first side, smooth normals). */
wv_status wv_cloth_drape(const wv_cloth_opts *o, wv_mesh *out, wv_error *err);

#endif
