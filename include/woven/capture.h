/* woven: the capture jobs behind woven fit, capture and capture-batch: a fit run to the
 * end with every output written into a directory that appears whole or not at all
 * (params.json, renders, report, viewer, drape, maps, fit.json and its checkpoint), and
 * the whole capture, which chains FabricNet's estimate of the photo (woven/estimate.h)
 * and that fit. */
#ifndef WOVEN_CAPTURE_H
#define WOVEN_CAPTURE_H

#include "woven/descriptor.h"
#include "woven/error.h"
#include "woven/estimate.h"
#include "woven/fit.h"
#include "woven/image.h"
#include "woven/params.h"
#include "woven/photo.h"
#include "woven/report.h"
#include "woven/scene.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Optional progress, all from the calling thread: a line for the user (no newline), and
 * each finished fit iteration. */
typedef struct {
  void (*on_note)(void *user, const char *text);
  void (*on_iter)(void *user, const wv_fit_state *st, const wv_fit_opts *o);
  void *user;
} wv_capture_progress;

/* A fit to run and write (woven fit, and the back half of woven capture). */
typedef struct {
  const wv_scene *scene;
  const wv_image *photo;
  wv_descriptor *desc;
  const wv_params *start; /* NULL when resuming */
  wv_fit_opts opts;
  const char *dir, *photo_path, *start_label, *title;
  int resume, iters_given, force;
  const wv_pattern_choice *pattern_choice; /* how the start's pattern was chosen, or NULL */
  /* For fit.json (a new fit): the crop used and the descriptor's weights file. */
  wv_crop crop;
  const char *weights;
  /* A file written with fit.json (capture: network.json), or NULL. */
  const char *extra_name, *extra_text;
  /* Files read by the job: none may lie inside the directory, which is replaced whole. */
  const char *inputs[7];
  /* The mesh scene the report shows the fit on (NULL: the bundled draped cloth; "none": no drape). */
  const char *drape;
  wv_capture_progress progress;
  /* A photo pair (docs/fit.md, "Photo pairs"): the transmission photo, its back-lit scene and
   * its path; all NULL: the photo alone. */
  const wv_scene *scene_t;
  const wv_image *photo_t;
  const char *photo_t_path;
  const char *kt_start; /* where a pair's transmission colours start: a pair model's path, or NULL (the prior) */
  int kt_tried;         /* ... the prior, after the pair model's start scored worse */
} wv_fit_job;

/* What a finished fit wrote, for the caller's summary. */
typedef struct {
  wv_fit_state state; /* the fit (wv_fit_state_free) */
  wv_scene fit_scene; /* the scene with the registration's fabric offset and the camera blur */
  double ssim_start, ssim_fit;
  wv_weave_views views; /* SSIM per channel and WSC of start and fit (wsc -2: not measured) */
  char start_label[32]; /* what the start was: prior, start (a parameter file), network */
  /* A photo pair's transmission photo against its re-render (pair 0: none): SSIM per RGB
   * channel, WSC (-2: not measured), the photo's blurred-copy SSIM, whether the re-render scores
   * below it, the share of the photo's detail in its spectral peaks (wv_detail_periodic; -2: not
   * measured), and the mean brightness of photo [0] and re-render [1] over the centre (half of
   * each side) [0] and the whole frame [1]. */
  int pair, below_blurred_copy_t;
  double ssim_rgb_t, wsc_t, ssim_rgb_blurred_t, periodic_share_t, mean_t[2][2];
  int kt_model; /* a pair's transmission colours started from a pair model (1), from the prior after the pair
                 * model's start scored worse on the pair's loss (2), from the prior without one (0) */
} wv_fit_outcome;

/* The output directory check, before any slow step: refuses a file, a directory holding
 * files that are not a fit's, an input inside it, and (unless force or resuming) an
 * earlier fit, finished or not. */
wv_status wv_fit_job_check_dir(const wv_fit_job *job, wv_error *err);
/* Runs the fit and writes every output. The directory's life: fit.json and a checkpoint
 * at iteration 0 appear first (one rename), checkpoints follow while fitting, and the
 * results replace the directory whole at the end. When it holds a finished fit (force,
 * or a resume adding iterations) all of that happens in a temporary directory beside it,
 * so the earlier fit stays whole until then. On success out holds the fit. */
