/* woven: scenes for the mesh renderer (`woven scene`): a camera, lights, objects
 * (mesh files or built-in shapes), materials (a fabric parameter file each, or a
 * Lambertian colour), spatially varying edits of the fabric over the mesh's UVs,
 * and the camera response of the capture scenes. The JSON format is in
 * docs/scene.md. Rendering is a path tracer on Embree (see wv_scene3d_render).
 *
 * Parsing never touches the file system (wv_scene3d_parse takes the text), so it
 * can be fuzzed; wv_world_load then reads the meshes, maps, environment and
 * parameter files the scene names, relative to the scene's directory. */
#ifndef WOVEN_SCENE3D_H
#define WOVEN_SCENE3D_H

#include <stddef.h>
#include <stdint.h>

#include "woven/error.h"
#include "woven/image.h"
#include "woven/params.h"
#include "woven/scene.h"

typedef enum { WV_LIGHT_POINT, WV_LIGHT_SPOT, WV_LIGHT_DIRECTIONAL, WV_LIGHT_AREA } wv_light_type;

typedef struct {
  wv_light_type type;
  double pos[3];      /* point, spot, area: position (centre of the area light) */
  double dir[3];      /* spot, area: unit direction it shines along; directional: unit direction toward the light */
  double color[3];    /* point, spot: intensity (radiance x mm^2 at 1 mm, like the capture scenes' light);
                         directional: irradiance on a surface facing it; area: emitted radiance */
  double cone_deg;    /* spot: half-angle of the full beam */
  double blend_deg;   /* spot: width of the soft edge inside the cone */
  double size[2];     /* area: width and height (mm) */
} wv_light3d;

typedef enum { WV_MAT_FABRIC = 0, WV_MAT_LAMBERT = 1 } wv_material_kind;

typedef struct {
  char name[64];
  wv_material_kind kind;
  char *params_path;     /* fabric: parameter file (resolved path) */
  double uv_mm[2];       /* fabric: mm of fabric per UV unit along u and v */
  double uv_offset_mm[2];
  double albedo[3];      /* lambert */
} wv_material3d;

typedef enum { WV_OBJ_MESH, WV_OBJ_QUAD, WV_OBJ_SPHERE, WV_OBJ_CYLINDER } wv_object_kind;

typedef struct {
  wv_object_kind kind;
  char *path;              /* mesh: file (resolved path) */
  int material;            /* index into materials */
  double centre[3];        /* quad, sphere, cylinder */
  double eu[3], ev[3];     /* quad: edge directions along u and v */
  double size[2];          /* quad: extent along eu, ev */
  double radius, length;   /* sphere, cylinder */
  int resolution;          /* segments (sphere, cylinder) or cells per side (quad) */
  double A[9], b[3];       /* transform x' = A x + b applied after loading/making */
} wv_object3d;

typedef enum {
  WV_EDIT_DIFFUSE_MULTIPLY, /* k_d *= map (RGB) */
  WV_EDIT_DIFFUSE_REPLACE,  /* k_d = map (RGB) */
  WV_EDIT_HEIGHTFIELD,      /* beta *= map (grey) */
  WV_EDIT_ROUGHNESS         /* alpha = map (grey), clamped to 0.01..1 */
} wv_edit_op;

typedef struct {
  wv_edit_op op;
  int material;  /* the fabric it applies to */
  char *map;     /* PNG or EXR over the UV square [0,1]^2 (repeats outside) */
  char *mask;    /* optional grey PNG or EXR of the map's size: where the edit applies (1 fully) */
  double gain;   /* the map's values are multiplied by this */
} wv_edit3d;

typedef enum { WV_ENV_NONE, WV_ENV_BUILTIN, WV_ENV_FILE, WV_ENV_UNIFORM } wv_env_kind;

typedef struct {
  char name[64];
  int width, height, spp;
  double cam_pos[3], cam_look_at[3], cam_up[3], vfov_deg;
  /* environment */
  wv_env_kind env;
  char env_name[16];  /* builtin */
  char *env_path;     /* file */
  double env_color[3];/* uniform */
  double env_strength, env_rotation_deg;
  int env_width;      /* builtin: pixels across */
  int env_visible;    /* camera rays that miss see the environment (else black) */
  wv_light3d *lights;
  int nlights;
  wv_material3d *materials;
  int nmaterials;
  wv_object3d *objects;
  int nobjects;
  wv_edit3d *edits;
  int nedits;
  /* integrator */
  int max_bounces;    /* path length after the camera hit (0: direct light only) */
  int yarn_samples;   /* fabric positions shaded per camera ray (sub-pixel yarns) */
  int opaque;         /* fabrics reflect only (render.transmission false): no light through the cloth */
  uint64_t seed;
  /* camera response: exposure, clip, encoding, gamma, falloff (wv_scene_response) */
  wv_scene response;
  size_t mesh_limit_bytes; /* memory limit of the job: meshes, ray tracer, edit maps, environment */
} wv_scene3d;

