/* woven fit: refine parameters from a photo; also the back half of woven capture. */
#include <errno.h>
#include <jansson.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "cli.h"
#include "woven/descriptor.h"
#include "woven/fit.h"
#include "woven/io.h"
#include "woven/maps.h"
#include "woven/metrics.h"
#include "woven/photo.h"
#include "woven/render.h"
#include "woven/report.h"

static const char *HELP =
    "usage: woven fit PHOTO --scene S.json|cylinder|flat45 [--init P.json | --pattern NAME] -o DIR\n"
    "                 [--iters N] [--descriptor default|vgg19] [--vgg19-weights FILE]\n"
    "                 [--crop x,y,w,h] [--iter-spp N] [--iter-scale N] [--align-radius N]\n"
    "                 [--register-radius N] [--w-struct X] [--no-colour-split]\n"
    "                 [--seed N] [--threads N]\n"
    "                 [--force] [--quiet] [--json]\n"
    "       woven fit --resume DIR [--iters N] [--quiet] [--json]\n"
    "\n"
    "Refines fabric parameters so that a render of the scene matches the photo (paper 4.3):\n"
    "Gram-matrix loss + 16x8 pixel loss + heightfield prior + the weave's spectrum (structure),\n"
    "Adam (lr 0.01) on the continuous\n"
    "parameters, random steps of noise level and densities every 5 iterations.\n"
    "  --init P.json     start here; --pattern NAME starts from the pattern's prior mean\n"
    "  --iters N         iterations (default 200)\n"
    "  --crop x,y,w,h    use this rectangle of the photo (default: centred, the scene's aspect)\n"
    "  --iter-spp N      samples per pixel while iterating (default 4)\n"
    "  --align-radius N  after the iterations, search each density +-N yarns/inch for the\n"
    "                    best SSIM in a centre window (default 230: the whole range; 0 = off)\n"
    "  --register-radius N  then register the weave to the photo: densities on a 2-D grid\n"
    "                    +-N yarns/inch refined to 0.1, and the weave's offset, by phase\n"
    "                    correlation; kept if the SSIM rises (default 6; 0 = off)\n"
    "  --w-struct X      weight of the structure term, the weave's log power spectrum (default 0.002;\n"
    "                    0 = off)\n"
    "  --no-colour-split do not try starts that split the warp and weft diffuse colours\n"
    "  --iter-scale N    iterate on the image downscaled N times (default 1); the final render\n"
    "                    and SSIM use the scene's full resolution and spp\n"
    "  --force           replace the results of an earlier fit in DIR\n"
    "  --resume DIR      continue a fit that was stopped (checkpoints every 10 iterations)\n"
    "Writes to DIR: params.json, render.png, compare.png (photo | start | fit), loss.svg,\n"
    "report.html, maps/, and fit.json + checkpoint.json (for --resume).\n";

int cli_parse_fit_opt(cli_args *a, const char *s, wv_fit_opts *o, int *iters_given, int *handled) {
  long v;
  *handled = 1;
  if (cli_is(a, s, "--iters")) {
    if (!cli_int(a, "--iters", 0, 100000, &v)) return EXIT_USAGE;
    o->iters = (int)v, *iters_given = 1;
  } else if (cli_is(a, s, "--iter-spp")) {
    if (!cli_int(a, "--iter-spp", 1, 4096, &v)) return EXIT_USAGE;
    o->iter_spp = (int)v;
  } else if (cli_is(a, s, "--iter-scale")) {
    if (!cli_int(a, "--iter-scale", 1, 16, &v)) return EXIT_USAGE;
    o->iter_scale = (int)v;
  } else if (cli_is(a, s, "--seed")) {
    if (!cli_int(a, "--seed", 0, 2147483647L, &v)) return EXIT_USAGE;
    o->seed = (uint64_t)v;
  } else if (cli_is(a, s, "--align-radius")) {
    if (!cli_int(a, "--align-radius", 0, 230, &v)) return EXIT_USAGE;
    o->align_radius = (int)v;
  } else if (cli_is(a, s, "--register-radius")) {
    if (!cli_int(a, "--register-radius", 0, 50, &v)) return EXIT_USAGE;
    o->register_radius = (int)v;
  } else if (cli_is(a, s, "--w-struct")) {
    const char *t = cli_value(a, "--w-struct");
    char *end;
    if (!t) return EXIT_USAGE;
    double w = strtod(t, &end);
    if (*end || !(w >= 0 && w <= 100)) return cli_usage_error(a->cmd, "--w-struct must be a number in [0, 100]");
    o->w_struct = w;
  } else if (!strcmp(s, "--no-colour-split")) {
    o->colour_split = 0;
  } else if (cli_is(a, s, "--threads")) {
    if (!cli_int(a, "--threads", 1, 1024, &v)) return EXIT_USAGE;
    o->threads = (int)v;
  } else {
    *handled = 0;
  }
  return 0;
}

