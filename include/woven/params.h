/* woven: fabric parameters (SPEC section 5) and their JSON file format.
 * Units are in the keys: densities in yarns per inch, angles in degrees. */
#ifndef WOVEN_PARAMS_H
#define WOVEN_PARAMS_H

#include <stdint.h>
#include "woven/error.h"
#include "woven/weave.h"

#define WV_DENSITY_MIN 20.0  /* yarns per inch */
#define WV_DENSITY_MAX 250.0

typedef struct {
  char pattern[16];                  /* plain, twill, satin, twill90, satin90 or custom */
  int custom_rows;                   /* custom pattern only */
  char custom[WV_WEAVE_MAX][WV_WEAVE_MAX + 1];
  double density[2];                 /* yarns per inch, [WV_WARP], [WV_WEFT]: 20..250 */
  double heightfield[2];             /* beta: 0..2 */
  double diffuse[2][3];              /* k_d RGB: 0..1 */
  double specular[2][3];             /* k_s RGB: 0..1 */
  double transmission[2][3];         /* k_t RGB: 0..1, diffuse transmission colour (light through the yarn) */
  double transmission_specular[2][3]; /* k_st RGB: 0..1, the specular transmission's colour */
  double transmission_forward[2][3]; /* k_f RGB: 0..1, the colour of the light scattered on around the fibres' forward cone */
  double forward_width;              /* its width in the sine of the longitudinal angle: 0.05..1, default 0.2 */
  double roughness[2];               /* alpha: 0.01..1 */
  double twist_deg;                  /* psi: -60..60 */
  double inclination_deg;            /* u_max: 5..70 */
  double diffuse_blend;              /* w: 0..1 */
  int noise_level;                   /* Q: 0..10 */
  double thickness;                  /* T: > 0, default 2 */
  double yarn_width;                 /* fraction of the spacing: 0.1..1 */
  int64_t seed;                      /* noise seed (U_n, U_s) */
  int specular_noise;                /* 1: glints U_s on (default); 0: U_s = 1 */
} wv_params;

/* The parameter file's format version: 2 adds "transmission" (k_t), 3
 * "transmission_specular" (k_st), 4 "transmission_forward" (k_f) and "forward_width"; a file
 * without one of those keys reads with its default (wv_params_transmission_default), which
 * renders it as its version did. */
#define WV_PARAMS_VERSION 4

/* Prior mean of a built-in pattern (also the fit's start without a network). */
wv_status wv_params_default(const char *pattern, wv_params *p, wv_error *err);
/* A random draw from the dataset prior of SPEC section 5 for a built-in pattern
 * (the 90-degree patterns mirror their base: warp and weft ranges swapped, twist
 * negated). Deterministic in seed. */
wv_status wv_params_sample_prior(const char *pattern, uint64_t seed, wv_params *p, wv_error *err);
/* The transmission colours' defaults, per yarn type and channel: k_t = k_d / 2 (the prior's
 * mean: light through a yarn takes the yarn's colour), k_st = k_s (the fibres that
 * reflect the light are the ones that scatter it through) and k_f = 0 (no forward band: the
 * model before it existed); forward_width 0.2. */
void wv_params_transmission_default(wv_params *p);

/* Whether p has a forward band: any k_f above 0. */
int wv_params_has_forward_band(const wv_params *p);

/* Every value in range, pattern known; the message names the key. */
wv_status wv_params_validate(const wv_params *p, wv_error *err);
/* Parse from a JSON text; 'source' names it in messages (a file name). */
wv_status wv_params_parse(const char *json, const char *source, wv_params *p, wv_error *err);
wv_status wv_params_read(const char *path, wv_params *p, wv_error *err);
/* JSON text (malloc'ed, caller frees) and atomic file write. */
char *wv_params_to_json(const wv_params *p);
wv_status wv_params_write(const char *path, const wv_params *p, wv_error *err);

/* The continuous parameters, in a fixed order (the differentiable renderer's and
 * the fit's vector). Values are in the file's units (angles in degrees). The
 * reflection model's come first (WV_P_REFLECT_COUNT of them: what a front-lit
 * photo shows, and FabricNet predicts); the transmission colours follow (k_t, k_st, then k_f). */
typedef enum {
  WV_P_BETA_WARP, WV_P_BETA_WEFT,
  WV_P_KD_WARP_R, WV_P_KD_WARP_G, WV_P_KD_WARP_B,
  WV_P_KD_WEFT_R, WV_P_KD_WEFT_G, WV_P_KD_WEFT_B,
  WV_P_KS_WARP_R, WV_P_KS_WARP_G, WV_P_KS_WARP_B,
  WV_P_KS_WEFT_R, WV_P_KS_WEFT_G, WV_P_KS_WEFT_B,
  WV_P_ALPHA_WARP, WV_P_ALPHA_WEFT,
  WV_P_UMAX_DEG, WV_P_BLEND, WV_P_TWIST_DEG,
  WV_P_KT_WARP_R, WV_P_KT_WARP_G, WV_P_KT_WARP_B,
  WV_P_KT_WEFT_R, WV_P_KT_WEFT_G, WV_P_KT_WEFT_B,
  WV_P_KST_WARP_R, WV_P_KST_WARP_G, WV_P_KST_WARP_B,
  WV_P_KST_WEFT_R, WV_P_KST_WEFT_G, WV_P_KST_WEFT_B,
  WV_P_KF_WARP_R, WV_P_KF_WARP_G, WV_P_KF_WARP_B,
  WV_P_KF_WEFT_R, WV_P_KF_WEFT_G, WV_P_KF_WEFT_B,
  WV_P_COUNT
} wv_param_id;
#define WV_P_REFLECT_COUNT WV_P_KT_WARP_R /* 19 */

const char *wv_param_name(int id);              /* e.g. "diffuse.warp[1]" */
void wv_param_range(int id, double *lo, double *hi);
/* The range of yarn_width (not a continuous parameter of the gradient: a photo pair's fit searches it). */
void wv_param_range_width(double *lo, double *hi);
/* The range of forward_width (likewise searched by a photo pair's fit). */
void wv_param_range_forward_width(double *lo, double *hi);
double wv_param_get(const wv_params *p, int id);
void wv_param_set(wv_params *p, int id, double value);

wv_status wv_params_weave(const wv_params *p, wv_weave *w, wv_error *err);

#endif
