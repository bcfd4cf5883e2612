/* woven: FabricNet's synthetic training set (docs/fabricnet.md): its description, its
 * samples, the camera augmentation of their images and the build of a whole set.
 * DIR/dataset.json: kind "woven-dataset", version, seed, per_pattern, patterns, spp,
 * renderer (WV_RENDER_VERSION that made the images; absent = 1),
 * scene (the full scene JSON), descriptor name and size, image size; a pair set (version
 * 3) also transmission_scene (the back-lit scene's JSON).
 * DIR/samples/<pattern>_<i>.json   parameters (the parameter file format)
 * DIR/samples/<pattern>_<i>.png    capture image, 8-bit
 * DIR/samples/<pattern>_<i>.t.png  a pair set's transmission image, 8-bit
 * DIR/samples/<pattern>_<i>.feat   descriptor features: 16-byte header + f16 values (a pair
 *                                  set's: the capture image's, then the transmission image's)
 * The feature file is written last (each file atomically): a sample is done when its
 * parameter file reads back with the sample's pattern, its PNG is whole (every chunk's
 * CRC, wv_png_check) and the feature file is complete and its CRC matches. */
#ifndef WOVEN_DATASET_H
#define WOVEN_DATASET_H

#include <stddef.h>
#include <stdint.h>

#include "woven/dist.h"
#include "woven/error.h"
#include "woven/image.h"
#include "woven/params.h"
#include "woven/scene.h"

#define WV_NET_PATTERNS 5
/* The five built-in patterns, in dataset order: plain, twill, satin, twill90, satin90. */
const char *wv_net_pattern(int i);

#define WV_DATASET_MAX_PER_PATTERN 1000000 /* most samples per pattern in a dataset */
#define WV_DATASET_VERSION 3 /* 1: the five earlier patterns; 2: every built-in, "augment"; 3: a pair set */
typedef struct {
  int version;  /* 1, 2 or 3: which patterns the samples cycle through (wv_dataset_pattern); 3 a pair set */
  int renderer; /* WV_RENDER_VERSION of the renderer that made the samples */
  int augment;  /* 1: images pass through wv_camera_augment (version 2 only) */
  int draws;    /* WV_DRAWS_PRIOR, or WV_DRAWS_PHOTO (version 2 and 3; "draws" in dataset.json) */
  uint64_t seed;
  int per_pattern;
  int spp;
  wv_scene scene;
  char scene_json[8192];
  int pair;         /* each sample also rendered in tscene, the back-lit scene */
  wv_scene tscene;
  char tscene_json[8192];
  char descriptor[32];
  int n_feat;       /* features per sample: the descriptor's size, twice it in a pair set */
} wv_dataset_info;

wv_status wv_dataset_info_read(const char *dir, wv_dataset_info *info, wv_error *err);
wv_status wv_dataset_info_write(const char *dir, const wv_dataset_info *info, wv_error *err);
/* The patterns a dataset cycles through: version 1 the five of wv_net_pattern, version 2
 * every canonical built-in (wv_weave_builtin_name). */
int wv_dataset_pattern_count(const wv_dataset_info *info);
const char *wv_dataset_pattern(const wv_dataset_info *info, int i);
/* Sample k (0 .. n per_pattern - 1, n patterns) interleaves the patterns: pattern k % n,
 * index k / n. */
void wv_dataset_sample_name(const wv_dataset_info *info, int k, char *buf, size_t cap);
/* How a set draws its cloths: from the priors (SPEC section 5), or as the photos of the flat45
 * rig show cloths: each yarn type's spacing uniform in WV_DATASET_PHOTO_SPACING_LO .. _HI
 * pixels at the image centre (the densities follow from the scene's camera), the noise level
 * uniform over its whole range, and the camera's blur up to WV_AUGMENT_PHOTO_BLUR pixels. */
