/* woven fit: refine parameters from a photo; also the back half of woven capture. */
#define _DEFAULT_SOURCE /* realpath */
#include <errno.h>
#include <limits.h>
#include <jansson.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "cli.h"
#include "util/json.h"
#include "woven/analysis.h"
#include "woven/descriptor.h"
#include "woven/fit.h"
#include "woven/io.h"
#include "woven/maps.h"
#include "woven/metrics.h"
#include "woven/photo.h"
#include "woven/render.h"
#include "woven/report.h"
#include "woven/scene3d.h"
#include "woven/view.h"

/* strtol-based: sscanf's %d has undefined behaviour on overflow. */
static int parse_nonneg_int(const char *s, char **end, int *out) {
  if (*s < '0' || *s > '9') return 0;
  errno = 0;
  long v = strtol(s, end, 10);
  if (errno == ERANGE || v > 2147483647L) return 0;
  *out = (int)v;
  return 1;
}

/* x,y,w,h: non-negative integers, w and h positive. */
static int parse_crop(const char *cmd, const cli_opt *o, const char *s, void *base) {
  wv_crop *c = (wv_crop *)((char *)base + o->off);
  int v[4];
  char *end = (char *)s;
  for (int i = 0; i < 4; i++) {
    if (!parse_nonneg_int(end, &end, &v[i]) || *end != (i < 3 ? ',' : '\0') || (i >= 2 && v[i] < 1))
      return cli_usage_error(cmd, "--crop must be x,y,w,h (non-negative integers)");
    if (i < 3) end++;
  }
  c->x = v[0], c->y = v[1], c->w = v[2], c->h = v[3];
  return 0;
}

static int parse_iters(const char *cmd, const cli_opt *o, const char *v, void *base) {
  capture_args *a = base;
  a->iters_given = 1;
  return cli_opt_int(cmd, o, v, &a->fit.iters);
}

static int parse_seed(const char *cmd, const cli_opt *o, const char *v, void *base) {
  capture_args *a = base;
  int seed;
  int rc = cli_opt_int(cmd, o, v, &seed);
  if (!rc) a->fit.seed = (uint64_t)seed;
  return rc;
}

static int parse_blur(const char *cmd, const cli_opt *o, const char *v, void *base) {
  capture_args *a = base;
  if (!strcmp(v, "auto")) {
    a->fit.psf_sigma = WV_FIT_PSF_AUTO;
    return 0;
  }
  return cli_opt_real(cmd, o, v, &a->fit.psf_sigma);
}

void cli_capture_args_init(capture_args *a) {
  memset(a, 0, sizeof *a);
  a->descriptor = "default";
  wv_fit_opts_default(&a->fit);
}

const cli_opt CLI_PHOTO_OPTS[] = {
    CLI_O_STR("--scene", NULL, capture_args, scene, "S", "the capture scene: a scene file, cylinder or flat45"),
    CLI_O_STR("--pattern", NULL, capture_args, pattern, "NAME",
              "a built-in pattern (plain, basket, twill21s ... twill31z, satin5,\nsatin8, the _90 variants; "
              "docs/model.md)"),
    CLI_O_STR("--output", "-o", capture_args, out, "OUT", "the output"),
    CLI_O_CUSTOM("--crop", capture_args, crop, 0, 0, parse_crop, "x,y,w,h",
                 "use this rectangle of the photo (default: centred, the scene's\naspect)"),
    CLI_O_STR("--descriptor", NULL, capture_args, descriptor, "default|vgg19", "the texture descriptor (default: default)"),
    CLI_O_STR("--vgg19-weights", NULL, capture_args, weights, "FILE", "the VGG-19 weights (--descriptor vgg19)"),
    CLI_O_FLAG("--force", capture_args, force, "replace an earlier output (a model for another scene: use it)"),
    CLI_O_END};

const cli_opt CLI_MODEL_OPTS[] = {
    CLI_O_STR("--model", NULL, capture_args, model, "M",
              "a model from 'woven train' (default: models/fabricnet-<scene\nname>.bin; the directory can be "
              "changed with WOVEN_MODEL_DIR)"),
    CLI_O_END};

