/* A loaded scene (wv_world): meshes, their ray tracer, prepared materials,
 * edit maps and lights, shared by the loader (world.c) and the path tracer
 * (integrator.c). Internal to the library. */
#ifndef WOVEN_WORLD_INTERNAL_H
#define WOVEN_WORLD_INTERNAL_H

#include "kernel/kernel.h"
#include "tracer/tracer.h"
#include "woven/emitters.h"
#include "woven/mesh.h"
#include "woven/scene3d.h"

typedef struct {
  wv_edit_op op;
  const wv_image *map;  /* linear values (sRGB PNG colour maps decoded); owned by wv_world.images */
  const wv_image *mask; /* NULL when the edit applies everywhere */
  float gain;
} wv_edit_map;

typedef struct {
  wv_material_kind kind;
  wv_fabric *fab;       /* fabric: prepared by the capture renderer's wv_fabric_prepare */
  float uv_mm[2], uv_off[2];
  float albedo[3];      /* lambert */
  float pback;          /* fabric: wv_back_prob */
  wv_edit_map *edits;
  int nedits;
} wv_world_material;

/* An edit map or mask read once, however many edits name it (the same file, by
 * device and inode, read the same way). */
typedef struct {
  wv_image img;
  unsigned long long dev, ino;
  int grey, colour;
} wv_world_image;

/* What a hit on a triangle reads first, in one cache line: its unit geometric
 * normal (the edges' cross product, normalised) and its corners' normals; flat
 * (1) when the three are the same: then nrm[0] is their normalised value (the
 * shading normal everywhere on the triangle, without interpolating), ng is turned
 * to its side (as make_surface would), and nrm[1], nrm[2] complete it to an
 * orthonormal frame (the bounce's, without computing it per hit). */
typedef struct {
  float ng[3];
  float nrm[3][3];
  int flat;
  float pad[3];
} wv_face;

/* Per triangle of a mesh with a fabric on it, what a hit reads next, in one cache
 * line: its corners' UVs and tangents (the mesh's; 0 without them) and the
 * tangents' handedness (the first corner's w; 1 without tangents). */
typedef struct {
  float uv[3][2];
  float tan[3][3];
  float w_sign;
} wv_face_uv;

/* Per triangle of a mesh with a fabric on it: the UV change per unit move in its
 * plane (rows du/dP and dv/dP). */
typedef struct {
  float gu[3], gv[3];
} wv_uv_grad;

/* The probability that a fabric's bounce goes through the sheet (integrator.c). */
float wv_back_prob(const wv_fabric *f);

/* The faces of mesh m (nt of them) into out, and into fuv and grad (unless NULL)
 * their corners' UVs and tangents and their UV gradients. */
void wv_faces_make(const wv_mesh *m, wv_face *out, wv_face_uv *fuv, wv_uv_grad *grad);

struct wv_world {
  wv_mesh *meshes; /* one per object */
  wv_face **faces; /* per object, per triangle (on 64-byte lines) */
  wv_face_uv **face_uv; /* per object, per triangle (on 64-byte lines); NULL for a mesh without a fabric */
  wv_uv_grad **uv_grad; /* per object, per triangle; NULL for a mesh without a fabric */
  int *material;   /* per object */
  int nobjects;
  wv_world_material *mats;
  int nmats;
  wv_world_image *images; /* edit maps and masks */
  int nimages;
  wv_tracer *tracer;
  int has_env;
  wv_envmap env;
  float scene_radius; /* of the meshes' bounding sphere, for ray offsets */
  /* Rays that leave a plane: per object, planar (all its vertices within plane_tol of
   * one plane, e.g. a floor) and the box around all the other objects (padded), which
   * a ray leaving it must enter to meet anything (wv_world_leaves_scene). */
  int *planar;
  float (*others)[2][3];
  float plane_tol;
};

/* Whether the ray from o along d, leaving planar object obj from a point at least
 * 4 plane_tol off its plane on the side d points to, surely meets nothing: it misses
 * the box around the other objects (so the tracer need not be asked). The slabs
 * without branches (the signs of d are not predictable); the box's padding covers
 * the rounding; a 0 in d as 1e-30 (the slab then reached beyond any other's, or
 * never left). */
static inline int wv_world_leaves_scene(const wv_world *w, int obj, const float o[3], const float d[3]) {
  const float *lo = w->others[obj][0], *hi = w->others[obj][1];
  if (!(lo[0] <= hi[0])) return 1; /* no other object */
  float t0 = 0, t1 = INFINITY;
  for (int k = 0; k < 3; k++) {
    float inv = 1.0f / (d[k] != 0.0f ? d[k] : 1e-30f), a = (lo[k] - o[k]) * inv, b = (hi[k] - o[k]) * inv;
    float near = a < b ? a : b, far = a < b ? b : a;
    t0 = near > t0 ? near : t0, t1 = far < t1 ? far : t1;
  }
  return t0 > t1;
}

/* cos and sin of 2 pi u for u in [0, 1) without libm (the bounce's turn about the
 * normal): the table's turn at the step below u (in double, rounded), turned on by
 * the rest, under 2 pi / WV_TURN_STEPS, whose sin and cos the Taylor series give to
 * x^3 and x^4 (the next terms below 1e-10). Error below 2e-7 (test_turn). */
#define WV_TURN_STEPS 256
typedef struct {
  float cs[WV_TURN_STEPS][2];
} wv_turn_table;
void wv_turn_table_make(wv_turn_table *t);
static inline void wv_turn(const wv_turn_table *t, float u, float *c, float *s) {
  float x = u * (float)WV_TURN_STEPS; /* exact; x - k too */
  int k = (int)x;
  k = k < 0 ? 0 : k >= WV_TURN_STEPS ? WV_TURN_STEPS - 1 : k;
  float a = (x - (float)k) * (float)(2 * 3.14159265358979323846 / WV_TURN_STEPS), a2 = a * a;
  float sa = a * (1.0f - a2 * (1.0f / 6)), ca = 1.0f - a2 * (0.5f - a2 * (1.0f / 24));
  const float *r = t->cs[k];
  *c = r[0] * ca - r[1] * sa, *s = r[1] * ca + r[0] * sa;
}

/* Bilinear lookup of an edit map (or mask) at UV (repeats; v up, the image's top row at v = 1). */
void wv_edit_lookup(const wv_image *img, float u, float v, float out[3]);

#endif
