/* The shading kernel: the fabric model evaluated at surface points, the one
 * place where the yarn geometry, the SGGX/SpongeCake specular, the blended
 * diffuse and their derivatives are written (kernel/kernel_impl.h). Internal
 * to the library; every renderer (the capture-scene integrators, the BRDF and
 * yarn functions of the public API, a mesh renderer) shades through it.
 *
 * Entry points for a renderer that brings its own geometry:
 *
 *   void wv_kernel_shade(const wv_fabric *f, float x, float y,
 *                        const float wi[3], const float wo[3], float out[3]);
 *   void wv_kernel_shade8(const wv_fabric *f, const float x[8], const float y[8],
 *                         const float wi[3][8], const float wo[3][8], float out[3][8]);
 *
 * (x, y): the point in fabric coordinates, millimetres (the weave's frame: x
 * along the weft, y along the warp; a mesh renderer maps its UV there, e.g.
 * x = u * tile_mm[0]). wi (toward the light) and wo (toward the viewer): unit
 * vectors in the fabric's local tangent frame at the point, z the macro
 * normal, x the fabric's x direction. out[c] = f_r(wi, wo) mu_i per RGB channel
 * (specular k_s U_s f_s mu_i plus diffuse k_d f_d mu_i): multiply by the
 * light's irradiance I / r^2 for radiance. 0 where wi or wo is below the
 * surface or the point falls in a gap between yarns (these entry points
 * reflect only). wv_kernel_shade8 shades eight points at once (SIMD; out[c][i]
 * is point i, bit-identical to wv_kernel_shade on each). f comes from
 * wv_fabric_prepare(params).
 *
 *   int wv_kernel_open(const wv_fabric *f, float x, float y);
 *
 * 1 where (x, y) falls in an open gap (no yarn of either type over it: light
 * passes straight through the cloth), else 0.
 *
 * Light through the cloth: the generic forms below shade a light behind the
 * cloth (wi.z < 0, wo.z > 0) with the kernel's transmission (wv_shade_trans,
 * docs/model.md); the capture rig's renderer and the mesh renderer use them so.
 *
 * Inside the library the generic forms are called directly and inline:
 * wv_shade_f / wv_shade_8 / wv_shade_d (one float, eight floats, double) take
 * the points, the directions (wv_dirs_*) and optionally return the
 * derivative sums the gradient renderer needs (wv_shade_grad_*). */
#ifndef WOVEN_KERNEL_H
#define WOVEN_KERNEL_H

#include <stdint.h>

#include "kernel/fastmath.h"
#include "kernel/lanes.h"
#include "woven/error.h"
#include "woven/params.h"
#include "woven/yarn.h"

/* What the gradient renderer sums per yarn type and pixel (times the light):
 * radiance of channel c = sum over types y of ks[y][c] S + kd[y][c] DF, and
 * the derivatives of S and DF with respect to the non-linear parameters. With
 * the light behind the cloth the same sums hold the transmission: S the
 * specular's, DF the diffuse's, whose albedos are then kst[y][c] and kt[y][c],
 * and F the forward band's (albedo kf[y][c]; 0 with the light in front). */
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
  WV_J_F,        /* the forward band's factor F_f / k_f (no other parameter moves it) */
  WV_J_COUNT
};

/* The parameters the yarn frame's tangents are taken with respect to. */
enum { WV_T_BETA, WV_T_UMAX, WV_T_PSI };

/* The continuous parameters in the kernel's form, in float (what the
 * renderers use) or double (gradient checks). Index [WV_WARP] / [WV_WEFT]. */
#define WV_SHADE_PARAMS(R)                                                                          \
  struct {                                                                                          \
    R beta[2];                 /* heightfield scaling */                                            \
    R uos[2];                  /* u_max / spacing[t] (radians per mm along a yarn of the other type) */ \
    R ispc[2];                 /* 1 / spacing[t]: d uos / d u_max */                                \
    R vsc[2];                  /* pi / (spacing[t] yarn_width) */                                    \
    R sin_psi, cos_psi;        /* fiber twist */                                                     \
    R noise;                   /* 0.1 Q */                                                           \
    R alpha[2], k[2], ia2m1[2], pia[2], ia[2]; /* alpha, 1 - alpha^2, 1/alpha^2 - 1, pi alpha, 1/alpha */ \
    R kd[2][3], ks[2][3];      /* albedos */                                                         \
    R kt[2][3], kst[2][3];     /* transmission colours: diffuse, specular */                        \
    R kf[2][3];                /* the forward band's colour */                                       \
    R fw_k, fw_norm;           /* 1 / (2 width^2); 1 / the band's mean at normal incidence */       \
    R blend, thickness;        /* diffuse blend w, SpongeCake thickness T */                         \
  }
typedef WV_SHADE_PARAMS(float) wv_shade_params_f;
typedef WV_SHADE_PARAMS(double) wv_shade_params_d;

/* Fabric parameters prepared for shading. */
typedef struct {
  wv_yarn_model ym;    /* the geometry's discrete part, and its parameters in float */
  wv_shade_params_f P; /* the continuous parameters in float */
  int glints;          /* specular noise U_s on */
  float inv_glint_cell[2]; /* 8 / spacing along x and y: the glint grid */
  /* -ln(1 - xi) at the midpoints of 4096 equal bins of xi: U_s without a log per
   * sample (mean 0.9998 instead of 1; the largest value 9.0 instead of 10). */
  float glint_table[4096];
  uint64_t seed;
} wv_fabric;

wv_status wv_fabric_prepare(const wv_params *p, wv_fabric *f, wv_error *err);
/* The geometry fields of P (beta .. noise) from a yarn model. */
void wv_shade_params_from_yarn(const wv_yarn_model *m, wv_shade_params_f *P);
/* Roughness alpha of yarn type t and the terms derived from it (a renderer that
 * edits alpha per point sets it through this). */
void wv_shade_params_set_roughness(wv_shade_params_f *P, int t, float a);
/* The forward band's mean g = 1 / (1 + s^2 / (2 width^2))^2 over a cosine-weighted hemisphere of
 * outgoing directions with the light straight behind (what normalises the band). */
double wv_forward_band_mean(double width);
/* All of P in double, straight from the parameters (for gradient checks). */
void wv_shade_params_double(const wv_params *p, wv_shade_params_d *P);

#define WV_LANE WV_LANE_F
#include "kernel/lane_begin.h"
#include "kernel/kernel_impl.h"
#include "kernel/lane_end.h"
#define WV_LANE WV_LANE_8
#include "kernel/lane_begin.h"
#include "kernel/kernel_impl.h"
#include "kernel/lane_end.h"
#define WV_LANE WV_LANE_D
#include "kernel/lane_begin.h"
#include "kernel/kernel_impl.h"
#include "kernel/lane_end.h"

void wv_kernel_shade(const wv_fabric *f, float x, float y, const float wi[3], const float wo[3], float out[3]);
void wv_kernel_shade8(const wv_fabric *f, const float x[8], const float y[8], const float wi[3][8],
                      const float wo[3][8], float out[3][8]);
int wv_kernel_open(const wv_fabric *f, float x, float y);

#endif