const cli_opt CLI_FIT_OPTS[] = {
    CLI_O_CUSTOM("--iters", capture_args, fit.iters, 0, WV_FIT_MAX_ITERS, parse_iters, "N", "iterations (default 200)"),
    CLI_O_INT("--iter-spp", NULL, capture_args, fit.iter_spp, 1, WV_SCENE_MAX_SPP, "N",
              "samples per pixel while iterating (default 4)"),
    CLI_O_INT("--iter-scale", NULL, capture_args, fit.iter_scale, 1, WV_FIT_MAX_ITER_SCALE, "N",
              "iterate on the image downscaled N times (default 1); the final\nrender and SSIM use the scene's full "
              "resolution and spp"),
    CLI_O_CUSTOM("--seed", capture_args, seed, 0, INT_MAX, parse_seed, "N", "the seed of the discrete steps"),
    CLI_O_INT("--align-radius", NULL, capture_args, fit.align_radius, 0, WV_FIT_MAX_ALIGN_RADIUS, "N",
              "after the iterations, search each density +-N yarns/inch for the\nbest SSIM in a centre window "
              "(default 230: the whole range;\n0 = off)"),
    CLI_O_INT("--register-radius", NULL, capture_args, fit.register_radius, 0, WV_FIT_MAX_REGISTER_RADIUS, "N",
              "then register the weave to the photo: densities on a 2-D grid\n+-N yarns/inch refined to 0.1, and "
              "the weave's offset, by phase\ncorrelation; kept if the SSIM rises (default 6; 0 = off)"),
    CLI_O_REAL("--w-struct", capture_args, fit.w_struct, 0, 100, 0, "X",
               "weight of the structure term, the weave's log power spectrum\n(default 0.002; 0 = off)"),
    CLI_O_CLEAR("--no-colour-split", capture_args, fit.colour_split,
                "do not try starts that split the warp and weft diffuse colours"),
    CLI_O_CUSTOM("--camera-blur", capture_args, fit.psf_sigma, 0, WV_PSF_MAX_SIGMA, parse_blur, "auto|S",
                 "the camera's blur, a Gaussian of sigma S pixels on the radiance in\nevery render; auto (default): "
                 "the scene's, else measured from the\nphoto's spectrum"),
    CLI_O_INT("--threads", NULL, capture_args, fit.threads, 1, 1024, "N", "worker threads (default: all cores)"),
    CLI_O_STR("--drape", NULL, capture_args, drape, "S.json|none",
              "the mesh scene the report shows the fit on (default: the bundled\ndraped cloth, "
              "scenes/drape-studio.json, at 512 x 384; 'none': no\ndrape)"),
    CLI_O_END};

static const cli_opt FIT_ONLY_OPTS[] = {
    CLI_O_STR("--init", NULL, capture_args, init, "P.json", "start here; --pattern NAME starts from the pattern's prior mean"),
    CLI_O_STR("--resume", NULL, capture_args, resume, "DIR",
              "continue a fit that was stopped (checkpoints at the start and every\n10 iterations), or add "
              "iterations to a finished one"),
    CLI_O_END};

static const cli_cmd CMD = {
    "fit",
    "usage: woven fit PHOTO --scene S.json|cylinder|flat45 [--init P.json | --pattern NAME] -o DIR\n"
    "                 [--iters N] [--descriptor default|vgg19] [--vgg19-weights FILE]\n"
    "                 [--crop x,y,w,h] [--iter-spp N] [--iter-scale N] [--align-radius N]\n"
    "                 [--register-radius N] [--w-struct X] [--no-colour-split] [--camera-blur auto|S]\n"
    "                 [--seed N] [--threads N] [--drape S.json|none]\n"
    "                 [--force] [--quiet] [--json]\n"
    "       woven fit --resume DIR [--iters N] [--quiet] [--json]\n"
    "\n"
    "Refines fabric parameters so that a render of the scene matches the photo (paper 4.3):\n"
    "Gram-matrix loss + 16x8 pixel loss + heightfield prior + the weave's spectrum (structure),\n"
    "Adam (lr 0.01) on the continuous\n"
    "parameters, random steps of noise level and densities every 5 iterations.\n",
    "Writes to DIR: params.json, render.png, compare.png (photo | start | fit), zoom.png (their\n"
    "centre crop enlarged 4x), spectra.png (their weave spectra), loss.svg, report.html (with\n"
    "SSIM and WSC, the weave-spectrum correlation, of start and fit), viewer.html (woven view),\n"
    "drape.png (the fit on a draped cloth), maps/, and fit.json +\n"
    "checkpoint.json (for --resume). DIR is replaced whole at the end; it may not hold other\n"
    "files, nor any input; --force replaces an earlier fit in DIR (it stays whole until the new\n"
    "one is done).\n",
    {{FIT_ONLY_OPTS, 0}, {CLI_PHOTO_OPTS, 0}, {CLI_FIT_OPTS, 0}}, 1, {offsetof(capture_args, photo)}};

typedef struct {
  cli_ctx *c;
  cli_progress bar;
  const char *ckpt;
  const char *descriptor;
  wv_error *err;
  int ckpt_failed;
} fit_cb_ctx;

