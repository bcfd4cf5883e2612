/* woven: tileable texture maps of a fabric for other renderers (SPEC section 8).
 * One tile covers exactly one repeat of the weave (cols warp yarns x rows weft
 * yarns); its physical size is tile_mm. Noise (U_n) repeats with the tile, so
 * the maps tile seamlessly. Vectors are in tangent space: x along the weft
 * (image right), y along the warp (image up), z out of the surface. */
#ifndef WOVEN_MAPS_H
#define WOVEN_MAPS_H

#include "woven/error.h"
#include "woven/image.h"
#include "woven/params.h"
#include "woven/yarn.h"

typedef struct {
  wv_image normal;    /* unit normal, xyz in [-1,1] */
  wv_image tangent;   /* unit fiber tangent (sign is arbitrary: fibers have no direction) */
  wv_image yarn_id;   /* R: warp, G: weft (1 where visible; both 0 in a gap), B: segment random in [0,1) */
  wv_image height;    /* heightfield, mm (grey in all three channels) */
  wv_image diffuse;   /* k_d, linear RGB */
  wv_image specular;  /* k_s, linear RGB */
  wv_image roughness; /* alpha (grey) */
  wv_image transmission; /* light through the cloth at normal incidence: k_t + k_f of the yarn it passes times
                          * the diffuse transmittance of the cloth's thickness there (at most 1), linear RGB; 0 in
                          * an open gap */
  wv_image open;      /* 1 in an open gap (no yarn of either kind: light passes straight through), else 0 (grey) */
  double tile_mm[2];  /* physical width and height of one tile, mm */
  double height_max;  /* largest height value, mm */
} wv_maps;

/* The transmission map's value at a point (woven's diffuse transmission and forward band at
 * normal incidence, where the band carries k_f): k_t + k_f of the yarn the light passes times
 * the cloth's diffuse transmittance there, at most 1, linear RGB; 0 in an open gap. */
void wv_maps_transmission_at(const wv_params *p, const wv_yarn_point *yp, float out[3]);

/* size x size pixels per tile (1..8192), one sample at each pixel centre. */
wv_status wv_maps_generate(const wv_params *p, int size, wv_maps *m, wv_error *err);
void wv_maps_free(wv_maps *m);
/* Writes <dir>/<map>.png (8-bit: vectors as 0.5 v + 0.5, albedos sRGB-encoded,
 * height normalised by height_max) and/or <dir>/<map>.exr (raw floats), plus
 * <dir>/maps.json describing tile size and encodings. format: "png", "exr" or "both".
 * The directory is written whole (wv_outdir): it appears, or replaces an earlier
 * maps directory, complete or not at all; a directory holding other files is refused. */
wv_status wv_maps_write(const wv_maps *m, const char *dir, const char *format, wv_error *err);

#endif