wv_status wv_fit_job_run(const wv_fit_job *job, wv_fit_outcome *out, wv_error *err);

/* What a fit directory's fit.json records for a resume (woven fit --resume DIR). */
typedef struct {
  char photo[4096], descriptor[64], weights[4096], start_label[32]; /* weights "": none */
  wv_crop crop;
  wv_scene scene;
  char photo_t[4096]; /* a photo pair's transmission photo ("": none) and its scene */
  wv_scene scene_t;
} wv_fit_record_job;
wv_status wv_fit_job_read(const char *dir, wv_fit_record_job *rec, wv_error *err);

/* A fit of a photo into a directory (woven fit): a new one from a parameter file (init)
 * or a pattern's prior mean, or the continuation of the one recorded by resume. */
typedef struct {
  const char *photo, *scene, *init, *pattern, *dir; /* with resume: only photo, NULL or the recorded one */
  const char *descriptor, *weights, *drape;         /* NULL descriptor: "default" */
  const char *photo_t, *scene_t; /* a transmission photo and its scene (wv_pair_scene); NULL: none */
  wv_crop crop;
  const wv_fit_record_job *resume; /* from wv_fit_job_read of dir, or NULL */
  wv_fit_opts fit;
  int iters_given, force;
  wv_capture_progress progress;
} wv_fit_dir_opts;
wv_status wv_fit_dir_run(const wv_fit_dir_opts *o, wv_fit_outcome *out, wv_error *err);

/* The back-lit counterpart of a reflection scene for a photo pair: scene_t when given (a
 * preset name or a file; it must be back-lit, wv_scene_transmits), else flat45-back for
 * flat45; any other scene has none and is refused with a message naming it. The
 * counterpart must render the reflection scene's image size. */
wv_status wv_pair_scene(const char *scene, const wv_scene *s, const char *scene_t, wv_scene *out, wv_error *err);

/* The whole capture (woven capture): the estimate, then the fit from it with every output
 * in dir (fit.json, network.json, ...). on_estimate (optional) is called between them. */
typedef struct {
  wv_estimate_opts estimate;
  wv_fit_opts fit;
  int iters_given;
  int align_given; /* 0: fit.align_radius becomes WV_CAPTURE_ALIGN_RADIUS when the weave
                    * analysis found the photo's lattice (wv_capture_fit_opts) */
  const char *dir, *drape;
  const char *photo_t, *scene_t; /* a transmission photo and its scene (wv_pair_scene); NULL: none */
  const char *pair_model;        /* the pair model for the transmission colours' start (NULL: the default,
                                  * wv_estimate_transmission; none there: the prior) */
  int force;
  void (*on_estimate)(void *user, const wv_estimate *e);
  wv_capture_progress progress; /* its user is on_estimate's too */
} wv_capture_opts;
#define WV_CAPTURE_ALIGN_RADIUS 0 /* yarns/inch; 0: no alignment (docs/analysis.md: on the real
                                   * photos it changed SSIM by nothing and lost the weave) */
/* The fit options of a capture after its pattern choice pc (NULL: the pattern was given).
 * With a lattice the densities are measured, and the fit keeps them: no random density
 * steps (density_steps 0) and, unless align_given, no density alignment, whose search for
 * the best SSIM lands on aliases that erase the weave. The registration still refines
 * them. */
void wv_capture_fit_opts(const wv_pattern_choice *pc, int align_given, wv_fit_opts *o);
/* A pair model's transmission colours (in est->params, wv_estimate_transmission) are a
 * proposal: the pair's loss (both photos, the fit's iteration spp) with them and with the
 * prior's, k_d / 2, and the lower kept in est->params; *kt_model becomes 2 when the prior's
 * was (it stays 1 otherwise). */
wv_status wv_capture_pair_start(wv_estimate *est, const wv_scene *scene_t, const wv_image *photo_t,
                                const wv_fit_opts *fo, int *kt_model, wv_error *err);
/* On success est holds the estimate (wv_estimate_free) and out the fit. */
wv_status wv_capture_run(const wv_capture_opts *o, wv_estimate *est, wv_fit_outcome *out, wv_error *err);

#ifdef __cplusplus
}
#endif
#endif
