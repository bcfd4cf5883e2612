/* Shared by the forward renderer and its derivative: the prepared scene
 * (camera, shape, light) and per-sample geometry. Internal to the library. */
#ifndef WOVEN_RENDER_INTERNAL_H
#define WOVEN_RENDER_INTERNAL_H

#include <math.h>
#include <stdint.h>

#include "util/hash.h"
#include "woven/params.h"
#include "woven/scene.h"
#include "woven/yarn.h"

typedef struct {
  int width, height;
  float cpos[3], fwd[3], right[3], up[3];
  float tan_half, aspect;
  int shape, warp_along_axis;
  float radius, rot_c, rot_s, off[2];
  float lpos[3], lint;
} wv_camera_rig;

/* Fabric parameters in the renderer's float form. */
typedef struct {
  wv_yarn_model ym;
  float kd[2][3], ks[2][3], alpha[2], blend, thickness;
  int glints;
  float glint_cell[2]; /* 1/8 of the yarn spacing along x and y */
  uint64_t seed;
} wv_fabric;

/* One camera sample hitting the fabric: geometry in fabric tangent space. */
typedef struct {
  float fx, fy;     /* fabric coordinates, mm */
  float wi[3], wo[3]; /* to light and to camera, fabric tangent space (z = macro normal) */
  float light;      /* I / r^2 */
} wv_hit;

void wv_rig_prepare(const wv_scene *s, wv_camera_rig *rig);
wv_status wv_fabric_prepare(const wv_params *p, wv_fabric *f, wv_error *err);

/* Stratified jittered sample position s of spp inside pixel (px, py). */
static inline void wv_pixel_sample(int px, int py, int s, int spp, int width, uint64_t seed, float *sx, float *sy) {
  int nx = (int)ceilf(sqrtf((float)spp));
  int ny = (spp + nx - 1) / nx;
  uint64_t h = wv_hash4((uint64_t)py * (uint64_t)width + (uint64_t)px, (uint64_t)s, seed, 0x70697865ULL);
  float j1 = (float)(h >> 40) * (1.0f / 16777216.0f);
  float j2 = (float)((h >> 16) & 0xffffffULL) * (1.0f / 16777216.0f);
  *sx = ((float)(s % nx) + j1) / (float)nx;
  *sy = ((float)(s / nx) + j2) / (float)ny;
}

/* Trace the camera ray through image point (x, y) (pixels, top-left origin).
 * Returns 0 when the ray misses the sample or a direction is below its horizon. */
int wv_rig_trace(const wv_camera_rig *rig, float x, float y, wv_hit *hit);

/* Specular glint multiplier U_s = min(-ln xi, 10), xi hashed on a fine grid. */
static inline float wv_glint(const wv_fabric *f, float fx, float fy) {
  if (!f->glints) return 1.0f;
  int64_t gx = (int64_t)floorf(fx / f->glint_cell[0]), gy = (int64_t)floorf(fy / f->glint_cell[1]);
  float xi = wv_u01(wv_hash4((uint64_t)gx, (uint64_t)gy, f->seed, 0x676c696eULL));
  float u = -logf(1.0f - xi); /* xi in [0,1): argument in (0,1] */
  return u < 10.0f ? u : 10.0f;
}

#endif
