/* The differentiable renderer's per-pixel loop, compiled twice from
 * grad_kernel.inc: in float (grad_f.c, the production path, bitwise the
 * forward renderer's arithmetic) and in double (grad_d.c, for checks).
 * Internal to the library. */
#ifndef WOVEN_GRAD_INTERNAL_H
#define WOVEN_GRAD_INTERNAL_H

#include "render/render_internal.h"
#include "woven/weave.h"

/* Per yarn type, the per-pixel sums (times the light, divided by spp) of what
 * radiance is linear in and of their derivatives (WV_J_*, kernel/kernel.h). */
typedef struct {
  double rad[3]; /* radiance; in float mode exactly the forward renderer's float value */
  double J[2][WV_J_COUNT];
} wv_grad_pixel;

void wv_grad_pixel_f(const wv_camera_rig *rig, const wv_fabric *fab, const wv_shade_params_f *P, int px, int py,
                     int spp, wv_grad_pixel *out);
void wv_grad_pixel_d(const wv_camera_rig *rig, const wv_fabric *fab, const wv_shade_params_d *P, int px, int py,
                     int spp, wv_grad_pixel *out);

#endif
