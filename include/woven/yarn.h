/* woven: bent-cylinder yarn geometry (SPEC section 3, paper section 3.1).
 * Evaluates, at a point (x, y) of the fabric plane in millimetres, which yarn is
 * visible and its normal n and fiber tangent t in fabric tangent space
 * (x along the weft, y along the warp, z the macroscopic normal). */
#ifndef WOVEN_YARN_H
#define WOVEN_YARN_H

#include <stdint.h>
#include "woven/error.h"
#include "woven/params.h"
#include "woven/weave.h"

typedef struct {
  wv_weave weave;
  float spacing[2];  /* [WV_WARP]: distance between warp yarns (mm, along x) = 25.4 / warp density;
                        [WV_WEFT]: distance between weft yarns (mm, along y) */
  float beta[2];     /* heightfield scaling per yarn type */
  float umax;        /* maximum inclination, radians */
  float psi;         /* fiber twist, radians */
  float width;       /* yarn width as a fraction of the spacing, (0, 1] */
  int noise_level;   /* Q, 0..10 */
  uint64_t seed;
  /* When > 0, segment identities repeat every period_rows x period_cols cells so
   * that a map of exactly that many cells tiles seamlessly. 0: never repeat. */
  int period_rows, period_cols;
  /* Derived by wv_yarn_model_update() from the fields above. */
  float sin_psi, cos_psi, sin_umax, cos_umax;
  float inv_spacing[2], umax_over_spacing[2], v_scale[2];
  /* weave.cell[r][c] as type | len << 8 | index << 16 at r * WV_WEAVE_MAX + c:
   * one 32-bit load per lookup, also for eight lookups at once */
  int32_t cellpack[WV_WEAVE_MAX * WV_WEAVE_MAX];
} wv_yarn_model;

/* The geometry model the renderer uses for these parameters. */
wv_status wv_params_yarn_model(const wv_params *p, wv_yarn_model *m, wv_error *err);
/* Recompute the derived fields; call after changing the weave, umax, psi,
 * spacing or width. */
void wv_yarn_model_update(wv_yarn_model *m);

typedef struct {
  int type;          /* WV_WARP, WV_WEFT, or -1 in a gap between yarns */
  float n[3], t[3];  /* unit normal and fiber tangent (n.t = 0), fabric tangent space */
  float height;      /* heightfield value, mm */
  float u, v;        /* inclination along and angle around the yarn (radians) */
  float beta;        /* the segment's heightfield scaling after noise U_n */
  uint64_t segment;  /* identity of the visible segment (hash) */
  /* Light through the cloth (docs/model.md): the yarn it passes (the visible one, or in
   * a gap beside it the crossing yarn underneath; -1 where no yarn covers the point: an
   * open gap, open = 1) and the cloth's local thickness there in yarn diameters (the
   * chords of the yarns' circular cross-sections, each in 0..1, summed over both). */
  int through;
  int open;
  float thickness;
} wv_yarn_point;

/* The cloth's diffuse transmittance where the light crosses an optical thickness tau
 * of yarn (the parameters' thickness T times wv_yarn_point.thickness): the two-stream
 * transmittance of a conservatively scattering slab, 1 / (1 + tau / 2)
 * (docs/model.md). Any arithmetic type (the renderer's 8-wide lanes too). */
#define WV_CLOTH_TRANSMITTANCE(tau) (1.0f / (1.0f + 0.5f * (tau)))

/* Fabric row/column of a point: rows grow toward -y, columns toward +x.
 * Evaluated by the shading kernel's geometry (src/kernel/), in scalar float. */
void wv_yarn_eval(const wv_yarn_model *m, float x, float y, wv_yarn_point *out);

#endif