/* Limits: what one scene may hold. */
#define WV_SCENE3D_MAX_ITEMS 256 /* lights, materials, objects, edits: each */
#define WV_SCENE3D_DEFAULT_SPP 64
#define WV_SCENE3D_DEFAULT_YARN_SAMPLES 4
#define WV_SCENE3D_MAX_MAP_VALUE 1e6 /* a value of an edit map or mask */

/* Parses a scene text. source names it in messages; relative paths in it are
 * resolved against base_dir (NULL: the current directory). No file is read. */
wv_status wv_scene3d_parse(const char *json, const char *source, const char *base_dir, wv_scene3d *s,
                           wv_error *err);
/* Reads and parses a scene file (paths relative to its directory). */
wv_status wv_scene3d_read(const char *path, wv_scene3d *s, wv_error *err);

/* The files a scene refers to (fabric parameter files, meshes, edit maps and masks,
 * the environment map), resolved, into paths (borrowed from s); returns how many
 * there are, of which at most cap are stored. Outputs must be none of them. */
int wv_scene3d_inputs(const wv_scene3d *s, const char **paths, int cap);
void wv_scene3d_free(wv_scene3d *s);

/* Everything a scene refers to, loaded and prepared for rendering. */
typedef struct wv_world wv_world;
/* params_override (may be NULL) replaces the parameters of every fabric material.
 * threads: for the ray tracer's build (0 = all cores). */
wv_status wv_world_load(const wv_scene3d *s, const wv_params *params_override, int threads, wv_world **out,
                        wv_error *err);
void wv_world_free(wv_world *w);
/* Triangles and vertices over all objects. */
void wv_world_size(const wv_world *w, long long *triangles, long long *vertices);

/* A zeroed struct (or NULL) means the defaults: the scene's spp, all threads, no progress. */
typedef struct {
  int spp;     /* camera rays per pixel; 0 = the scene's */
  int threads; /* 0 = OpenMP default */
  void (*progress)(void *user, double fraction);
  void *progress_user;
} wv_scene3d_opts;

typedef struct {
  int spp;
  double rays;        /* rays traced (camera, bounce and shadow rays) */
  double shade_calls; /* fabric points shaded */
} wv_scene3d_stats;

/* Renders the scene with its world: a unidirectional path tracer. Per camera ray:
 * the closest hit through Embree; at each hit, next-event estimation (one shadow
 * ray per point, spot and directional light, one sample of the area lights and
 * of the environment, both weighted against the bounce by multiple importance
 * sampling, power heuristic), then a bounce in a cosine-weighted direction about
 * the shading normal, up to max_bounces, with Russian roulette from the third
 * vertex on. Fabrics transmit unless s->opaque: a light behind the sheet is
 * sampled through it (the kernel's transmission, the shadow ray from the other
 * side), the bounce may continue through it, and where a shaded position falls in
 * an open gap between yarns the path goes straight on. Camera-ray positions in the pixel come from the capture renderer's
 * correlated multi-jittered sampler; a fabric hit seen by the camera is shaded
 * at yarn_samples positions spread over the pixel's footprint on the cloth
 * (sharing the ray's light samples), so yarns smaller than a pixel are averaged.
 * Every random number is a hash of (pixel, sample, dimension, seed): the image
 * does not depend on the thread count. capture: after the scene's response;
 * radiance (may be NULL): linear. Both allocated here. */
wv_status wv_scene3d_render(const wv_scene3d *s, const wv_world *w, const wv_scene3d_opts *opt, wv_image *capture,
                            wv_image *radiance, wv_scene3d_stats *stats, wv_error *err);

/* A scene file rendered with every fabric's parameters replaced (the capture's
 * report shows a fit on the bundled draped cloth this way). A zeroed struct means
 * the scene's size and spp on all threads. */
typedef struct {
  int width, height; /* image size instead of the scene's (same camera); 0: the scene's */
  int spp;           /* 0: the scene's */
  int threads;       /* 0: OpenMP default */
} wv_scene3d_preview;

wv_status wv_scene3d_render_file(const char *scene_path, const wv_params *params, const wv_scene3d_preview *opt,
                                 wv_image *capture, wv_error *err);

#endif