int cli_parse_crop(const char *s, wv_crop *c) {
  char tail;
  return sscanf(s, "%d,%d,%d,%d%c", &c->x, &c->y, &c->w, &c->h, &tail) == 4 && c->w > 0 && c->h > 0 && c->x >= 0 &&
         c->y >= 0;
}

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

/* A directory for results: created if missing; refused if it holds an earlier fit
 * and the user did not say --force. */
int fit_prepare_dir(const char *cmd, const char *dir, int force, int resume) {
  struct stat sb;
  if (stat(dir, &sb) == 0) {
    if (!S_ISDIR(sb.st_mode)) {
      fprintf(stderr, "woven %s: error: %s exists and is not a directory\n", cmd, dir);
      return WV_ERR_IO;
    }
    char p[4096];
    snprintf(p, sizeof p, "%s/params.json", dir);
    if (!resume && !force && stat(p, &sb) == 0) {
      fprintf(stderr, "woven %s: error: %s already holds a fit (params.json); use --force to replace it\n", cmd, dir);
      return WV_ERR_IO;
    }
    return 0;
  }
  if (mkdir(dir, 0777) != 0) {
    fprintf(stderr, "woven %s: error: %s: cannot create directory: %s\n", cmd, dir, strerror(errno));
    return WV_ERR_IO;
  }
  return 0;
}

