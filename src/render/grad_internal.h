/* The differentiable renderer's per-pixel kernel, compiled twice from
 * grad_kernel.inc: in float (grad_f.c, the production path, bitwise the
 * forward renderer's arithmetic) and in double (grad_d.c, for checks).
 * Internal to the library. */
#ifndef WOVEN_GRAD_INTERNAL_H
#define WOVEN_GRAD_INTERNAL_H

#include "render/render_internal.h"
#include "woven/weave.h"

/* Per yarn type, the per-pixel sums (times the light, divided by spp) of what
 * radiance is linear in, and of their derivatives with respect to the
 * non-linear parameters. Radiance of channel c is
 *   sum over types y of ks[y][c] J[y][S] + kd[y][c] J[y][DF]. */
enum {
  WV_J_S,        /* specular factor f_s mu_i / k_s (with the glint) */
  WV_J_DF,       /* diffuse factor f_d mu_i / k_d */
  WV_J_S_BETA,   /* d S / d beta of this type */
  WV_J_S_ALPHA,  /* d S / d alpha of this type */
  WV_J_S_UMAX,   /* d S / d u_max (radians) */
  WV_J_S_PSI,    /* d S / d psi (radians) */
  WV_J_DF_BETA,  /* d DF / d beta */
  WV_J_DF_UMAX,  /* d DF / d u_max (radians) */
  WV_J_DF_BLEND, /* d DF / d w */
  WV_J_COUNT
};

typedef struct {
  double rad[3]; /* radiance; in float mode exactly the forward renderer's float value */
  double J[2][WV_J_COUNT];
} wv_grad_pixel;

/* The continuous parameters and derived constants the kernel reads. Filled
 * either from the forward renderer's float fabric (values exactly the floats it
 * uses) or from the parameters in double. */
typedef struct {
  double beta[2], alpha[2], kd[2][3], ks[2][3], blend, thickness;
  double sin_psi, cos_psi;
  double umax_over_spacing[2]; /* u_max / spacing, as wv_yarn_model */
  double inv_spacing[2];       /* d(u_max / spacing) / d u_max */
  double v_scale[2];
  double inv_len[WV_WEAVE_MAX + 1];
} wv_grad_model;

void wv_grad_pixel_f(const wv_camera_rig *rig, const wv_fabric *fab, const wv_grad_model *gm, int px, int py,
                     int spp, wv_grad_pixel *out);
void wv_grad_pixel_d(const wv_camera_rig *rig, const wv_fabric *fab, const wv_grad_model *gm, int px, int py,
                     int spp, wv_grad_pixel *out);

#endif
