/* Shared by the forward renderer and its derivative: the prepared scene
 * (camera, shape, light) and per-sample geometry. Internal to the library. */
#ifndef WOVEN_RENDER_INTERNAL_H
#define WOVEN_RENDER_INTERNAL_H

#include <math.h>
#include <stdint.h>

#include "kernel/kernel.h"
#include "util/hash.h"
#include "woven/params.h"
#include "woven/render.h"
#include "woven/scene.h"
#include "woven/yarn.h"

typedef struct {
  int width, height;
  float cpos[3], fwd[3], right[3], up[3];
  float tan_half, aspect;
  int shape, warp_along_axis;
  float radius, rot_c, rot_s, off[2], scale;
  float lpos[3], lint;
  const struct wv_footprint_s *cache; /* per-pixel footprints made once (wv_footprints) or NULL */
} wv_camera_rig;

/* One camera sample hitting the fabric: geometry in fabric tangent space. */
typedef struct {
  float fx, fy;     /* fabric coordinates, mm */
  float wi[3], wo[3]; /* to light and to camera, fabric tangent space (z = macro normal) */
  float light;      /* I / r^2 */
} wv_hit;

void wv_rig_prepare(const wv_scene *s, wv_camera_rig *rig);
/* wv_rig_prepare plus opt's footprint cache, refused if made for another geometry. */
wv_status wv_rig_prepare_opts(const wv_scene *s, const wv_render_opts *opt, wv_camera_rig *rig, wv_error *err);
/* What every render starts with: the scene validated, the fabric prepared, the
 * spp resolved (opt's, else the scene's) and the w x h x spp sample limit checked. */
wv_status wv_render_setup(const wv_scene *s, const wv_params *p, const wv_render_opts *opt, int w, int h,
                          wv_fabric *fab, int *spp, wv_error *err);

/* A permutation of 0 .. len-1 chosen by key (len <= 2^16): a bijection on the
 * next power of two (xor with the key, multiplications by odd numbers and
 * xorshifts are each invertible there), repeated until the value lands below len
 * (cycle walking: the walk stays on the bijection's cycle, so still a bijection). */
static inline uint32_t wv_permute(uint32_t i, uint32_t len, uint32_t key) {
  uint32_t mask = len - 1;
  mask |= mask >> 1, mask |= mask >> 2, mask |= mask >> 4, mask |= mask >> 8;
  do {
    i ^= key & mask;
    i = (i * 0x2c1b3c6dU) & mask;
    i ^= (key >> 16) & mask;
    i ^= i >> 2;
    i = (i * 0x297a2d39U + (key >> 8)) & mask;
    i ^= i >> 1;
  } while (i >= len);
  return i;
}

/* Sample grid of a pixel: nx columns by ny rows, nx = ceil(sqrt(spp)). */
static inline void wv_pixel_grid(int spp, int *nx, int *ny) {
  *nx = (int)ceilf(sqrtf((float)spp));
  *ny = (spp + *nx - 1) / *nx;
}
/* The pixel's hash (wv_hash2's first round) and its two permutation keys. */
static inline uint64_t wv_pixel_hash(int px, int py, int width, uint64_t seed) {
  return wv_mix64(((uint64_t)py * (uint64_t)width + (uint64_t)px) * 0x9e3779b97f4a7c15ULL + (seed ^ 0x70697865ULL));
}
static inline uint64_t wv_pixel_keys(uint64_t pixel_hash) { return wv_mix64(pixel_hash ^ 0x6d756c7469ULL); }

/* Sample s of spp inside pixel (px, py): correlated multi-jittered (Kensler 2013,
 * "Correlated Multi-Jittered Sampling"). Sample s sits in cell (s mod nx, s div nx)
 * of the grid, as plain jittered sampling, and inside the cell in a sub-column and
 * sub-row given by a per-pixel permutation, so that the x values of all samples
 * fall in distinct 1/(nx ny) strata, and so do the y values. Yarn edges and the
 * glint grid are close to axis-aligned in the image: their coverage then comes
 * out nearly exact, where independent cells leave a sqrt(nx) error per edge.
 * wv_pixel_sampler holds what every sample of the pixel shares. */
typedef struct {
  int nx, ny;
  uint64_t hash;       /* wv_pixel_hash */
  uint32_t keyx, keyy; /* the permutations' keys (wv_pixel_keys) */
} wv_pixel_sampler;

static inline void wv_pixel_sampler_init(wv_pixel_sampler *ps, int px, int py, int spp, int width, uint64_t seed) {
  wv_pixel_grid(spp, &ps->nx, &ps->ny);
  ps->hash = wv_pixel_hash(px, py, width, seed);
  uint64_t keys = wv_pixel_keys(ps->hash);
  ps->keyx = (uint32_t)keys, ps->keyy = (uint32_t)(keys >> 32);
}