int fit_pipeline(cli_ctx *c, const fit_job *job) {
  wv_error err = {0};
  char path[4096], ckpt[4096];
  snprintf(ckpt, sizeof ckpt, "%s/checkpoint.json", job->dir);
  wv_fit_state st;
  wv_fit_opts o = job->opts;
  if (job->resume) {
    char dname[64];
    if (wv_fit_checkpoint_read(ckpt, &st, &o, dname, sizeof dname, &err)) return cli_fail(c, &err);
    if (strcmp(dname, wv_descriptor_name(job->desc))) {
      wv_fit_state_free(&st);
      fprintf(stderr, "woven %s: error: %s was made with descriptor '%s', not '%s'\n", c->cmd, ckpt, dname,
              wv_descriptor_name(job->desc));
      return WV_ERR_INVALID;
    }
    if (job->opts.iters > 0 && job->iters_given) o.iters = job->opts.iters;
    if (st.iter > o.iters) o.iters = st.iter;
  } else if (wv_fit_state_init(&st, job->start, &o, &err)) {
    return cli_fail(c, &err);
  }
  fit_cb_ctx u = {c, {0}, ckpt, wv_descriptor_name(job->desc), &err, 0};
  cli_progress_start(&u.bar, c, "fit");
  if (!job->resume || st.iter < o.iters)
    cli_info(c, "fitting %s: %d iterations from %d (%s start, iterating at 1/%d scale, %d spp)\n", job->photo_path,
             o.iters, st.iter, job->start_label, o.iter_scale, o.iter_spp);
  wv_status rc = wv_fit_run(&st, job->scene, job->photo, job->desc, &o, on_iter, &u, &err);
  cli_progress_end(&u.bar);
  if (!rc && !u.ckpt_failed) rc = wv_fit_checkpoint_write(ckpt, &st, &o, u.descriptor, &err); /* with the alignment */
  if (rc || u.ckpt_failed) {
    wv_fit_state_free(&st);
    return cli_fail(c, &err);
  }
  /* Final renders at full quality: the start and the fit. */
  wv_render_opts ro = {0, o.threads, NULL, NULL, NULL};
  wv_image r_start = {0}, r_fit = {0}, cmp = {0};
  double ssim_start = 0, ssim_fit = 0;
  cli_info(c, "rendering start and fit at %d x %d, %d spp\n", job->scene->width, job->scene->height,
           job->scene->spp);
  rc = wv_render(job->scene, &st.start, &ro, &r_start, NULL, &err);
  wv_scene fit_scene; /* with the registration's fabric offset */
  wv_fit_scene(&st, job->scene, &fit_scene);
  if (!rc) rc = wv_render(&fit_scene, &st.params, &ro, &r_fit, NULL, &err);
  if (!rc) rc = wv_ssim(job->photo, &r_start, WV_SSIM_LUMA, &ssim_start, &err);
  if (!rc) rc = wv_ssim(job->photo, &r_fit, WV_SSIM_LUMA, &ssim_fit, &err);
  const wv_image *side[3] = {job->photo, &r_start, &r_fit};
  if (!rc) rc = wv_image_hconcat(side, 3, 4, &cmp, &err);
  char pphoto[4096], pstart[4096], pfit[4096];
  snprintf(pphoto, sizeof pphoto, "%s/photo.png", job->dir);
  snprintf(pstart, sizeof pstart, "%s/start.png", job->dir);
  snprintf(pfit, sizeof pfit, "%s/render.png", job->dir);
  if (!rc) rc = wv_image_write_png(pphoto, job->photo, 8, &err);
  if (!rc) rc = wv_image_write_png(pstart, &r_start, 8, &err);
  if (!rc) rc = wv_image_write_png(pfit, &r_fit, 8, &err);
  snprintf(path, sizeof path, "%s/compare.png", job->dir);
  if (!rc) rc = wv_image_write_png(path, &cmp, 8, &err);
  char *svg = rc ? NULL : wv_loss_svg(st.log, st.iter, &o);
  if (!rc && !svg) rc = wv_fail(&err, WV_ERR_NOMEM, "out of memory for the loss plot");
  snprintf(path, sizeof path, "%s/loss.svg", job->dir);
  if (!rc) rc = wv_write_file_atomic(path, svg, strlen(svg), &err);
  wv_report rep = {job->title,  pphoto,      pstart,     pfit,      job->start_label,      ssim_start, ssim_fit,
                   &st.start,   &st.params,  svg,        &st.timing, st.iter,              wv_descriptor_name(job->desc),
                   job->pattern_choice};
  snprintf(path, sizeof path, "%s/report.html", job->dir);
  if (!rc) rc = wv_report_write_html(path, &rep, &err);
  free(svg);
  wv_maps maps = {0};
  snprintf(path, sizeof path, "%s/maps", job->dir);
  if (!rc) rc = wv_maps_generate(&st.params, 1024, &maps, &err);
  if (!rc) rc = wv_maps_write(&maps, path, "png", &err);
  wv_maps_free(&maps);
  /* scene.json: the scene with the registered offset, to re-render exactly this fit */
  snprintf(path, sizeof path, "%s/scene.json", job->dir);
  char *scene_text = rc ? NULL : wv_scene_to_json(&fit_scene);
  if (!rc && !scene_text) rc = wv_fail(&err, WV_ERR_NOMEM, "out of memory for scene.json");
  if (!rc) rc = wv_write_file_atomic(path, scene_text, strlen(scene_text), &err);
  free(scene_text);
  /* params.json last: its presence marks a finished fit */
  snprintf(path, sizeof path, "%s/params.json", job->dir);
  if (!rc) rc = wv_params_write(path, &st.params, &err);
  wv_image_free(&r_start), wv_image_free(&r_fit), wv_image_free(&cmp);
  if (rc) {
    wv_fit_state_free(&st);
    return cli_fail(c, &err);
  }
  const wv_fit_record *last = st.iter ? &st.log[st.iter - 1] : NULL;
  cli_info(c, "SSIM %s %.4f -> fit %.4f; %d iterations in %.1f s; results in %s/\n", job->start_label, ssim_start,
           ssim_fit, st.iter, st.timing.total, job->dir);
  if (c->json) {
    char *pj = wv_params_to_json(&st.params);
    char *pc = job->pattern_choice ? wv_pattern_choice_to_json(job->pattern_choice) : NULL;
    printf("{\"dir\": \"%s\", \"iterations\": %d, \"ssim_start\": %.6f, \"ssim_fit\": %.6f, \"loss\": %.8f, "
           "\"time_s\": {\"total\": %.3f, \"render\": %.3f, \"gradient\": %.3f, \"descriptor\": %.3f, "
           "\"discrete\": %.3f, \"registration\": %.3f}, \"density_alignment_ssim\": [%.4f, %.4f], "
           "\"registration\": {\"offset_mm\": [%.6f, %.6f], \"ncc\": [%.4f, %.4f], \"window_ssim\": [%.4f, %.4f]}, "
           "\"pattern_choice\": %s, \"params\": %s}\n",
           job->dir, st.iter, ssim_start, ssim_fit, last ? last->loss : 0.0, st.timing.total, st.timing.render,
           st.timing.gradient, st.timing.descriptor, st.timing.discrete, st.timing.registration,
           st.align_ssim_before, st.align_ssim_after, st.offset_mm[0], st.offset_mm[1], st.reg_ncc_before,
           st.reg_ncc_after, st.reg_ssim_before, st.reg_ssim_after, pc ? pc : "null", pj ? pj : "null");
    free(pj), free(pc);
  }
  wv_fit_state_free(&st);
  return 0;
}

