/* woven: the forward renderer. Renders fabric parameters in a capture scene:
 * stratified supersampling of each pixel, bent-cylinder geometry, SGGX/SpongeCake
 * specular and blended Lambert diffuse under one point light. Threads: OpenMP.
 * Deterministic: every sample position and noise value is a hash of
 * (pixel, sample, seed), so results do not depend on the thread count. */
#ifndef WOVEN_RENDER_H
#define WOVEN_RENDER_H

#include "woven/error.h"
#include "woven/image.h"
#include "woven/params.h"
#include "woven/scene.h"

/* Bumped when the same parameters, scene and seed render to another image (a new
 * sampler, say): data made by an older renderer is not extended with newer images.
 * 1: jittered samples (renderer version 1); 2: correlated multi-jittered samples; 3: their
 * grid as many cells as samples at any spp (the same images as 2 where 2's grid was full: a
 * square spp, or 2, 6, 12, ...). */
#define WV_RENDER_VERSION 3

/* Per-pixel camera geometry of one scene (where each pixel's corners land on the
 * fabric, light and view directions). It does not depend on the fabric, so a fit
 * or a search that renders one scene many times makes it once. */
typedef struct wv_footprints wv_footprints;
wv_status wv_footprints_create(const wv_scene *s, int threads, wv_footprints **out, wv_error *err);
void wv_footprints_free(wv_footprints *f);

typedef struct {
  int spp;            /* samples per pixel; 0 = the scene's */
  int threads;        /* 0 = OpenMP default */
  /* Called now and then from one thread with the fraction done (may be NULL). */
  void (*progress)(void *user, double fraction);
  void *progress_user;
  /* Optional (NULL): footprints from wv_footprints_create for this scene's
   * geometry (a render with another geometry is refused). Same image either way. */
  const wv_footprints *footprints;
} wv_render_opts;

/* radiance (optional, may be NULL): linear radiance before the sensor response.
 * capture: the image as the scene's camera records it. Both allocated here. */
wv_status wv_render(const wv_scene *s, const wv_params *p, const wv_render_opts *opt, wv_image *capture,
                    wv_image *radiance, wv_error *err);

/* Fabric coordinates (mm, the frame the weave is laid out in) seen at image
 * position (x, y) in pixels (0.5, 0.5 is the first pixel's centre). Returns 0
 * when the ray misses the sample or the point faces away. */
int wv_render_fabric_at(const wv_scene *s, double x, double y, double f[2]);

/* The fabric's frame at the image centre: jt[k] the fabric mm one pixel along image axis k
 * (x, then y) moves, and *mm_per_px the scale (the square root of the map's determinant).
 * Returns 0 when the centre pixel or its neighbours miss the sample. */
int wv_render_centre_scale(const wv_scene *s, double jt[2][2], double *mm_per_px);

#endif
