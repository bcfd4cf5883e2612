/* The renderers' shared parts: what every render starts with, the camera rig
 * with the render's footprints (footprints.c), and the 8-wide loop over a row's
 * samples (render/rows.c) that both the forward renderer (forward.c) and the
 * gradient renderer (gradient.c) run. Internal to the library. */
#ifndef WOVEN_RENDER_INTERNAL_H
#define WOVEN_RENDER_INTERNAL_H

#include "kernel/kernel.h"
#include "sampler/sampler.h"
#include "sensor/sensor.h"
#include "woven/params.h"
#include "woven/render.h"
#include "woven/scene.h"

/* What every render starts with: the scene validated, the fabric prepared, the
 * spp resolved (opt's, else the scene's) and the w x h x spp sample limit checked. */
wv_status wv_render_setup(const wv_scene *s, const wv_params *p, const wv_render_opts *opt, int w, int h,
                          wv_fabric *fab, int *spp, wv_error *err);

/* wv_rig_prepare plus opt's footprint cache, refused if made for another geometry. */
wv_status wv_rig_prepare_opts(const wv_scene *s, const wv_render_opts *opt, wv_camera_rig *rig, wv_error *err);

/* A pixel's sums: sample s is added to row s mod 8 (in sample order) and the
 * rows are added in a fixed tree at the end (WV_ACC_TREE): every path adds the
 * same numbers in the same order, so the image does not depend on which one
 * ran. The 8-wide loop keeps the rows in its vector lanes. */
#define WV_ACC_ROWS 8
#define WV_ACC_TREE(acc, c)                                                                   \
  ((((acc)[0][c] + (acc)[1][c]) + ((acc)[2][c] + (acc)[3][c])) +                              \
   (((acc)[4][c] + (acc)[5][c]) + ((acc)[6][c] + (acc)[7][c])))

/* A pixel's radiance and, per yarn type, its sums over the samples (times the
 * light, not yet divided by spp) of what radiance is linear in and of their
 * derivatives (WV_J_*, kernel/kernel.h). */
typedef struct {
  double rad[3];           /* radiance; in float mode exactly the forward renderer's float value */
  double J[2][WV_J_COUNT]; /* in float mode float sums, exactly */
} wv_grad_pixel;

/* Pixels x0 .. x0+n-1 of image row py, spp samples each, eight samples at a
 * time: their radiance into rad[i] (may be NULL) and, with grad non-NULL, the
 * derivative sums into grad[i]. Samples of one pixel share a vector when spp >=
 * 8; the remaining spp mod 8 of each pixel are packed with those of the next
 * pixels. */
void wv_render_row(const wv_camera_rig *rig, const wv_fabric *fab, int py, int x0, int n, int spp, float (*rad)[3],
                   wv_grad_pixel *grad);

/* One pixel, one sample at a time, in double (gradient checks). */
void wv_grad_pixel_d(const wv_camera_rig *rig, const wv_fabric *fab, const wv_shade_params_d *P, int px, int py,
                     int spp, wv_grad_pixel *out);

#endif