/* fit.json records what a resume needs: the photo, crop, scene and descriptor. */
wv_status fit_write_job(const char *dir, const char *photo, const wv_crop *crop, const wv_scene *s,
                           const char *descriptor, const char *weights, const wv_pattern_choice *pc,
                           wv_error *err) {
  char *sj = wv_scene_to_json(s);
  json_t *scene = json_loads(sj, 0, NULL);
  free(sj);
  json_t *o = json_pack("{s:s,s:i,s:s,s:[i,i,i,i],s:o,s:s,s:s*}", "kind", "woven-fit", "version", 1, "photo", photo,
                        "crop", crop->x, crop->y, crop->w, crop->h, "scene", scene, "descriptor", descriptor,
                        "vgg19_weights", weights);
  if (pc) { /* informative: a resume does not need it */
    char *pj = wv_pattern_choice_to_json(pc);
    if (pj) json_object_set_new(o, "pattern_choice", json_loads(pj, 0, NULL));
    free(pj);
  }
  char *text = json_dumps(o, JSON_INDENT(2) | JSON_PRESERVE_ORDER | JSON_REAL_PRECISION(17));
  json_decref(o);
  char path[4096];
  snprintf(path, sizeof path, "%s/fit.json", dir);
  wv_status st = wv_write_file_atomic(path, text, strlen(text), err);
  free(text);
  return st;
}

static wv_status read_job(const char *dir, char *photo, size_t pcap, wv_crop *crop, wv_scene *s, char *desc,
                          size_t dcap, char *weights, size_t wcap, wv_error *err) {
  char path[4096];
  snprintf(path, sizeof path, "%s/fit.json", dir);
  json_error_t je;
  json_t *o = json_load_file(path, JSON_REJECT_DUPLICATES, &je);
  if (!o) return wv_fail(err, WV_ERR_INVALID, "%s is not a fit directory (no readable fit.json: %s)", dir, je.text);
  const char *ph = NULL, *de = NULL, *we = NULL, *kind = NULL;
  json_t *scene = NULL;
  wv_status st = WV_OK;
  if (json_unpack(o, "{s:s,s:s,s:[i,i,i,i],s:o,s:s,s?s}", "kind", &kind, "photo", &ph, "crop", &crop->x, &crop->y,
                  &crop->w, &crop->h, "scene", &scene, "descriptor", &de, "vgg19_weights", &we) ||
      strcmp(kind, "woven-fit")) {
    st = wv_fail(err, WV_ERR_FORMAT, "%s: not a woven fit description", path);
  } else {
    snprintf(photo, pcap, "%s", ph);
    snprintf(desc, dcap, "%s", de);
    snprintf(weights, wcap, "%s", we ? we : "");
    char *sj = json_dumps(scene, JSON_REAL_PRECISION(17));
    st = wv_scene_parse(sj, path, s, err);
    free(sj);
  }
  json_decref(o);
  return st;
}