static int on_iter(void *user, const wv_fit_state *st, const wv_fit_opts *o) {
  fit_cb_ctx *u = user;
  const wv_fit_record *r = &st->log[st->iter - 1];
  if (u->bar.enabled) {
    double el = cli_now() - u->bar.start, f = (double)st->iter / o->iters;
    fprintf(stderr, "\rfit %3d/%d  loss %.5f (Gram %.5f, pixel %.4f, prior %.3f, structure %.3f)  %.0fs, %.0fs left ",
            st->iter, o->iters, r->loss, r->gram, r->pixel, r->prior, r->structure, el,
            f > 0 ? el * (1 - f) / f : 0.0);
    fflush(stderr);
  }
  if (u->ckpt && o->checkpoint_every > 0 && (st->iter % o->checkpoint_every == 0 || st->iter == o->iters)) {
    if (wv_fit_checkpoint_write(u->ckpt, st, o, u->descriptor, u->err)) {
      u->ckpt_failed = 1;
      return 1;
    }
  }
  return 0;
}

/* What a fit directory may hold (woven capture adds network.json). */
static const char *const FIT_FILES[] = {"fit.json",    "checkpoint.json", "params.json", "render.png",
                                        "start.png",   "photo.png",       "compare.png", "loss.svg",
                                        "report.html", "viewer.html", "drape.png", "maps",            "scene.json",  "network.json",
                                        "zoom.png",    "spectra.png", NULL};

typedef enum { FIT_DIR_NONE, FIT_DIR_UNFINISHED, FIT_DIR_FINISHED } fit_dir_state;

/* params.json, written last, marks a finished fit; fit.json alone one in progress. */
static fit_dir_state dir_state(const char *dir) {
  char p[4096];
  struct stat sb;
  snprintf(p, sizeof p, "%s/params.json", dir);
  if (stat(p, &sb) == 0) return FIT_DIR_FINISHED;
  snprintf(p, sizeof p, "%s/fit.json", dir);
  if (stat(p, &sb) == 0) return FIT_DIR_UNFINISHED;
  return FIT_DIR_NONE;
}

int fit_check_dir(const cli_ctx *c, const fit_job *job) {
  wv_error err = {0};
  if (wv_outdir_check(job->dir, FIT_FILES, &err)) return cli_fail(c, &err);
  int rc = cli_check_not_input(c, job->dir, 1, job->inputs, (int)(sizeof job->inputs / sizeof job->inputs[0]));
  if (rc || job->resume || job->force) return rc;
  fit_dir_state ds = dir_state(job->dir);
  if (ds == FIT_DIR_FINISHED) {
    fprintf(stderr, "woven %s: error: %s already holds a fit (params.json); use --force to replace it\n", c->cmd,
            job->dir);
    return WV_ERR_IO;
  }
  if (ds == FIT_DIR_UNFINISHED) {
    fprintf(stderr,
            "woven %s: error: %s holds an unfinished fit (fit.json, no params.json); continue it with 'woven fit "
            "--resume %s' or replace it with --force\n",
            c->cmd, job->dir, job->dir);
    return WV_ERR_IO;
  }
  return 0;
}

/* dir/name -> into/name; a missing optional file is skipped. */
static wv_status copy_into(const char *dir, const char *name, const char *into, int optional, wv_error *err) {
  char from[4096], to[4096];
  struct stat sb;
  snprintf(from, sizeof from, "%s/%s", dir, name);
  snprintf(to, sizeof to, "%s/%s", into, name);
  if (optional && stat(from, &sb) != 0) return WV_OK;
  char *data;
  size_t len;
  wv_status st = wv_read_file_max(from, WV_JSON_MAX_BYTES, &data, &len, err);
  if (st) return st;
  st = wv_write_file_atomic(to, data, len, err);
  free(data);
  return st;
}

static wv_status write_text(const char *dir, const char *name, const char *text, wv_error *err) {
  char path[4096];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  if (!text) return wv_fail(err, WV_ERR_NOMEM, "%s: out of memory", path);
  return wv_write_file_atomic(path, text, strlen(text), err);
}

/* fit.json records what a resume needs: the photo (absolute, so a resume works from any
 * directory), crop, scene and descriptor; also the start's label for the report. */
