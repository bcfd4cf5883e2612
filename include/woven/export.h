/* woven: the fabric leaves woven for other tools. A glTF 2.0 binary (.glb) holds
 * a triangle mesh and the fabric baked into standard PBR textures over one weave
 * tile: base colour, tangent-space normal, metallic-roughness,
 * KHR_materials_anisotropy, KHR_materials_sheen, and KHR_texture_transform tiling
 * that keeps the tile's physical size. The baking fits, per texel and by least
 * squares, the standard model (src/export/std_model.h) to the woven BRDF over a
 * fixed set of light and view directions (docs/export.md). */
#ifndef WOVEN_EXPORT_H
#define WOVEN_EXPORT_H

#include <stdint.h>

#include "woven/error.h"
#include "woven/image.h"
#include "woven/params.h"
#include "woven/scene.h"

/* What `woven export` and `woven view` start from: a parameter file, or the
 * directory of a finished fit (params.json, written last, marks it finished;
 * scene.json is the scene the fit was registered in; photo.png the photo at the
 * scene's size). */
typedef struct {
  wv_params params;
  int is_fit;            /* a fit directory */
  int has_scene;         /* scene: the fit's scene.json */
  wv_scene scene;
  int has_photo;         /* photo: path of the fit's photo.png */
  char photo[4096];
} wv_source;
wv_status wv_source_load(const char *path, wv_source *src, wv_error *err);
/* The files a source was read from, for output checks: path itself, and for a fit's
 * directory its params.json, scene.json and photo.png. The names are written into
 * names and pointed to by paths; returns how many (at most 4). */
int wv_source_inputs(const char *path, const wv_source *src, char names[4][4096], const char **paths);

/* A triangle mesh as the exporter (and the viewer) take it. Positions in metres
 * (glTF's unit), +y up; unit normals; UVs with u along the fabric's weft (x) and
 * v downward (glTF's texture convention: fabric y = -v uv_mm); tangents along +u
 * with the bitangent sign in w (glTF's TANGENT), NULL to have them derived from
 * the UVs. The arrays belong to whoever filled the struct; wv_tri_mesh_free
 * frees the ones woven's generators allocated. */
typedef struct {
  int vertex_count, index_count; /* index_count = 3 x triangles */
  float *positions;              /* 3 per vertex */
  float *normals;                /* 3 per vertex */
  float *uvs;                    /* 2 per vertex */
  float *tangents;               /* 4 per vertex, or NULL */
  uint32_t *indices;
  double uv_mm;                  /* millimetres of fabric per UV unit */
} wv_tri_mesh;

/* A flat square of side_mm in the x-z plane facing +y, UVs 0..1 (uv_mm = side_mm). */
wv_status wv_tri_mesh_quad(double side_mm, wv_tri_mesh *m, wv_error *err);
/* A square sheet of side_mm laid over a sphere of radius_mm (centre at the
 * origin, the sheet's centre on its top): procedural, not simulated. On the cap
 * the sheet keeps the arc length along every radial line; past the contact
 * circle it falls away on a curve that turns to vertical, and radial folds take
 * up the circumference it no longer needs. n x n quads; UVs are the flat
 * sheet's coordinates (0..1), so the fabric keeps its scale along the radii. */
wv_status wv_tri_mesh_drape(double side_mm, double radius_mm, int n, wv_tri_mesh *m, wv_error *err);
/* Tangents from UVs and normals (per triangle, accumulated, Gram-Schmidt). */
wv_status wv_tri_mesh_tangents(wv_tri_mesh *m, wv_error *err);
/* Rejects meshes the exporter cannot write (NaN, indices out of range, ...). */
wv_status wv_tri_mesh_validate(const wv_tri_mesh *m, wv_error *err);
void wv_tri_mesh_free(wv_tri_mesh *m);

/* 0 in a field (a zeroed struct, or NULL) takes its default. */
typedef struct {
  int texture_size; /* texels per tile side, 8..1024 (0: 64) */
  int samples;      /* woven samples per texel side, 1..8 (0: 3, i.e. 9 positions) */
  int directions;   /* light/view direction pairs of the fit, 8..256 (0: 48) */
  int threads;      /* 0: all cores */
} wv_bake_opts;
/* The defaults written out (what 0 stands for). */
void wv_bake_opts_default(wv_bake_opts *o);

typedef struct {
  /* texture_size x texture_size, one weave tile (row 0 at fabric y = 0, downward).
   * Each holds what its PNG stores: values in [0,1], already on the 8-bit grid. */
  wv_image base_color;  /* base colour, sRGB-encoded */
  wv_image normal;      /* 0.5 n + 0.5, n the unit tangent-space normal */
  wv_image metal_rough; /* glTF layout: R 1, G roughness, B metallic */
  wv_image anisotropy;  /* glTF layout: RG 0.5 d + 0.5 (d the axis in the tangent plane), B strength */
  wv_image sheen;       /* RGB sheen colour, sRGB-encoded; A sheen roughness */
  /* The light through the cloth (docs/export.md): KHR_materials_diffuse_transmission's
   * colour (RGB, sRGB-encoded) and factor (A), whose product is the texel's mean of woven's
   * diffuse transmission at normal incidence (wv_maps_transmission_at); and the texel's
   * open area (grey, linear), KHR_materials_transmission's factor. */
  wv_image diffuse_transmission;
  wv_image open;
  int has_open;         /* some texel has open area (else no KHR_materials_transmission) */
  double tile_mm[2];    /* physical size of the tile */
  /* The fit's residual, over all texels, direction pairs and channels, of the
   * model with the stored (8-bit) textures against the woven BRDF x cosine. */
  double rms, target_rms, relative; /* relative = rms / target_rms */
  int directions;
} wv_bake;

wv_status wv_bake_fabric(const wv_params *p, const wv_bake_opts *o, wv_bake *b, wv_error *err);
void wv_bake_free(wv_bake *b);

/* Writes the .glb (atomically: a failure leaves no file and keeps an earlier one).
 * The material's extras record the tile size, the fit's residual and p. */
wv_status wv_gltf_write(const char *path, const wv_tri_mesh *m, const wv_bake *b, const wv_params *p,
                        wv_error *err);

#endif
