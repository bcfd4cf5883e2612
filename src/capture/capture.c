/* woven: the capture jobs (woven/capture.h): a fit run with every output written into a
 * directory that appears whole or not at all, and the capture that chains FabricNet's
 * estimate of a photo (src/net/estimate.c) and that fit. */
#define _DEFAULT_SOURCE /* realpath */
#include "woven/capture.h"

#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "io/json_file.h"
#include "util/json.h"
#include "util/note.h"
#include "woven/analysis.h"
#include "woven/io.h"
#include "woven/maps.h"
#include "woven/metrics.h"
#include "woven/render.h"
#include "woven/scene3d.h"
#include "woven/view.h"

/* What a fit directory may hold (woven capture adds network.json). */
static const char *const FIT_FILES[] = {
    "fit.json",    "checkpoint.json", "params.json", "render.png",  "start.png", "photo.png",
    "compare.png", "loss.svg",        "report.html", "viewer.html", "drape.png", "maps",
    "scene.json",  "network.json",    "zoom.png",    "spectra.png", "photo_t.png", "render_t.png", "scene_t.json", NULL};

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

wv_status wv_fit_job_check_dir(const wv_fit_job *job, wv_error *err) {
  wv_status rc = wv_outdir_check(job->dir, FIT_FILES, err);
  if (!rc) rc = wv_check_not_input(job->dir, 1, job->inputs, (int)(sizeof job->inputs / sizeof job->inputs[0]), err);
  if (rc || job->resume || job->force) return rc;
  fit_dir_state ds = dir_state(job->dir);
  if (ds == FIT_DIR_FINISHED)
    return wv_fail(err, WV_ERR_IO, "%s already holds a fit (params.json); use --force to replace it", job->dir);
  if (ds == FIT_DIR_UNFINISHED)
    return wv_fail(err, WV_ERR_IO,
                   "%s holds an unfinished fit (fit.json, no params.json); continue it with 'woven fit --resume %s' "
                   "or replace it with --force",
                   job->dir, job->dir);
  return WV_OK;
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
static char *job_json(const wv_fit_job *job) {
  char *photo = realpath(job->photo_path, NULL), *weights = job->weights ? realpath(job->weights, NULL) : NULL;
  char *sj = wv_scene_to_json(job->scene);
  json_t *scene = sj ? json_loads(sj, 0, NULL) : NULL;
  free(sj);
  json_t *o = json_pack("{s:s,s:i,s:o,s:[i,i,i,i],s:o,s:s,s:s}", "kind", "woven-fit", "version", 1, "photo",
                        wv_json_str_lossy(photo ? photo : job->photo_path), "crop", job->crop.x, job->crop.y,
                        job->crop.w, job->crop.h, "scene", scene ? scene : json_null(), "descriptor",
                        wv_descriptor_name(job->desc), "start_label", job->start_label);
  if (o && job->weights) json_object_set_new(o, "vgg19_weights", wv_json_str_lossy(weights ? weights : job->weights));
  free(photo), free(weights);
  if (o && job->photo_t_path) { /* a photo pair: the transmission photo and its scene */
    char *pt = realpath(job->photo_t_path, NULL), *stj = wv_scene_to_json(job->scene_t);
    json_t *sc = stj ? json_loads(stj, 0, NULL) : NULL;
    json_object_set_new(o, "transmission", json_pack("{s:o,s:o}", "photo", wv_json_str_lossy(pt ? pt : job->photo_t_path),
                                                     "scene", sc ? sc : json_null()));
    free(pt), free(stj);
  }
  if (o && job->pattern_choice) /* informative: a resume does not need it */
    json_object_set_new(o, "pattern_choice", wv_json_from_text(wv_pattern_choice_to_json(job->pattern_choice)));
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
static int render_drape(const wv_fit_job *job, const char *dir, const wv_params *p, int threads, char *out, size_t cap,
                        char *note, size_t ncap, wv_error *err, wv_status *rc) {
  if (job->drape && !strcmp(job->drape, "none")) return 0;
  char scene[4096];
  const char *d = getenv("WOVEN_SCENE_DIR");
  if (job->drape)
    snprintf(scene, sizeof scene, "%s", job->drape);
  else
    snprintf(scene, sizeof scene, "%s/drape-studio.json", d && *d ? d : WOVEN_SCENE_DIR);
  struct stat sb;
  if (!job->drape && stat(scene, &sb) != 0) {
    snprintf(note, ncap, "No drape: the bundled scene %s was not found (set WOVEN_SCENE_DIR).", scene);
    return 0;
  }
  wv_scene3d_preview po = {.width = 512, .height = 384, .spp = 16, .threads = threads};
  wv_image img = {0};
  snprintf(out, cap, "%s/drape.png", dir);
  *rc = wv_scene3d_render_file(scene, p, &po, &img, err);
  if (!*rc) *rc = wv_image_write_png(out, &img, 8, err);
  wv_image_free(&img);
  if (*rc) return 0;
  snprintf(note, ncap,
           "The fit on %s under its lights, 512 x 384, 16 samples per pixel "
           "(<code>woven scene %s --params params.json</code> renders it in full).",
           job->drape ? "the scene given" : "the bundled draped cloth",
           job->drape ? "S.json" : "scenes/drape-studio.json");
  return 1;
}

/* The mean brightness of im over its centre (half of each side) [0] and the whole frame [1]. */
static wv_status centre_whole_mean(const wv_image *im, double m[2], wv_error *err) {
  wv_image c = {0};
  wv_status rc = wv_image_centre_crop(im, im->w / 2, im->h / 2, &c, err);
  if (!rc) m[0] = wv_image_mean(&c), m[1] = wv_image_mean(im);
  wv_image_free(&c);
  return rc;
}

/* A photo pair's transmission side: the fit re-rendered in the back-lit scene as the back-lit
 * photo sees the cloth (wv_fit_scene_t: its own scale, rotation, offset and distortion, the
 * fit's blur; the densities it shows), photo_t.png and render_t.png, and the figures against
 * the transmission photo. */
static wv_status write_transmission(const wv_fit_job *job, const char *dir, const wv_fit_state *st, int threads,
                                    wv_fit_outcome *out, char *pphoto, char *pfit, size_t cap, wv_error *err) {
  wv_scene fs;
  wv_params pt;
  wv_fit_scene_t(st, job->scene_t, &fs);
  wv_fit_params_t(st, &st->params, &pt);
  wv_render_opts ro = {.threads = threads};
  wv_image r = {0};
  wv_status rc = wv_render(&fs, &pt, &ro, &r, NULL, err);
  out->pair = 1, out->wsc_t = -2, out->ssim_rgb_blurred_t = -2, out->periodic_share_t = -2;
  out->below_blurred_copy_t = 0;
  if (!rc) rc = wv_ssim(job->photo_t, &r, WV_SSIM_RGB, &out->ssim_rgb_t, err);
  if (!rc && wv_wsc(job->photo_t, &r, &out->wsc_t, NULL)) out->wsc_t = -2; /* too small an image: not measured */
  if (!rc && wv_blurred_copy_ssim(job->photo_t, WV_BLURRED_COPY_SIGMA, &out->ssim_rgb_blurred_t, NULL))
    out->ssim_rgb_blurred_t = -2;
  if (!rc && out->ssim_rgb_blurred_t > -2) out->below_blurred_copy_t = out->ssim_rgb_t < out->ssim_rgb_blurred_t;
  if (!rc && wv_detail_periodic(job->photo_t, WV_BLURRED_COPY_SIGMA, &out->periodic_share_t, NULL, NULL))
    out->periodic_share_t = -2;
  if (!rc) rc = centre_whole_mean(job->photo_t, out->mean_t[0], err);
  if (!rc) rc = centre_whole_mean(&r, out->mean_t[1], err);
  snprintf(pphoto, cap, "%s/photo_t.png", dir);
  snprintf(pfit, cap, "%s/render_t.png", dir);
  if (!rc) rc = wv_image_write_png(pphoto, job->photo_t, 8, err);
  if (!rc) rc = wv_image_write_png(pfit, &r, 8, err);
  wv_image_free(&r);
  return rc;
}

static wv_status write_results(const wv_fit_job *job, const char *dir, const wv_fit_state *st, const wv_fit_opts *o,
                               const wv_scene *fit_scene, double *ssim_start, double *ssim_fit, wv_weave_views *wv,
                               wv_fit_outcome *out, wv_error *err) {
  wv_render_opts ro = {.threads = o->threads};
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
  char pphoto_t[4096], pfit_t[4096];
  if (!rc && job->photo_t)
    rc = write_transmission(job, dir, st, o->threads, out, pphoto_t, pfit_t, sizeof pphoto_t, err);
  char pdrape[4096], note[1024] = "";
  int drape = 0;
  if (!rc) drape = render_drape(job, dir, &st->params, o->threads, pdrape, sizeof pdrape, note, sizeof note, err, &rc);
  char *svg = rc ? NULL : wv_loss_svg(st->log, st->iter, o);
  if (!rc) rc = write_text(dir, "loss.svg", svg, err);
  wv_report rep = {.title = job->title,
                   .photo_png = pphoto,
                   .start_png = pstart,
                   .fit_png = pfit,
                   .start_label = job->start_label,
                   .ssim_start = *ssim_start,
                   .ssim_fit = *ssim_fit,
                   .start = &st->start,
                   .fit = &st->params,
                   .loss_svg = svg,
                   .timing = &st->timing,
                   .iters = st->iter,
                   .descriptor = wv_descriptor_name(job->desc),
                   .pattern_choice = job->pattern_choice,
                   .weave = wv,
                   .camera_blur = fit_scene->psf_sigma,
                   .camera_blur_measured = st->psf_fit ? st->psf_start : -1,
                   .viewer_html = "viewer.html",
                   .drape_png = drape ? pdrape : NULL,
                   .drape_note = note[0] ? note : NULL,
                   .photo_t_png = out->pair ? pphoto_t : NULL,
                   .fit_t_png = out->pair ? pfit_t : NULL,
                   .ssim_rgb_t = out->ssim_rgb_t,
                   .wsc_t = out->wsc_t,
                   .ssim_rgb_blurred_t = out->ssim_rgb_blurred_t,
                   .below_blurred_copy_t = out->below_blurred_copy_t,
                   .periodic_share_t = out->periodic_share_t,
                   .kt_fitted = wv_scene_transmits(job->scene),
                   .kt_start = job->kt_start,
                   .kt_tried = job->kt_tried,
                   .open_measured = st->open_measured,
                   .open_area = st->open_photo,
                   .view_t = out->pair && st->t_related,
                   .view_t_related = st->t_found,
                   .view_t_scale = st->t_scale,
                   .view_t_rotation_deg = st->t_rotation_deg};
  /* the viewer of the fit in its registered scene, with the photo (the report embeds it) */
  wv_view_opts vo = {.params = &st->params, .scene = fit_scene, .photo = pphoto, .title = job->title};
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
  if (!rc && job->photo_t) {
    /* scene_t.json: the back-lit scene as the back-lit photo sees the cloth (render_t.png with
     * params.json, the densities times view_t.density_ratio) */
    wv_scene fs_t;
    wv_fit_scene_t(st, job->scene_t, &fs_t);
    scene_text = wv_scene_to_json(&fs_t);
    rc = scene_text ? write_text(dir, "scene_t.json", scene_text, err) : wv_fail(err, WV_ERR_NOMEM, "out of memory");
    free(scene_text);
  }
  /* params.json last: its presence marks a finished fit */
  snprintf(path, sizeof path, "%s/params.json", dir);
  if (!rc) rc = wv_params_write(path, &st->params, err);
  return rc;
}

/* The state a run starts from and the directory its checkpoints go to (work): the
 * fit directory itself while it holds no finished fit, otherwise od's temporary
 * directory (*staged), so the finished fit stays whole until the new one replaces it. */
static wv_status open_state(const wv_fit_job *job, wv_fit_state *st, wv_fit_opts *o, wv_outdir *od, int *staged,
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
      return wv_fail(err, WV_ERR_IO,
                     "%s holds no checkpoint.json (stopped before its first checkpoint by an older "
                     "woven): start the fit again with --force",
                     job->dir);
    if ((rc = wv_fit_checkpoint_read(ckpt, st, o, dname, sizeof dname, err))) return rc;
    if (strcmp(dname, wv_descriptor_name(job->desc))) {
      wv_fit_state_free(st);
      return wv_fail(err, WV_ERR_INVALID, "%s/checkpoint.json was made with descriptor '%s', not '%s'", job->dir, dname,
                     wv_descriptor_name(job->desc));
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

/* Writes each checkpoint while fitting, then reports the iteration. */
typedef struct {
  const wv_fit_job *job;
  const char *ckpt;
  const char *descriptor;
  wv_error *err;
  int ckpt_failed;
} fit_cb_ctx;

static int on_iter(void *user, const wv_fit_state *st, const wv_fit_opts *o) {
  fit_cb_ctx *u = user;
  const wv_capture_progress *p = &u->job->progress;
  if (p->on_iter) p->on_iter(p->user, st, o);
  if (u->ckpt && o->checkpoint_every > 0 && (st->iter % o->checkpoint_every == 0 || st->iter == o->iters)) {
    if (wv_fit_checkpoint_write(u->ckpt, st, o, u->descriptor, u->err)) {
      u->ckpt_failed = 1;
      return 1;
    }
  }
  return 0;
}

wv_status wv_fit_job_run(const wv_fit_job *job, wv_fit_outcome *out, wv_error *err) {
  char work[4096], ckpt[4096];
  wv_fit_state st;
  wv_fit_opts o = job->opts;
  wv_outdir od = {NULL, NULL, -1};
  int staged = 0;
  wv_status rc;
  memset(out, 0, sizeof *out);
  if (job->drape && strcmp(job->drape, "none")) { /* a scene that cannot render is refused before the fit */
    wv_scene3d s3;
    if ((rc = wv_scene3d_read(job->drape, &s3, err))) return rc;
    wv_scene3d_free(&s3);
  }
  if ((rc = open_state(job, &st, &o, &od, &staged, work, sizeof work, err))) {
    wv_outdir_abort(&od, err);
    return rc;
  }
  snprintf(ckpt, sizeof ckpt, "%s/checkpoint.json", work);
  fit_cb_ctx u = {job, ckpt, wv_descriptor_name(job->desc), err, 0};
  if (!job->resume || st.iter < o.iters)
    wv_note(job->progress.on_note, job->progress.user,
            "fitting %s: %d iterations from %d (%s start, iterating at 1/%d scale, %d spp)", job->photo_path, o.iters,
            st.iter, job->start_label, o.iter_scale, o.iter_spp);
  rc = wv_fit_run_pair(&st, job->scene, job->photo, job->photo_t ? job->scene_t : NULL, job->photo_t, job->desc, &o,
                       on_iter, &u, err);
  if (!rc && !u.ckpt_failed) rc = wv_fit_checkpoint_write(ckpt, &st, &o, u.descriptor, err); /* with the alignment */
  if (u.ckpt_failed && !rc) rc = err->code;
  /* The results go into a temporary directory that then replaces the fit directory. */
  if (!rc && !staged && !(rc = wv_outdir_begin(&od, job->dir, FIT_FILES, err))) {
    if (!(rc = copy_into(job->dir, "fit.json", od.tmp, 0, err)) &&
        !(rc = copy_into(job->dir, "checkpoint.json", od.tmp, 0, err)))
      rc = copy_into(job->dir, "network.json", od.tmp, 1, err);
  }
  out->views = (wv_weave_views){
      .wsc = {-2, -2}, .wsc_whitened = {-2, -2}, .ssim_rgb_blurred = -2, .periodic_share = -2};
  wv_fit_scene(&st, job->scene, &out->fit_scene); /* with the registration's fabric offset */
  if (!rc)
    wv_note(job->progress.on_note, job->progress.user, "rendering start and fit at %d x %d, %d spp", job->scene->width,
            job->scene->height, job->scene->spp);
  if (!rc)
    rc = write_results(job, od.tmp, &st, &o, &out->fit_scene, &out->ssim_start, &out->ssim_fit, &out->views, out, err);
  if (!rc) rc = wv_outdir_commit(&od, err);
  if (rc) {
    wv_outdir_abort(&od, err);
    wv_fit_state_free(&st);
    return rc;
  }
  out->state = st;
  snprintf(out->start_label, sizeof out->start_label, "%s", job->start_label);
  return WV_OK;
}

wv_status wv_pair_scene(const char *scene, const wv_scene *s, const char *scene_t, wv_scene *out, wv_error *err) {
  wv_status rc;
  if (scene_t) {
    if ((rc = wv_scene_load(scene_t, out, err))) return rc;
    if (!wv_scene_transmits(out))
      return wv_fail(err, WV_ERR_INVALID,
                     "%s is not a back-lit scene (a plane with its light below the cloth): it cannot render the "
                     "transmission photo",
                     scene_t);
  } else if (scene && !strcmp(scene, "flat45")) {
    if ((rc = wv_scene_load("flat45-back", out, err))) return rc;
  } else {
    return wv_fail(err, WV_ERR_INVALID,
                   "the scene %s has no built-in back-lit counterpart for --transmission: name one with "
                   "--transmission-scene S.json",
                   scene ? scene : "given");
  }
  if (out->width != s->width || out->height != s->height)
    return wv_fail(err, WV_ERR_INVALID, "the back-lit scene %s renders %d x %d, not the %d x %d of %s",
                   scene_t ? scene_t : "flat45-back", out->width, out->height, s->width, s->height,
                   scene ? scene : "the scene");
  return WV_OK;
}

/* The transmission photo of a pair, brought to its scene with the reflection photo's crop;
 * taken by the same camera, its file must have the reflection photo's size. */
static wv_status load_photo_t(const char *path, const wv_scene *s_t, const wv_crop *crop, const char *photo,
                              const wv_photo_info *ri, wv_image *out, wv_error *err) {
  wv_photo_info ti;
  /* read whole first (its own centre crop), so that a photo of another size is named as such */
  wv_status rc = wv_photo_load(path, s_t, &(wv_crop){0, 0, 0, 0}, out, &ti, err);
  if (rc) {
    if (!strstr(err->msg, path)) wv_error_prefix(err, "%s", path);
    return rc;
  }
  if (ti.width != ri->width || ti.height != ri->height) {
    wv_image_free(out);
    return wv_fail(err, WV_ERR_INVALID,
                   "%s is %d x %d but the reflection photo %s is %d x %d: a photo pair is taken by one camera", path,
                   ti.width, ti.height, photo, ri->width, ri->height);
  }
  if (!memcmp(ti.crop, (int[4]){crop->x, crop->y, crop->w, crop->h}, sizeof ti.crop)) return WV_OK;
  wv_image_free(out); /* the reflection photo's crop differs from the centre one: read it with that crop */
  return wv_photo_load(path, s_t, crop, out, &ti, err);
}

wv_status wv_fit_dir_run(const wv_fit_dir_opts *o, wv_fit_outcome *out, wv_error *err) {
  const wv_fit_record_job *rec = o->resume;
  const char *photo = rec ? rec->photo : o->photo, *desc_name = rec ? rec->descriptor : o->descriptor;
  const char *weights = rec ? (rec->weights[0] ? rec->weights : NULL) : o->weights;
  wv_crop crop = rec ? rec->crop : o->crop;
  wv_fit_job job;
  memset(&job, 0, sizeof job);
  job.opts = o->fit, job.drape = o->drape, job.progress = o->progress;
  wv_scene scene;
  wv_status rc;
  if (rec)
    scene = rec->scene;
  else if ((rc = wv_scene_load(o->scene, &scene, err)))
    return rc;
  /* Everything is checked before anything is written; the directory first (cheap). */
  job.dir = o->dir, job.resume = rec != NULL, job.force = o->force;
  const char *inputs[] = {photo, rec ? NULL : o->scene, o->init, weights, rec ? NULL : o->photo_t,
                          rec ? NULL : o->scene_t};
  memcpy(job.inputs, inputs, sizeof inputs);
  if ((rc = wv_fit_job_check_dir(&job, err))) return rc;
  wv_params start;
  if (!rec && o->init) {
    if ((rc = wv_params_read(o->init, &start, err))) return rc;
    if (o->pattern && strcmp(o->pattern, start.pattern))
      return wv_fail(err, WV_ERR_INVALID, "--pattern %s disagrees with %s (pattern '%s')", o->pattern, o->init,
                     start.pattern);
  } else if (!rec && (rc = wv_params_default(o->pattern, &start, err))) {
    return rc;
  }
  wv_descriptor *desc;
  if ((rc = wv_descriptor_create(desc_name ? desc_name : "default", weights, &desc, err))) return rc;
  wv_image ph = {0}, ph_t = {0};
  wv_photo_info info;
  const char *photo_t = rec ? (rec->photo_t[0] ? rec->photo_t : NULL) : o->photo_t;
  wv_scene scene_t;
  memset(&scene_t, 0, sizeof scene_t);
  if (rec && photo_t)
    scene_t = rec->scene_t;
  else if (photo_t && (rc = wv_pair_scene(o->scene, &scene, o->scene_t, &scene_t, err))) {
    wv_descriptor_free(desc);
    return rc;
  }
  if ((rec || !(rc = wv_fit_check_sizes(&scene, desc, &job.opts, err))) &&
      !(rc = wv_photo_load(photo, &scene, &crop, &ph, &info, err)) &&
      !(photo_t && (rc = load_photo_t(photo_t, &scene_t, &(wv_crop){info.crop[0], info.crop[1], info.crop[2], info.crop[3]},
                                      photo, &info, &ph_t, err)))) {
    if (photo_t) job.scene_t = &scene_t, job.photo_t = &ph_t, job.photo_t_path = photo_t;
    job.crop = (wv_crop){info.crop[0], info.crop[1], info.crop[2], info.crop[3]};
    job.weights = weights;
    job.scene = &scene, job.photo = &ph, job.desc = desc, job.start = rec ? NULL : &start;
    job.photo_path = photo, job.iters_given = o->iters_given;
    job.start_label = rec ? rec->start_label : o->init ? "start" : "prior";
    job.title = "woven fit";
    rc = wv_fit_job_run(&job, out, err);
  }
  wv_descriptor_free(desc);
  wv_image_free(&ph), wv_image_free(&ph_t);
  return rc;
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

wv_status wv_fit_job_read(const char *dir, wv_fit_record_job *rec, wv_error *err) {
  char *photo = rec->photo, *desc = rec->descriptor, *weights = rec->weights, *label = rec->start_label;
  size_t pcap = sizeof rec->photo, dcap = sizeof rec->descriptor, wcap = sizeof rec->weights,
         lcap = sizeof rec->start_label;
  wv_crop *crop = &rec->crop;
  wv_scene *s = &rec->scene;
  char path[4096];
  snprintf(path, sizeof path, "%s/fit.json", dir);
  struct stat sb;
  if (stat(path, &sb) != 0) return wv_fail(err, WV_ERR_INVALID, "%s is not a fit directory (no fit.json)", dir);
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
  rec->photo_t[0] = '\0';
  json_t *tr = json_object_get(o, "transmission");
  if (!st && tr) { /* a photo pair */
    const char *pt = NULL;
    json_t *ts = NULL;
    if (json_unpack(tr, "{s:s,s:o}", "photo", &pt, "scene", &ts)) {
      st = wv_fail(err, WV_ERR_FORMAT, "%s: \"transmission\" needs a photo and a scene", path);
    } else {
      resolve_recorded(dir, pt, rec->photo_t, sizeof rec->photo_t);
      char *sj = json_dumps(ts, JSON_REAL_PRECISION(17));
      st = sj ? wv_scene_parse(sj, path, &rec->scene_t, err) : wv_fail(err, WV_ERR_NOMEM, "%s: out of memory", path);
      free(sj);
    }
  }
  json_decref(o);
  return st;
}

void wv_capture_fit_opts(const wv_pattern_choice *pc, int align_given, wv_fit_opts *o) {
  if (!pc || !pc->lattice.found) return;
  if (!align_given && o->align_radius > WV_CAPTURE_ALIGN_RADIUS) o->align_radius = WV_CAPTURE_ALIGN_RADIUS;
  o->density_steps = 0; /* random density steps follow what the Gram loss prefers, often an alias */
}

wv_status wv_capture_pair_start(wv_estimate *est, const wv_scene *scene_t, const wv_image *photo_t,
                                const wv_fit_opts *fo, int *kt_model, wv_error *err) {
  wv_params cand[2] = {est->params, est->params};
  wv_params_transmission_default(&cand[1]);
  wv_scene sc[2] = {est->scene, *scene_t};
  const wv_image *ph[2] = {&est->photo, photo_t};
  double loss[2] = {0, 0};
  for (int k = 0; k < 2; k++) {
    sc[k].spp = fo->iter_spp;
    for (int c = 0; c < 2; c++) {
      wv_fit_record rec = {0};
      wv_status rc = wv_fit_loss(&sc[k], ph[k], est->desc, &cand[c], fo, &rec, err);
      if (rc) return rc;
      loss[c] += rec.loss;
    }
  }
  if (!(loss[0] < loss[1])) est->params = cand[1], *kt_model = 2;
  return WV_OK;
}

wv_status wv_capture_run(const wv_capture_opts *o, wv_estimate *est, wv_fit_outcome *out, wv_error *err) {
  memset(est, 0, sizeof *est);
  /* Everything is checked before anything is written; the directory first (cheap). */
  wv_fit_job job;
  memset(&job, 0, sizeof job);
  job.opts = o->fit, job.drape = o->drape, job.dir = o->dir, job.force = o->force;
  const char *inputs[] = {o->estimate.photo, o->estimate.scene, o->estimate.model, o->estimate.weights,
                          o->photo_t, o->scene_t, o->pair_model};
  memcpy(job.inputs, inputs, sizeof inputs);
  wv_status rc = wv_fit_job_check_dir(&job, err);
  if (rc) return rc;
  wv_scene scene, scene_t; /* loaded once: the fit's size limits are checked before the network runs */
  if ((rc = wv_scene_load(o->estimate.scene, &scene, err)) || (rc = wv_fit_check_sizes(&scene, NULL, &o->fit, err)))
    return rc;
  wv_image ph_t = {0};
  if (o->photo_t) { /* the pair's photo read before the network runs (the crop: the photo's, as the estimate takes it) */
    wv_image ph = {0};
    wv_photo_info info;
    if ((rc = wv_pair_scene(o->estimate.scene, &scene, o->scene_t, &scene_t, err)) ||
        (rc = wv_photo_load(o->estimate.photo, &scene, &o->estimate.crop, &ph, &info, err)))
      return rc;
    wv_image_free(&ph);
    if ((rc = load_photo_t(o->photo_t, &scene_t, &(wv_crop){info.crop[0], info.crop[1], info.crop[2], info.crop[3]},
                           o->estimate.photo, &info, &ph_t, err)))
      return rc;
  }
  int kt_model = 0; /* a pair model for the transmission colours' start, checked before the network runs */
  char kt_path[4096];
  if (o->photo_t && (rc = wv_estimate_pair_model(&scene, &scene_t, o->pair_model, kt_path, sizeof kt_path, &kt_model, err))) {
    wv_image_free(&ph_t);
    return rc;
  }
  if ((rc = wv_estimate_run_scene(&o->estimate, &scene, est, err)) ||
      (kt_model && (rc = wv_estimate_transmission(est, &scene_t, &ph_t, kt_path, err)))) {
    wv_image_free(&ph_t);
    if (est->desc) wv_estimate_free(est);
    return rc;
  }
  /* the same camera sees the cloth at the same angle lit from behind: the pattern choice's
   * rotation and skew of the weave lattice go to the back-lit scene too */
  if (o->photo_t && est->chosen) wv_pattern_choice_scene(&est->choice, &scene_t, est->choice.best, &scene_t);
  if (kt_model && (rc = wv_capture_pair_start(est, &scene_t, &ph_t, &o->fit, &kt_model, err))) {
    wv_image_free(&ph_t);
    wv_estimate_free(est);
    return rc;
  }
  if (o->on_estimate) o->on_estimate(o->progress.user, est);
  char *network = wv_params_to_json(&est->params), *nl = network ? realloc(network, strlen(network) + 2) : NULL;
  if (nl) strcat(nl, "\n"), network = nl; /* as wv_params_write writes it */
  if (!(rc = wv_fit_check_sizes(&est->scene, est->desc, &o->fit, err)) && !network)
    rc = wv_fail(err, WV_ERR_NOMEM, "out of memory");
  if (!rc) {
    job.crop = (wv_crop){est->info.crop[0], est->info.crop[1], est->info.crop[2], est->info.crop[3]};
    job.weights = o->estimate.weights;
    job.extra_name = "network.json", job.extra_text = network;
    job.scene = &est->scene, job.photo = &est->photo, job.desc = est->desc, job.start = &est->params;
    job.pattern_choice = est->chosen ? &est->choice : NULL;
    wv_capture_fit_opts(est->chosen ? &est->choice : NULL, o->align_given, &job.opts);
    job.photo_path = o->estimate.photo, job.iters_given = o->iters_given;
    job.start_label = "network";
    job.title = "woven capture";
    job.progress = o->progress;
    if (o->photo_t) job.scene_t = &scene_t, job.photo_t = &ph_t, job.photo_t_path = o->photo_t;
    job.kt_start = kt_model == 1 ? kt_path : NULL, job.kt_tried = kt_model == 2;
    rc = wv_fit_job_run(&job, out, err);
    if (!rc) out->kt_model = kt_model;
  }
  wv_image_free(&ph_t);
  free(network);
  if (rc) wv_estimate_free(est);
  return rc;
}