static char *job_json(const fit_job *job) {
  char *photo = realpath(job->photo_path, NULL), *weights = job->weights ? realpath(job->weights, NULL) : NULL;
  char *sj = wv_scene_to_json(job->scene);
  json_t *scene = sj ? json_loads(sj, 0, NULL) : NULL;
  free(sj);
  json_t *o = json_pack("{s:s,s:i,s:o,s:[i,i,i,i],s:o,s:s,s:s}", "kind", "woven-fit", "version", 1, "photo",
                        cli_str(photo ? photo : job->photo_path), "crop", job->crop.x, job->crop.y, job->crop.w,
                        job->crop.h, "scene", scene ? scene : json_null(), "descriptor",
                        wv_descriptor_name(job->desc), "start_label", job->start_label);
  if (o && job->weights) json_object_set_new(o, "vgg19_weights", cli_str(weights ? weights : job->weights));
  free(photo), free(weights);
  if (o && job->pattern_choice) /* informative: a resume does not need it */
    json_object_set_new(o, "pattern_choice", cli_json_text(wv_pattern_choice_to_json(job->pattern_choice)));
  char *text = o ? json_dumps(o, JSON_INDENT(2) | JSON_PRESERVE_ORDER | JSON_REAL_PRECISION(17)) : NULL;
  json_decref(o);
  return text;
}

/* The results of a finished fit, written into dir (a temporary directory). */
#ifndef WOVEN_SCENE_DIR
#define WOVEN_SCENE_DIR "scenes"
#endif

/* drape.png: the fit on a mesh scene (--drape, default the bundled draped cloth in
 * $WOVEN_SCENE_DIR or the source tree's scenes/), at 512 x 384 and 16 spp. A missing
 * default scene (woven run away from its tree) is noted in the report, not an error;
 * a scene the user named must render. Returns 1 when drape.png was written. */
static int render_drape(const fit_job *job, const char *dir, const wv_params *p, int threads, char *out, size_t cap,
                        char *note, size_t ncap, wv_error *err, wv_status *rc) {
  if (job->drape && !strcmp(job->drape, "none")) return 0;
  char scene[4096];
  const char *d = getenv("WOVEN_SCENE_DIR");
  if (job->drape) snprintf(scene, sizeof scene, "%s", job->drape);
  else snprintf(scene, sizeof scene, "%s/drape-studio.json", d && *d ? d : WOVEN_SCENE_DIR);
  struct stat sb;
  if (!job->drape && stat(scene, &sb) != 0) {
    snprintf(note, ncap, "No drape: the bundled scene %s was not found (set WOVEN_SCENE_DIR).", scene);
    return 0;
  }
  wv_scene3d_preview po = {512, 384, 16, threads};
  wv_image img = {0};
  snprintf(out, cap, "%s/drape.png", dir);
  *rc = wv_scene3d_render_file(scene, p, &po, &img, err);
  if (!*rc) *rc = wv_image_write_png(out, &img, 8, err);
  wv_image_free(&img);
  if (*rc) return 0;
  snprintf(note, ncap, "The fit on %s under its lights, 512 x 384, 16 samples per pixel "
           "(<code>woven scene %s --params params.json</code> renders it in full).", job->drape ? "the scene given" :
           "the bundled draped cloth", job->drape ? "S.json" : "scenes/drape-studio.json");
  return 1;
}

