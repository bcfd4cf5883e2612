/* woven: light sources of the mesh renderer. An environment map (equirectangular,
 * importance-sampled), point, spot and directional lights and a small rectangular
 * area light; and the project's own environments (a studio with soft boxes, a
 * sunny sky, a uniform white), generated in code: no downloads.
 *
 * Directions are world space, y up. Equirectangular mapping: column u in [0, 1)
 * is the longitude phi = 2 pi u - pi measured from -z toward +x, row v in [0, 1)
 * the polar angle theta = pi v from +y (the top row is the zenith). */
#ifndef WOVEN_EMITTERS_H
#define WOVEN_EMITTERS_H

#include "woven/error.h"
#include "woven/image.h"

typedef struct {
  int w, h;
  float *rgb;     /* w x h x 3 radiance, times the strength */
  float *cdf_row; /* h + 1: marginal CDF of the rows */
  float *cdf_col; /* h x (w + 1): each row's conditional CDF */
  double total;   /* sum of the sampling weights (luminance x sin theta) */
  float rot_c, rot_s; /* rotation about +y */
} wv_envmap;

/* Largest radiance of a map after its strength (refused above, with its pixel). */
#define WV_ENV_MAX_RADIANCE 1e18

/* Tables for importance sampling of img (3 channels; copied, scaled by strength,
 * turned by rotation_deg about +y). Every value times strength must be finite and
 * at most WV_ENV_MAX_RADIANCE. name is used in messages. */
wv_status wv_envmap_init(wv_envmap *e, const wv_image *img, double strength, double rotation_deg, const char *name,
                         wv_error *err);
void wv_envmap_free(wv_envmap *e);
/* Bytes wv_envmap_init allocates for a w x h map. */
size_t wv_envmap_bytes(int w, int h);
/* Radiance arriving from direction d (unit, pointing away from the scene point). */
void wv_envmap_eval(const wv_envmap *e, const float d[3], float rgb[3]);
/* Solid-angle density with which wv_envmap_sample picks d. */
float wv_envmap_pdf(const wv_envmap *e, const float d[3]);
/* A direction drawn with density ~ luminance x (u1, u2 in [0,1)); returns its
 * pdf (0 when the map is black) and the radiance in rgb. */
float wv_envmap_sample(const wv_envmap *e, float u1, float u2, float d[3], float rgb[3]);

/* The built-in environments: "studio" (dark grey room, a large warm key soft box,
 * a fill and a rim box), "sky" (blue sky, bright horizon, ground, a sun 40 degrees
 * up) and "white" (uniform 1). width x width/2 pixels (16..8192). */
wv_status wv_env_builtin(const char *name, int width, wv_image *out, wv_error *err);
int wv_env_is_builtin(const char *name);

#endif