#define WV_DRAWS_PRIOR 0
#define WV_DRAWS_PHOTO 1
#define WV_DATASET_PHOTO_SPACING_LO 1.0
#define WV_DATASET_PHOTO_SPACING_HI 2.5
#define WV_AUGMENT_PHOTO_BLUR 1.5
#define WV_AUGMENT_BLUR 0.8 /* the camera augmentation's defocus otherwise: sigma 0 .. this, pixels */
#define WV_DATASET_PAIR_WIDTH_LO 0.7 /* a pair set's yarn widths: uniform in this .. 1 (open area up to 9%) */
/* The prior draw of sample k (deterministic in the dataset seed); a pair set's with open gaps. */
wv_status wv_dataset_sample_params(const wv_dataset_info *info, int k, wv_params *p, wv_error *err);
/* Path of one of a sample's files: ext "json", "png", "t.png" or "feat". */
void wv_dataset_path(const char *dir, const wv_dataset_info *info, int k, const char *ext, char *buf, size_t cap);
/* 1 when the sample's files are complete. */
int wv_dataset_sample_done(const char *dir, const wv_dataset_info *info, int k);
/* Makes sample k in dir (whose samples/ exists): the prior draw rendered at info's
 * spp with render_threads (0 = all) and the footprints fp (made for info's scene,
 * or NULL), passed through the camera augmentation when info->augment (else only
 * quantised to 8 bits as a photo arrives), then its parameter file, PNG and, last,
 * its features computed by d into feat (n_feat floats of scratch). A pair set's sample
 * is also rendered in the back-lit scene (footprints fp_t, or NULL), with a camera
 * augmentation of its own. */
struct wv_descriptor;
struct wv_footprints;
wv_status wv_dataset_make_sample(const char *dir, const wv_dataset_info *info, int k, int render_threads,
                                 const struct wv_footprints *fp, const struct wv_footprints *fp_t,
                                 struct wv_descriptor *d, float *feat, wv_error *err);
/* What a real camera adds to a render, drawn from seed (docs/fabricnet.md, "Camera
 * augmentation"): on the linear radiance, glint speckle, defocus blur, exposure and
 * white-balance gains and signal-dependent sensor noise; then the scene's response,
 * 8-bit quantisation and, most of the time, a JPEG round trip. capture is allocated here
 * (the scene's image, 8-bit values). The same seed gives the same image. */
wv_status wv_camera_augment(const wv_scene *s, const wv_image *radiance, uint64_t seed, wv_image *capture,
                            wv_error *err);
/* The same with the defocus's sigma drawn up to blur_max pixels (WV_AUGMENT_BLUR above). */
wv_status wv_camera_augment_blur(const wv_scene *s, const wv_image *radiance, uint64_t seed, double blur_max,
                                 wv_image *capture, wv_error *err);

/* Building a dataset (woven dataset): resumable, shared over the ranks of dist. */
typedef struct {
  const char *scene;       /* a scene file or preset name */
  const char *transmission_scene; /* optional: a back-lit scene (file or preset) for a pair set */
  const char *dir;         /* DIR: dataset.json and samples/ */
  int per_pattern;         /* samples per pattern (1..WV_DATASET_MAX_PER_PATTERN) */
  uint64_t seed;           /* 1 */
  int spp;                 /* 0: the scene's */
  int augment;             /* 1: the camera augmentation */
  int draws;               /* WV_DRAWS_PRIOR (0) or WV_DRAWS_PHOTO */
  int jobs;                /* samples rendered at once, one thread each (0: all cores) */
  const char *descriptor;  /* "default" */
  const char *weights;     /* the descriptor's weights file, or NULL */
  /* Optional, called on rank 0 only: a line for the user (no newline), and progress
   * after each sample (samples done of todo, seconds since rendering began); a non-zero
   * return stops the build once the samples in flight are done (res->stopped). */
  void (*on_note)(void *user, const char *text);
  int (*on_progress)(void *user, int done, int todo, double seconds);
  void *user;
} wv_dataset_build_opts;
void wv_dataset_build_opts_default(wv_dataset_build_opts *o);
typedef struct {
  int samples, done_before, rendered; /* rendered: by every rank */
  int spp, width, height, jobs;
  int per_pattern; /* as recorded: a larger earlier size is kept */
  int stopped;     /* on_progress stopped the build: run it again to finish */
  double seconds;
} wv_dataset_build_result;
/* Renders the samples of dir that are not done (the dataset grows in place: inputs may
 * not be its files). Rank 0 holds the directory's lock and writes dataset.json before
 * any sample; a directory made with other settings is refused. Every rank calls it;
 * a rank whose own step succeeded returns the failure of another with an empty message. */
wv_status wv_dataset_build(const wv_dist *dist, const wv_dataset_build_opts *o, wv_dataset_build_result *res,
                           wv_error *err);

/* Features as f16 (n_feat values) with a header (magic, count, CRC). */
wv_status wv_dataset_write_features(const char *path, const float *x, int n, wv_error *err);
wv_status wv_dataset_read_features(const char *path, int n, uint16_t *out, wv_error *err);

#endif