static wv_status write_results(const fit_job *job, const char *dir, const wv_fit_state *st, const wv_fit_opts *o,
                               const wv_scene *fit_scene, double *ssim_start, double *ssim_fit, wv_weave_views *wv,
                               wv_error *err) {
  wv_render_opts ro = {0, o->threads, NULL, NULL, NULL};
  wv_image r_start = {0}, r_fit = {0}, cmp = {0};
  char path[4096], pphoto[4096], pstart[4096], pfit[4096];
  wv_scene start_scene = *job->scene; /* the start seen through the same camera blur as the fit */
  start_scene.psf_sigma = fit_scene->psf_sigma;
  wv_status rc = wv_render(&start_scene, &st->start, &ro, &r_start, NULL, err);
  if (!rc) rc = wv_render(fit_scene, &st->params, &ro, &r_fit, NULL, err);
  if (!rc) rc = wv_ssim(job->photo, &r_start, WV_SSIM_LUMA, ssim_start, err);
  if (!rc) rc = wv_ssim(job->photo, &r_fit, WV_SSIM_LUMA, ssim_fit, err);
  if (!rc) rc = wv_weave_views_write(dir, job->photo, &r_start, &r_fit, wv, err);
  const wv_image *side[3] = {job->photo, &r_start, &r_fit};
  if (!rc) rc = wv_image_hconcat(side, 3, 4, &cmp, err);
  snprintf(pphoto, sizeof pphoto, "%s/photo.png", dir);
  snprintf(pstart, sizeof pstart, "%s/start.png", dir);
  snprintf(pfit, sizeof pfit, "%s/render.png", dir);
  if (!rc) rc = wv_image_write_png(pphoto, job->photo, 8, err);
  if (!rc) rc = wv_image_write_png(pstart, &r_start, 8, err);
  if (!rc) rc = wv_image_write_png(pfit, &r_fit, 8, err);
  snprintf(path, sizeof path, "%s/compare.png", dir);
  if (!rc) rc = wv_image_write_png(path, &cmp, 8, err);
  wv_image_free(&r_start), wv_image_free(&r_fit), wv_image_free(&cmp);
  char pdrape[4096], note[1024] = "";
  int drape = 0;
  if (!rc) drape = render_drape(job, dir, &st->params, o->threads, pdrape, sizeof pdrape, note, sizeof note, err, &rc);
  char *svg = rc ? NULL : wv_loss_svg(st->log, st->iter, o);
  if (!rc) rc = write_text(dir, "loss.svg", svg, err);
  wv_report rep = {.title = job->title, .photo_png = pphoto, .start_png = pstart, .fit_png = pfit,
                   .start_label = job->start_label, .ssim_start = *ssim_start, .ssim_fit = *ssim_fit,
                   .start = &st->start, .fit = &st->params, .loss_svg = svg, .timing = &st->timing,
                   .iters = st->iter, .descriptor = wv_descriptor_name(job->desc),
                   .pattern_choice = job->pattern_choice, .weave = wv, .camera_blur = fit_scene->psf_sigma,
                   .viewer_html = "viewer.html", .drape_png = drape ? pdrape : NULL,
                   .drape_note = note[0] ? note : NULL};
  /* the viewer of the fit in its registered scene, with the photo (the report embeds it) */
  wv_view_opts vo = {&st->params, fit_scene, pphoto, job->title};
  snprintf(path, sizeof path, "%s/viewer.html", dir);
  if (!rc) rc = wv_view_write(path, &vo, err);
  snprintf(path, sizeof path, "%s/report.html", dir);
  if (!rc) rc = wv_report_write_html(path, &rep, err);
  free(svg);
  wv_maps maps = {0};
  snprintf(path, sizeof path, "%s/maps", dir);
  if (!rc) rc = wv_maps_generate(&st->params, 1024, &maps, err);
  if (!rc) rc = wv_maps_write(&maps, path, "png", err);
  wv_maps_free(&maps);
  /* scene.json: the scene with the registered offset, to re-render exactly this fit */
  char *scene_text = rc ? NULL : wv_scene_to_json(fit_scene);
  if (!rc) rc = write_text(dir, "scene.json", scene_text, err);
  free(scene_text);
  /* params.json last: its presence marks a finished fit */
  snprintf(path, sizeof path, "%s/params.json", dir);
  if (!rc) rc = wv_params_write(path, &st->params, err);
  return rc;
}

/* The state a run starts from and the directory its checkpoints go to (work): the
 * fit directory itself while it holds no finished fit, otherwise od's temporary
 * directory (*staged), so the finished fit stays whole until the new one replaces it. */
static wv_status open_state(const fit_job *job, wv_fit_state *st, wv_fit_opts *o, wv_outdir *od, int *staged,
                            char *work, size_t wcap, wv_error *err) {
  fit_dir_state ds = dir_state(job->dir);
  char ckpt[4096];
  wv_status rc;
  *staged = ds == FIT_DIR_FINISHED;
  if (job->resume) {
    if (*staged) {
      if ((rc = wv_outdir_begin(od, job->dir, FIT_FILES, err))) return rc;
      if ((rc = copy_into(job->dir, "fit.json", od->tmp, 0, err)) ||
          (rc = copy_into(job->dir, "checkpoint.json", od->tmp, 0, err)) ||
          (rc = copy_into(job->dir, "network.json", od->tmp, 1, err)))
        return rc;
      snprintf(work, wcap, "%s", od->tmp);
    } else {
      snprintf(work, wcap, "%s", job->dir);
      wv_remove_stale_temps(job->dir, NULL); /* left by a run that was killed while writing */
    }
    char dname[64];
    snprintf(ckpt, sizeof ckpt, "%s/checkpoint.json", job->dir); /* the copy in work is the same */
    struct stat sb;
    if (stat(ckpt, &sb) != 0)
      return wv_fail(err, WV_ERR_IO, "%s holds no checkpoint.json (stopped before its first checkpoint by an older "
                     "woven): start the fit again with --force", job->dir);
    if ((rc = wv_fit_checkpoint_read(ckpt, st, o, dname, sizeof dname, err))) return rc;
    if (strcmp(dname, wv_descriptor_name(job->desc))) {
      wv_fit_state_free(st);
      return wv_fail(err, WV_ERR_INVALID, "%s/checkpoint.json was made with descriptor '%s', not '%s'", job->dir,
                     dname, wv_descriptor_name(job->desc));
    }
    if (job->opts.iters > 0 && job->iters_given) o->iters = job->opts.iters;
    if (st->iter > o->iters) o->iters = st->iter;
    return WV_OK;
  }
  /* A new fit: fit.json and the iteration-0 checkpoint appear together, so a fit
   * stopped at any point can be resumed. */
  if ((rc = wv_fit_state_init(st, job->start, o, err))) return rc;
  char *text = job_json(job);
  if (!(rc = wv_outdir_begin(od, job->dir, FIT_FILES, err))) {
    snprintf(ckpt, sizeof ckpt, "%s/checkpoint.json", od->tmp);
    rc = write_text(od->tmp, "fit.json", text, err);
    if (!rc && job->extra_name) rc = write_text(od->tmp, job->extra_name, job->extra_text, err);
    if (!rc) rc = wv_fit_checkpoint_write(ckpt, st, o, wv_descriptor_name(job->desc), err);
    if (!rc && !*staged) rc = wv_outdir_commit(od, err);
  }
  free(text);
  if (rc) {
    wv_fit_state_free(st);
    return rc;
  }
  snprintf(work, wcap, "%s", *staged ? od->tmp : job->dir);
  return WV_OK;
}

