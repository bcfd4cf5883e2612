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

#include <stddef.h>

#include "woven/error.h"
#include "woven/image.h"

typedef struct {
  int w, h;
  float *rgb;     /* w x h x 3 radiance, times the strength */
  float *cdf_row; /* h + 1: marginal CDF of the rows */
  float *cdf_col; /* h x (w + 1): each row's conditional CDF */
  double total;   /* sum of the sampling weights (luminance x sin theta) */
  float rot_c, rot_s; /* rotation about +y */
  /* Lookup tables (what the path tracer reads per sample, kept small and local):
   * texel: w x h x 4, the radiance and the pixel's solid-angle density (one cache
   * line per lookup); guide_row: WV_ENV_GUIDE + 1 and guide_col: h x
   * (WV_ENV_GUIDE + 1), where the CDF passes i / WV_ENV_GUIDE (search start points).
   * A direction's pixel without trigonometry: edge_y (h + 1), cos theta at the rows'
   * edges; edge_x (w + 1), the columns' edges as pseudo-angles (emitters/envmap.c);
   * guide_y (2 h + 1) and guide_x (2 w + 1), the row and the column at each of
   * equal steps of a coordinate close to theta and of the pseudo-angle; centre_x
   * (w x 2), the unit horizontal world direction (x, z) through each column's centre. */
  float *texel;
  int *guide_row, *guide_col;
  float *edge_y, *edge_x, *centre_x;
  int *guide_y, *guide_x;
} wv_envmap;
#define WV_ENV_GUIDE 64

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
/* Both at once (one lookup): the radiance from d in rgb; returns the pdf of d. */
float wv_envmap_lookup(const wv_envmap *e, const float d[3], float rgb[3]);
/* wv_envmap_lookup in two halves: wv_envmap_at finds d's texel and starts
 * fetching it, wv_envmap_read (later, after other work) reads it. */
typedef struct {
  size_t texel;
} wv_env_at;
wv_env_at wv_envmap_at(const wv_envmap *e, const float d[3]);
float wv_envmap_read(const wv_envmap *e, wv_env_at a, float rgb[3]);
/* A direction drawn with density ~ luminance x (u1, u2 in [0,1)): a pixel by the
 * CDFs, then a point uniform in solid angle within it (uniform in cos theta and in
 * longitude); returns its pdf (0 when the map is black) and the radiance in rgb. */
float wv_envmap_sample(const wv_envmap *e, float u1, float u2, float d[3], float rgb[3]);
/* wv_envmap_sample for n pairs u[j] (the same results), faster than one by one. */
typedef struct {
  float d[3], rgb[3], pdf;
} wv_env_sample;
void wv_envmap_sample_n(const wv_envmap *e, int n, const float (*u)[2], wv_env_sample *out);

/* The built-in environments: "studio" (dark grey room, a large warm key soft box,
 * a fill and a rim box), "sky" (blue sky, bright horizon, ground, a sun 40 degrees
 * up) and "white" (uniform 1). width x width/2 pixels (16..8192). */
wv_status wv_env_builtin(const char *name, int width, wv_image *out, wv_error *err);
int wv_env_is_builtin(const char *name);

#endif