static inline void wv_pixel_sampler_at(const wv_pixel_sampler *ps, int s, float *sx, float *sy) {
  uint64_t h = wv_mix64(ps->hash ^ ((uint64_t)s * 0xc2b2ae3d27d4eb4fULL)); /* = wv_hash2(pixel, s, seed) */
  float j1 = (float)(h >> 40) * (1.0f / 16777216.0f);
  float j2 = (float)((h >> 16) & 0xffffffULL) * (1.0f / 16777216.0f);
  int col = s % ps->nx, row = s / ps->nx;
  float subx = (float)wv_permute((uint32_t)row, (uint32_t)ps->ny, ps->keyx);
  float suby = (float)wv_permute((uint32_t)col, (uint32_t)ps->nx, ps->keyy);
  *sx = ((float)col + (subx + j1) / (float)ps->ny) / (float)ps->nx;
  *sy = ((float)row + (suby + j2) / (float)ps->nx) / (float)ps->ny;
}

/* Directions shared by all samples of a pixel. A pixel spans ~1e-3 rad seen from
 * the light and the camera, so light and view directions are taken at the pixel
 * centre while the fabric position (what changes across yarns) is per sample. */
typedef wv_dirs_f wv_dirs;

static inline void wv_dirs_from_hit(const wv_hit *hit, wv_dirs *d) { wv_dirs_make_f(hit->wi, hit->wo, hit->light, d); }

/* A pixel's footprint on the fabric: bilinear in the four corners when all four
 * and the centre hit the sample (exact for the plane up to perspective, and
 * within 1e-6 of a pixel on the cylinder away from its silhouette). */
typedef struct wv_footprint_s {
  int fast;              /* 1: use corners and dirs; 0: trace every sample */
  float fx[4], fy[4];    /* corners (0,0), (1,0), (0,1), (1,1) */
  wv_dirs dirs;
  int centre_hit;
} wv_footprint;

/* Trace the camera ray through image point (x, y) (pixels, top-left origin).
 * Returns 0 when the ray misses the sample or a direction is below its horizon. */
int wv_rig_trace(const wv_camera_rig *rig, float x, float y, wv_hit *hit);

void wv_footprint_prepare(const wv_camera_rig *rig, int px, int py, wv_footprint *fp);

static inline void wv_footprint_at(const wv_footprint *fp, float sx, float sy, float *fx, float *fy) {
  float w00 = (1 - sx) * (1 - sy), w10 = sx * (1 - sy), w01 = (1 - sx) * sy, w11 = sx * sy;
  *fx = w00 * fp->fx[0] + w10 * fp->fx[1] + w01 * fp->fx[2] + w11 * fp->fx[3];
  *fy = w00 * fp->fy[0] + w10 * fp->fy[1] + w01 * fp->fy[2] + w11 * fp->fy[3];
}

/* Radiance of one sample at fabric point (fx, fy) (the shading kernel in
 * scalar float), added to acc. */
static inline void wv_shade(const wv_fabric *f, const wv_dirs *d, float fx, float fy, float acc[3]) {
  float rad[3];
  wv_shade_f(f, &f->P, d, fx, fy, rad, NULL);
  for (int c = 0; c < 3; c++) acc[c] += rad[c];
}

/* A pixel's running sums: sample s is added to row s mod 8 (in sample order) and
 * the rows are added in a fixed tree at the end (wv_acc_total). The 8-wide path
 * keeps the rows in its vector lanes, so every path adds the same numbers in the
 * same order and the image does not depend on which one ran. */
#define WV_ACC_ROWS 8
/* The tree, for channel c of acc (float here, float or double in grad_kernel.inc). */
#define WV_ACC_TREE(acc, c)                                                                   \
  ((((acc)[0][c] + (acc)[1][c]) + ((acc)[2][c] + (acc)[3][c])) +                              \
   (((acc)[4][c] + (acc)[5][c]) + ((acc)[6][c] + (acc)[7][c])))
static inline void wv_acc_total(const float acc[WV_ACC_ROWS][3], float out[3]) {
  for (int c = 0; c < 3; c++) out[c] = WV_ACC_TREE(acc, c);
}

/* The samples of a pixel whose footprint is fast (fp->fast), eight at a time
 * where the CPU allows: their radiance added into the rows of acc,
 * bit-identical to calling wv_shade on each (render_simd.c). */
void wv_render_fast_pixel(const wv_fabric *f, const wv_footprint *fp, int px, int py, int spp, int width,
                          float acc[WV_ACC_ROWS][3]);
/* The other pixels (on the silhouette, or beside the sample): every sample
 * traced with wv_rig_trace, shaded with wv_shade, added into the rows of acc. */
void wv_render_traced_pixel(const wv_camera_rig *rig, const wv_fabric *f, int px, int py, int spp,
                            float acc[WV_ACC_ROWS][3]);

#endif