int fit_pipeline(cli_ctx *c, const fit_job *job) {
  wv_error err = {0};
  char work[4096], ckpt[4096];
  wv_fit_state st;
  wv_fit_opts o = job->opts;
  wv_outdir od = {NULL, NULL, -1};
  int staged = 0;
  if (job->drape && strcmp(job->drape, "none")) { /* a scene that cannot render is refused before the fit */
    wv_scene3d s3;
    if (wv_scene3d_read(job->drape, &s3, &err)) return cli_fail(c, &err);
    wv_scene3d_free(&s3);
  }
  if (open_state(job, &st, &o, &od, &staged, work, sizeof work, &err)) {
    wv_outdir_abort(&od, &err);
    return cli_fail(c, &err);
  }
  snprintf(ckpt, sizeof ckpt, "%s/checkpoint.json", work);
  fit_cb_ctx u = {c, {0}, ckpt, wv_descriptor_name(job->desc), &err, 0};
  cli_progress_start(&u.bar, c, "fit");
  if (!job->resume || st.iter < o.iters)
    cli_info(c, "fitting %s: %d iterations from %d (%s start, iterating at 1/%d scale, %d spp)\n", job->photo_path,
             o.iters, st.iter, job->start_label, o.iter_scale, o.iter_spp);
  wv_status rc = wv_fit_run(&st, job->scene, job->photo, job->desc, &o, on_iter, &u, &err);
  cli_progress_end(&u.bar);
  if (!rc && !u.ckpt_failed) rc = wv_fit_checkpoint_write(ckpt, &st, &o, u.descriptor, &err); /* with the alignment */
  if (u.ckpt_failed && !rc) rc = err.code;
  /* The results go into a temporary directory that then replaces the fit directory. */
  if (!rc && !staged && !(rc = wv_outdir_begin(&od, job->dir, FIT_FILES, &err))) {
    if (!(rc = copy_into(job->dir, "fit.json", od.tmp, 0, &err)) &&
        !(rc = copy_into(job->dir, "checkpoint.json", od.tmp, 0, &err)))
      rc = copy_into(job->dir, "network.json", od.tmp, 1, &err);
  }
  double ssim_start = 0, ssim_fit = 0;
  wv_weave_views wv = {.wsc = {-2, -2}};
  wv_scene fit_scene; /* with the registration's fabric offset */
  wv_fit_scene(&st, job->scene, &fit_scene);
  if (!rc)
    cli_info(c, "rendering start and fit at %d x %d, %d spp\n", job->scene->width, job->scene->height,
             job->scene->spp);
  if (!rc) rc = write_results(job, od.tmp, &st, &o, &fit_scene, &ssim_start, &ssim_fit, &wv, &err);
  if (!rc) rc = wv_outdir_commit(&od, &err);
  if (rc) {
    wv_outdir_abort(&od, &err);
    wv_fit_state_free(&st);
    return cli_fail(c, &err);
  }
  const wv_fit_record *last = st.iter ? &st.log[st.iter - 1] : NULL;
  cli_info(c, "SSIM %s %.4f -> fit %.4f, WSC %.3f -> %.3f; %d iterations in %.1f s; results in %s/\n",
           job->start_label, ssim_start, ssim_fit, wv.wsc[0], wv.wsc[1], st.iter, st.timing.total, job->dir);
  if (c->json) {
    json_t *o_json = json_pack(
        "{s:o,s:i,s:o,s:o,s:o,s:{s:o,s:o,s:o,s:o,s:o,s:o},s:[o,o],s:{s:[o,o],s:[o,o],s:[o,o]}}", "dir",
        cli_str(job->dir), "iterations", st.iter, "ssim_start", cli_real(ssim_start, 6), "ssim_fit",
        cli_real(ssim_fit, 6), "loss", cli_real(last ? last->loss : 0.0, 8), "time_s", "total",
        cli_real(st.timing.total, 3), "render", cli_real(st.timing.render, 3), "gradient",
        cli_real(st.timing.gradient, 3), "descriptor", cli_real(st.timing.descriptor, 3), "discrete",
        cli_real(st.timing.discrete, 3), "registration", cli_real(st.timing.registration, 3),
        "density_alignment_ssim", cli_real(st.align_ssim_before, 4), cli_real(st.align_ssim_after, 4),
        "registration", "offset_mm", cli_real(st.offset_mm[0], 6), cli_real(st.offset_mm[1], 6), "ncc",
        cli_real(st.reg_ncc_before, 4), cli_real(st.reg_ncc_after, 4), "window_ssim", cli_real(st.reg_ssim_before, 4),
        cli_real(st.reg_ssim_after, 4));
    if (o_json) {
      json_object_set_new(o_json, "pattern_choice",
                          job->pattern_choice ? cli_json_text(wv_pattern_choice_to_json(job->pattern_choice))
                                              : json_null());
      json_object_set_new(o_json, "camera_blur_px", cli_real(fit_scene.psf_sigma, 3));
      json_object_set_new(o_json, "ssim_rgb_start", cli_real(wv.ssim_rgb[0], 6));
      json_object_set_new(o_json, "ssim_rgb_fit", cli_real(wv.ssim_rgb[1], 6));
      json_object_set_new(o_json, "wsc_start", wv.wsc[0] > -2 ? cli_real(wv.wsc[0], 6) : json_null());
      json_object_set_new(o_json, "wsc_fit", wv.wsc[1] > -2 ? cli_real(wv.wsc[1], 6) : json_null());
      char bounds[WV_P_COUNT + 3][96];
      int nb = wv_params_at_bounds(&st.params, bounds, WV_P_COUNT + 3);
      json_t *ab = json_array();
      for (int i = 0; i < nb && ab; i++) json_array_append_new(ab, cli_str(bounds[i]));
      json_object_set_new(o_json, "at_bounds", ab ? ab : json_null());
      json_object_set_new(o_json, "params", cli_json_text(wv_params_to_json(&st.params)));
    }
    cli_print_json(o_json);
  }
  if (job->result) {
    job->result->ssim_start = ssim_start, job->result->ssim_fit = ssim_fit, job->result->iterations = st.iter;
    job->result->wsc = wv.wsc[1];
    snprintf(job->result->pattern, sizeof job->result->pattern, "%s", st.params.pattern);
  }
  wv_fit_state_free(&st);
  return 0;
}