int cmd_fit(int argc, char **argv) {
  cli_ctx c = {0, 0, "fit"};
  cli_args a;
  cli_args_init(&a, argc, argv, c.cmd);
  const char *photo = NULL, *scene_name = NULL, *init = NULL, *pattern = NULL, *dir = NULL, *resume = NULL;
  const char *desc_name = "default", *weights = NULL;
  wv_crop crop = {0, 0, 0, 0};
  int force = 0, iters_given = 0;
  fit_job job;
  memset(&job, 0, sizeof job);
  wv_fit_opts_default(&job.opts);
  for (const char *s; (s = cli_next(&a));) {
    int handled;
    if (cli_parse_fit_opt(&a, s, &job.opts, &iters_given, &handled)) return EXIT_USAGE;
    if (handled) continue;
    if (!strcmp(s, "--help") || !strcmp(s, "-h")) {
      fputs(HELP, stdout);
      return 0;
    } else if (cli_is(&a, s, "--scene")) {
      if (!(scene_name = cli_value(&a, "--scene"))) return EXIT_USAGE;
    } else if (cli_is(&a, s, "--init")) {
      if (!(init = cli_value(&a, "--init"))) return EXIT_USAGE;
    } else if (cli_is(&a, s, "--pattern")) {
      if (!(pattern = cli_value(&a, "--pattern"))) return EXIT_USAGE;
    } else if (cli_is(&a, s, "-o") || cli_is(&a, s, "--output")) {
      if (!(dir = cli_value(&a, "-o"))) return EXIT_USAGE;
    } else if (cli_is(&a, s, "--resume")) {
      if (!(resume = cli_value(&a, "--resume"))) return EXIT_USAGE;
    } else if (cli_is(&a, s, "--descriptor")) {
      if (!(desc_name = cli_value(&a, "--descriptor"))) return EXIT_USAGE;
    } else if (cli_is(&a, s, "--vgg19-weights")) {
      if (!(weights = cli_value(&a, "--vgg19-weights"))) return EXIT_USAGE;
    } else if (cli_is(&a, s, "--crop")) {
      const char *cv = cli_value(&a, "--crop");
      if (!cv) return EXIT_USAGE;
      if (!cli_parse_crop(cv, &crop)) return cli_usage_error(c.cmd, "--crop must be x,y,w,h (non-negative integers)");
    } else if (!strcmp(s, "--force")) {
      force = 1;
    } else if (cli_common_flag(&c, s)) {
      /* --quiet, -q, --json */
    } else if (s[0] == '-' && s[1]) {
      return cli_usage_error(c.cmd, "unknown option '%s'", s);
    } else if (!photo) {
      photo = s;
    } else {
      return cli_usage_error(c.cmd, "unexpected argument '%s'", s);
    }
  }
  wv_error err = {0};
  wv_scene scene;
  char photo_buf[4096], desc_buf[64], weights_buf[4096];
  if (resume) {
    if (init || pattern || scene_name || dir)
      return cli_usage_error(c.cmd, "--resume DIR takes its photo, scene, start and output from DIR");
    if (read_job(resume, photo_buf, sizeof photo_buf, &crop, &scene, desc_buf, sizeof desc_buf, weights_buf,
                 sizeof weights_buf, &err))
      return cli_fail(&c, &err);
    if (photo && strcmp(photo, photo_buf))
      return cli_usage_error(c.cmd, "%s was fitted to %s, not %s", resume, photo_buf, photo);
    photo = photo_buf, desc_name = desc_buf, weights = weights_buf[0] ? weights_buf : NULL, dir = resume;
  } else {
    if (!photo) return cli_usage_error(c.cmd, "a PHOTO is required");
    if (!scene_name) return cli_usage_error(c.cmd, "--scene is required");
    if (!dir) return cli_usage_error(c.cmd, "-o DIR is required");
    if (!init && !pattern) return cli_usage_error(c.cmd, "give --init P.json or --pattern NAME");
    if (wv_scene_load(scene_name, &scene, &err)) return cli_fail(&c, &err);
  }
  /* Everything is checked before anything is written. */
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
  if (scene.width < WV_FIT_MIN_SIDE || scene.height < WV_FIT_MIN_SIDE) {
    fprintf(stderr, "woven fit: error: the scene's image (%d x %d) is too small for a fit (at least %d x %d)\n",
            scene.width, scene.height, WV_FIT_MIN_SIDE, WV_FIT_MIN_SIDE);
    return WV_ERR_INVALID;
  }
  wv_image ph;
  wv_photo_info info;
  if (wv_photo_load(photo, &scene, &crop, &ph, &info, &err)) return cli_fail(&c, &err);
  wv_descriptor *desc;
  if (wv_descriptor_create(desc_name, weights, &desc, &err)) {
    wv_image_free(&ph);
    return cli_fail(&c, &err);
  }
  int rc = fit_prepare_dir(c.cmd, dir, force, resume != NULL);
  wv_crop used = {info.crop[0], info.crop[1], info.crop[2], info.crop[3]};
  if (!rc && !resume && fit_write_job(dir, photo, &used, &scene, desc_name, weights, NULL, &err)) rc = cli_fail(&c, &err);
  if (!rc) {
    job.scene = &scene, job.photo = &ph, job.desc = desc, job.start = resume ? NULL : &start;
    job.dir = dir, job.photo_path = photo, job.resume = resume != NULL, job.iters_given = iters_given;
    job.start_label = init ? "start" : "prior";
    job.title = "woven fit";
    rc = fit_pipeline(&c, &job);
  }
  wv_descriptor_free(desc);
  wv_image_free(&ph);
  return rc;
}