/* A path in fit.json: absolute; a relative one (written by older versions, relative to
 * the working directory of the time) is looked up from here, then from the fit directory. */
static void resolve_recorded(const char *dir, const char *p, char *out, size_t cap) {
  struct stat sb;
  snprintf(out, cap, "%s", p);
  if (p[0] == '/' || stat(out, &sb) == 0) return;
  snprintf(out, cap, "%s/%s", dir, p);
  if (stat(out, &sb) != 0) snprintf(out, cap, "%s", p); /* the message names it as recorded */
}

static wv_status read_job(const char *dir, char *photo, size_t pcap, wv_crop *crop, wv_scene *s, char *desc,
                          size_t dcap, char *weights, size_t wcap, char *label, size_t lcap, wv_error *err) {
  char path[4096];
  snprintf(path, sizeof path, "%s/fit.json", dir);
  struct stat sb;
  if (stat(path, &sb) != 0)
    return wv_fail(err, WV_ERR_INVALID, "%s is not a fit directory (no fit.json)", dir);
  json_t *o;
  wv_status st = wv_json_load_file(path, &o, err);
  if (st) return st;
  const char *ph = NULL, *de = NULL, *we = NULL, *kind = NULL, *lb = NULL;
  json_t *scene = NULL, *cr = json_object_get(o, "crop");
  if (json_unpack(o, "{s:s,s:s,s:o,s:s,s?s,s?s}", "kind", &kind, "photo", &ph, "scene", &scene, "descriptor", &de,
                  "vgg19_weights", &we, "start_label", &lb) ||
      strcmp(kind, "woven-fit") || !json_is_array(cr) || json_array_size(cr) != 4) {
    st = wv_fail(err, WV_ERR_FORMAT, "%s: not a woven fit description", path);
  } else {
    static const char *names[4] = {"crop[0]", "crop[1]", "crop[2]", "crop[3]"};
    int *dst[4] = {&crop->x, &crop->y, &crop->w, &crop->h};
    for (int i = 0; i < 4 && !st; i++) {
      long long v;
      st = wv_json_integer_value(json_array_get(cr, (size_t)i), names[i], i < 2 ? 0 : 1, 2147483647LL, &v, err);
      if (!st) *dst[i] = (int)v;
    }
    if (st) wv_error_prefix(err, "%s", path);
  }
  if (!st) {
    resolve_recorded(dir, ph, photo, pcap);
    snprintf(desc, dcap, "%s", de);
    if (we)
      resolve_recorded(dir, we, weights, wcap);
    else
      weights[0] = '\0';
    snprintf(label, lcap, "%s", lb ? lb : "start");
    char *sj = json_dumps(scene, JSON_REAL_PRECISION(17));
    st = sj ? wv_scene_parse(sj, path, s, err) : wv_fail(err, WV_ERR_NOMEM, "%s: out of memory", path);
    free(sj);
  }
  json_decref(o);
  return st;
}

int cmd_fit(int argc, char **argv) {
  cli_ctx c = {0, 0, "fit"};
  capture_args ca;
  cli_capture_args_init(&ca);
  CLI_PARSE(&CMD, argc, argv, &ca, &c);
  const char *photo = ca.photo, *scene_name = ca.scene, *init = ca.init, *pattern = ca.pattern, *dir = ca.out;
  const char *resume = ca.resume, *desc_name = ca.descriptor, *weights = ca.weights;
  wv_crop crop = ca.crop;
  int force = ca.force, iters_given = ca.iters_given;
  fit_job job;
  memset(&job, 0, sizeof job);
  job.opts = ca.fit, job.drape = ca.drape;
  wv_error err = {0};
  wv_scene scene;
  char photo_buf[4096], desc_buf[64], weights_buf[4096], label_buf[32];
  if (resume) {
    if (init || pattern || scene_name || dir)
      return cli_usage_error(c.cmd, "--resume DIR takes its photo, scene, start and output from DIR");
    if (read_job(resume, photo_buf, sizeof photo_buf, &crop, &scene, desc_buf, sizeof desc_buf, weights_buf,
                 sizeof weights_buf, label_buf, sizeof label_buf, &err))
      return cli_fail(&c, &err);
    if (photo && !wv_same_file(photo, photo_buf))
      return cli_usage_error(c.cmd, "%s was fitted to %s, not %s", resume, photo_buf, photo);
    photo = photo_buf, desc_name = desc_buf, weights = weights_buf[0] ? weights_buf : NULL, dir = resume;
  } else {
    if (!photo) return cli_usage_error(c.cmd, "a PHOTO is required");
    if (!scene_name) return cli_usage_error(c.cmd, "--scene is required");
    if (!dir) return cli_usage_error(c.cmd, "-o DIR is required");
    if (!init && !pattern) return cli_usage_error(c.cmd, "give --init P.json or --pattern NAME");
    if (wv_scene_load(scene_name, &scene, &err)) return cli_fail(&c, &err);
  }
  /* Everything is checked before anything is written; the directory first (cheap). */
  job.dir = dir, job.resume = resume != NULL, job.force = force;
  const char *inputs[] = {photo, resume ? NULL : scene_name, init, weights};
  memcpy(job.inputs, inputs, sizeof inputs);
  int rc = fit_check_dir(&c, &job);
  if (rc) return rc;
  wv_params start;
  if (!resume) {
    if (init) {
      if (wv_params_read(init, &start, &err)) return cli_fail(&c, &err);
      if (pattern && strcmp(pattern, start.pattern)) {
        fprintf(stderr, "woven fit: error: --pattern %s disagrees with %s (pattern '%s')\n", pattern, init,
                start.pattern);
        return WV_ERR_INVALID;
      }
    } else if (wv_params_default(pattern, &start, &err)) {
      return cli_fail(&c, &err);
    }
  }
  wv_descriptor *desc;
  if (wv_descriptor_create(desc_name, weights, &desc, &err)) return cli_fail(&c, &err);
  wv_image ph = {0};
  wv_photo_info info;
  if ((!resume && wv_fit_check_sizes(&scene, desc, &job.opts, &err)) ||
      wv_photo_load(photo, &scene, &crop, &ph, &info, &err)) {
    wv_descriptor_free(desc);
    return cli_fail(&c, &err);
  }
  job.crop = (wv_crop){info.crop[0], info.crop[1], info.crop[2], info.crop[3]};
  job.weights = weights;
  job.scene = &scene, job.photo = &ph, job.desc = desc, job.start = resume ? NULL : &start;
  job.photo_path = photo, job.iters_given = iters_given;
  job.start_label = resume ? label_buf : init ? "start" : "prior";
  job.title = "woven fit";
  rc = fit_pipeline(&c, &job);
  wv_descriptor_free(desc);
  wv_image_free(&ph);
  return rc;
}
