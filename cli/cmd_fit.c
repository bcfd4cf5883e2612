/* woven fit: refine parameters from a photo (the job is the library's, woven/capture.h);
 * also the options and the summary woven capture shares. */
#include <errno.h>
#include <limits.h>
#include <jansson.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "woven/descriptor.h"
#include "woven/fit.h"
#include "woven/io.h"
#include "woven/nn.h"
#include "woven/photo.h"

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

static int parse_align(const char *cmd, const cli_opt *o, const char *v, void *base) {
  capture_args *a = base;
  a->align_given = 1;
  return cli_opt_int(cmd, o, v, &a->fit.align_radius);
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
  if (!strcmp(v, "auto") || !strcmp(v, "measured")) {
    a->fit.psf_sigma = WV_FIT_PSF_AUTO;
    a->fit.psf_fit = !strcmp(v, "auto");
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

const cli_opt CLI_PAIR_OPTS[] = {
    CLI_O_STR("--transmission", NULL, capture_args, transmission, "T.png",
              "a back-lit photo of the same cloth by the same camera: one set of\nparameters is fitted to both "
              "photos, the transmission colours\nincluded (docs/fit.md, \"Photo pairs\")"),
    CLI_O_STR("--transmission-scene", NULL, capture_args, transmission_scene, "S",
              "the back-lit scene of --transmission (default: flat45-back for\nflat45; other scenes need it)"),
    CLI_O_END};

const cli_opt CLI_PAIR_MODEL_OPTS[] = {
    CLI_O_STR("--pair-model", NULL, capture_args, pair_model, "M",
              "with --transmission: the pair model that starts the transmission\ncolours (default: "
              "models/fabricnet-<scene>+<back-lit scene>.bin\nif there is one, else the prior)"),
    CLI_O_END};

const cli_opt CLI_MODEL_OPTS[] = {
    CLI_O_STR("--model", NULL, capture_args, model, "M",
              "a model from 'woven train' (default: models/fabricnet-<scene\nname>.bin; the directory can be "
              "changed with WOVEN_MODEL_DIR)"),
    CLI_O_END};

const cli_opt CLI_FIT_OPTS[] = {
    CLI_O_CUSTOM("--iters", capture_args, fit.iters, 0, WV_FIT_MAX_ITERS, parse_iters, "N", "iterations (default 200)"),
    CLI_O_REAL("--lr", capture_args, fit.lr, 1e-6, 1, 0, "X",
               "Adam's step size on the parameters scaled to [0, 1] (default 0.02)"),
    CLI_O_INT("--iter-spp", NULL, capture_args, fit.iter_spp, 1, WV_SCENE_MAX_SPP, "N",
              "samples per pixel while iterating (default 4)"),
    CLI_O_INT("--iter-scale", NULL, capture_args, fit.iter_scale, 1, WV_FIT_MAX_ITER_SCALE, "N",
              "iterate on the image downscaled N times (default 1); the final\nrender and SSIM use the scene's full "
              "resolution and spp"),
    CLI_O_FLAG("--schedule", capture_args, fit.schedule,
               "iterate first on the centre window of half of each side, then on\nthe whole image"),
    CLI_O_CLEAR("--no-schedule", capture_args, fit.schedule, "every iteration on the whole image (the default)"),
    CLI_O_INT("--patience", NULL, capture_args, fit.patience, 0, WV_FIT_MAX_ITERS, "N",
              "end a stage when its smoothed loss has not fallen by 1% in N\niterations; the last stage's end "
              "ends the iterations (default 10;\n0 = run every iteration)"),
    CLI_O_CLEAR("--no-width-sweep", capture_args, fit.width_sweep,
                "with --transmission: leave the yarn width (the open gaps) at its\nstart (by default it is set to the "
                "open area the back-lit photo's gap\nglow measures, or, in a rig without a glow, searched on both "
                "photos\nwhen the iterations end)"),
    CLI_O_CLEAR("--no-forward-sweep", capture_args, fit.forward_sweep,
                "with --transmission: leave the forward band as it starts (by default\nwhether the back-lit photo "
                "shows one, and its width over 0.1, 0.2,\n0.4 and 0.8, is searched before the transmission colours' "
                "start and,\nwhere none is found, after it)"),
    CLI_O_CLEAR("--no-noise-sweep", capture_args, fit.noise_sweep,
                "leave the noise level to the discrete steps (by default every level\nis tried when the iterations end)"),
    CLI_O_CUSTOM("--seed", capture_args, fit.seed, 0, INT_MAX, parse_seed, "N", "the seed of the discrete steps"),
    CLI_O_CUSTOM("--align-radius", capture_args, fit.align_radius, 0, WV_FIT_MAX_ALIGN_RADIUS, parse_align, "N",
                 "after the iterations, search each density +-N yarns/inch for the\nbest SSIM in a centre window "
                 "(default 230: the whole range; 0 = off, the default of a\ncapture whose weave analysis measured the "
                 "densities)"),
    CLI_O_INT("--register-radius", NULL, capture_args, fit.register_radius, 0, WV_FIT_MAX_REGISTER_RADIUS, "N",
              "then register the weave to the photo: densities on a 2-D grid\n+-N yarns/inch refined to 0.1, and "
              "the weave's offset, by phase\ncorrelation; kept if the SSIM rises (default 6; 0 = off)"),
    CLI_O_INT("--distort-degree", NULL, capture_args, fit.distort_degree, 0, 3, "N",
              "then, on a plane, the cloth's distortion: a polynomial of degree N\ndisplacing the fabric so that "
              "the weave stays in register across the\nwhole photo; kept if the SSIM rises (default 3; 0 = off)"),
    CLI_O_REAL("--w-struct", capture_args, fit.w_struct, 0, 100, 0, "X",
               "weight of the structure term, the weave's log power spectrum\n(default 0: off; 0.002 puts it at the "
               "other terms' order)"),
    CLI_O_REAL("--w-colour", capture_args, fit.w_colour, 0, 100, 0, "X",
               "weight of the detail-colour term, how the colour varies between\nyarns (default 0.1; 0 = off)"),
    CLI_O_FLAG("--colour-split", capture_args, fit.colour_split,
               "before the first iteration, try starts that split the warp and weft\ndiffuse colours, the "
               "colour that covers more on the yarn type\nthat covers more (the default)"),
    CLI_O_CLEAR("--no-colour-split", capture_args, fit.colour_split, "no such starts"),
    CLI_O_CUSTOM("--camera-blur", capture_args, fit.psf_sigma, 0, WV_PSF_MAX_SIGMA, parse_blur, "auto|measured|S",
                 "the camera's blur, a Gaussian of sigma S pixels on the radiance in\nevery render; auto (default): "
                 "the scene's, else measured from the\nphoto's spectrum and then fitted with the parameters; "
                 "measured:\nmeasured and kept"),
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
    "                 [--iters N] [--lr X] [--descriptor default|vgg19] [--vgg19-weights FILE]\n"
    "                 [--crop x,y,w,h] [--iter-spp N] [--iter-scale N] [--[no-]schedule]\n"
    "                 [--patience N] [--no-noise-sweep] [--align-radius N]\n"
    "                 [--register-radius N] [--distort-degree N] [--w-struct X] [--w-colour X] [--colour-split]\n"
    "                 [--camera-blur auto|measured|S] [--transmission T.png [--transmission-scene S]]\n"
    "                 [--seed N] [--threads N] [--drape S.json|none]\n"
    "                 [--force] [--quiet] [--json]\n"
    "       woven fit --resume DIR [--iters N] [--quiet] [--json]\n"
    "\n"
    "Refines fabric parameters so that a render of the scene matches the photo (paper 4.3):\n"
    "Gram-matrix loss + 16x8 pixel loss + heightfield prior + the weave's spectrum (structure)\n"
    "+ the colour of its detail, Adam (lr 0.02) on the continuous\n"
    "parameters, random steps of noise level and densities every 5 iterations.\n",
    "Writes to DIR: params.json, render.png, compare.png (photo | start | fit), zoom.png (their\n"
    "centre crop enlarged 4x), spectra.png (their weave spectra), loss.svg, report.html (with\n"
    "SSIM and WSC, the weave-spectrum correlation, of start and fit), viewer.html (woven view),\n"
    "drape.png (the fit on a draped cloth), maps/, with --transmission photo_t.png, render_t.png\n"
    "and scene_t.json (the back-lit photo, the fit in the back-lit scene as that photo sees the\n"
    "cloth, and that scene), and fit.json +\n"
    "checkpoint.json (for --resume). DIR is replaced whole at the end; it may not hold other\n"
    "files, nor any input; --force replaces an earlier fit in DIR (it stays whole until the new\n"
    "one is done).\n",
    {{FIT_ONLY_OPTS, 0}, {CLI_PHOTO_OPTS, 0}, {CLI_PAIR_OPTS, 0}, {CLI_FIT_OPTS, 0}}, 1, {offsetof(capture_args, photo)}};

/* The fit's progress line on a terminal, and the job's messages. */
static void on_iter(void *user, const wv_fit_state *st, const wv_fit_opts *o) {
  cli_fit_ui *u = user;
  const wv_fit_record *r = &st->log[st->iter - 1];
  if (!u->bar.enabled) return;
  double el = cli_now() - u->bar.start, f = (double)st->iter / o->iters;
  fprintf(stderr,
          "\rfit %3d/%d  loss %.5f (Gram %.5f, pixel %.4f, prior %.3f, structure %.3f, colour %.3f)  %.0fs, %.0fs left ",
          st->iter, o->iters, r->loss, r->gram, r->pixel, r->prior, r->structure, r->colour, el,
          f > 0 ? el * (1 - f) / f : 0.0);
  fflush(stderr);
}

static void on_note(void *user, const char *text) {
  cli_fit_ui *u = user;
  cli_progress_end(&u->bar); /* the fit's line ends before the next message */
  cli_info(u->c, "%s\n", text);
}

wv_capture_progress cli_fit_progress(cli_fit_ui *u, cli_ctx *c) {
  u->c = c;
  cli_progress_start(&u->bar, c, "fit");
  return (wv_capture_progress){on_note, on_iter, u};
}

int cli_fit_summary(cli_ctx *c, const char *dir, const wv_pattern_choice *pc, wv_fit_outcome *r) {
  const wv_fit_state *st = &r->state;
  const wv_weave_views *wv = &r->views;
  const wv_fit_record *last = st->iter ? &st->log[st->iter - 1] : NULL;
  cli_info(c, "SSIM %s %.4f -> fit %.4f, WSC %.3f -> %.3f, whitened WSC %.3f -> %.3f; %d iterations in %.1f s; "
              "results in %s/\n", r->start_label, r->ssim_start, r->ssim_fit, wv->wsc[0], wv->wsc[1],
           wv->wsc_whitened[0], wv->wsc_whitened[1], st->iter, st->timing.total, dir);
  if (wv->below_blurred_copy) {
    char grain[96] = "";
    if (wv->periodic_share > -2)
      snprintf(grain, sizeof grain, "; %.0f%% of the photo's detail is weave, the rest grain", 100 * wv->periodic_share);
    cli_info(c, "an unsure fit: SSIM per RGB channel %.4f, below the photo's copy blurred by %.0f px (%.4f)%s; "
                "see report.html\n",
             wv->ssim_rgb[1], WV_BLURRED_COPY_SIGMA, wv->ssim_rgb_blurred, grain);
  }
  if (r->pair && r->below_blurred_copy_t) {
    char grain[96] = "";
    if (r->periodic_share_t > -2)
      snprintf(grain, sizeof grain, "; %.0f%% of its detail is weave, the rest grain", 100 * r->periodic_share_t);
    cli_info(c, "an unsure back-lit re-render: SSIM per RGB channel %.4f, below the transmission photo's copy "
                "blurred by %.0f px (%.4f)%s; see report.html\n",
             r->ssim_rgb_t, WV_BLURRED_COPY_SIGMA, r->ssim_rgb_blurred_t, grain);
  }
  if (c->json) {
    json_t *o_json = json_pack(
        "{s:o,s:i,s:o,s:o,s:o,s:{s:o,s:o,s:o,s:o,s:o,s:o},s:[o,o],s:{s:[o,o],s:[o,o],s:[o,o]}}", "dir",
        cli_str(dir), "iterations", st->iter, "ssim_start", cli_real(r->ssim_start, 6), "ssim_fit",
        cli_real(r->ssim_fit, 6), "loss", cli_real(last ? last->loss : 0.0, 8), "time_s", "total",
        cli_real(st->timing.total, 3), "render", cli_real(st->timing.render, 3), "gradient",
        cli_real(st->timing.gradient, 3), "descriptor", cli_real(st->timing.descriptor, 3), "discrete",
        cli_real(st->timing.discrete, 3), "registration", cli_real(st->timing.registration, 3),
        "density_alignment_ssim", cli_real(st->align_ssim_before, 4), cli_real(st->align_ssim_after, 4),
        "registration", "offset_mm", cli_real(st->offset_mm[0], 6), cli_real(st->offset_mm[1], 6), "ncc",
        cli_real(st->reg_ncc_before, 4), cli_real(st->reg_ncc_after, 4), "window_ssim",
        cli_real(st->reg_ssim_before, 4), cli_real(st->reg_ssim_after, 4));
    if (o_json) {
      json_object_set_new(o_json, "pattern_choice", pc ? cli_json_text(wv_pattern_choice_to_json(pc)) : json_null());
      json_object_set_new(o_json, "density_alignment_wsc",
                          json_pack("[o,o]", cli_real(st->align_wsc_before, 4), cli_real(st->align_wsc_after, 4)));
      json_object_set_new(o_json, "blas_core", json_string(wv_nn_blas_core()));
      json_object_set_new(o_json, "camera_blur_px", cli_real(r->fit_scene.psf_sigma, 3));
      json_object_set_new(o_json, "camera_blur_measured_px", cli_real(st->psf_start, 3));
      json_object_set_new(json_object_get(o_json, "time_s"), "distortion", cli_real(st->timing.distortion, 3));
      json_object_set_new(o_json, "distortion",
                          json_pack("{s:b,s:o,s:[o,o]}", "kept", st->dist_ssim_after > st->dist_ssim_before,
                                    "extent_mm", cli_real(st->distort_extent_mm, 4), "ssim", cli_real(st->dist_ssim_before, 4),
                                    cli_real(st->dist_ssim_after, 4)));
      json_object_set_new(o_json, "ssim_rgb_start", cli_real(wv->ssim_rgb[0], 6));
      json_object_set_new(o_json, "ssim_rgb_fit", cli_real(wv->ssim_rgb[1], 6));
      json_object_set_new(o_json, "ssim_rgb_blurred_photo",
                          wv->ssim_rgb_blurred > -2 ? cli_real(wv->ssim_rgb_blurred, 6) : json_null());
      json_object_set_new(o_json, "below_blurred_copy", json_boolean(wv->below_blurred_copy));
      json_object_set_new(o_json, "photo_periodic_share",
                          wv->periodic_share > -2 ? cli_real(wv->periodic_share, 4) : json_null());
      json_t *fam = NULL;
      wv_pattern_families fs;
      if (pc) wv_pattern_family_scores(pc, &fs);
      if (pc && strcmp(fs.kind, "none") && (fam = json_object()))
        for (int k = 0; k < WV_PATTERN_FAMILIES; k++) { /* best first */
          int f = fs.order[k];
          if (fs.pattern[f] >= 0)
            json_object_set_new(fam, fs.family[f], json_pack("{s:s,s:o}", "pattern", wv_weave_builtin_name(fs.pattern[f]),
                                                             "score", cli_real(fs.score[f], 6)));
        }
      json_object_set_new(o_json, "family_scores", fam ? fam : json_null());
      json_object_set_new(o_json, "family_score_kind", fam ? json_string(fs.kind) : json_null());
      json_object_set_new(o_json, "wsc_start", wv->wsc[0] > -2 ? cli_real(wv->wsc[0], 6) : json_null());
      json_object_set_new(o_json, "wsc_fit", wv->wsc[1] > -2 ? cli_real(wv->wsc[1], 6) : json_null());
      json_object_set_new(o_json, "wsc_whitened_start",
                          wv->wsc_whitened[0] > -2 ? cli_real(wv->wsc_whitened[0], 6) : json_null());
      json_object_set_new(o_json, "wsc_whitened_fit",
                          wv->wsc_whitened[1] > -2 ? cli_real(wv->wsc_whitened[1], 6) : json_null());
      char bounds[WV_P_COUNT + 3][96];
      int nb = wv_params_at_bounds(&st->params, bounds, WV_P_COUNT + 3);
      json_t *ab = json_array();
      for (int i = 0; i < nb && ab; i++) json_array_append_new(ab, cli_str(bounds[i]));
      json_object_set_new(o_json, "at_bounds", ab ? ab : json_null());
      json_object_set_new(o_json, "params", cli_json_text(wv_params_to_json(&st->params)));
      if (r->pair) { /* the transmission photo against the fit's back-lit render */
        json_object_set_new(o_json, "ssim_rgb_fit_t", cli_real(r->ssim_rgb_t, 6));
        json_object_set_new(o_json, "ssim_rgb_blurred_photo_t",
                            r->ssim_rgb_blurred_t > -2 ? cli_real(r->ssim_rgb_blurred_t, 6) : json_null());
        json_object_set_new(o_json, "below_blurred_copy_t", json_boolean(r->below_blurred_copy_t));
        json_object_set_new(o_json, "photo_periodic_share_t",
                            r->periodic_share_t > -2 ? cli_real(r->periodic_share_t, 4) : json_null());
        json_object_set_new(o_json, "wsc_fit_t", r->wsc_t > -2 ? cli_real(r->wsc_t, 6) : json_null());
        json_object_set_new(o_json, "kt_start", json_string(r->kt_model == 1   ? "pair model"
                                                            : r->kt_model == 2 ? "prior (the pair model's start scored worse)"
                                                                               : "prior"));
        json_object_set_new(o_json, "open_area_photo", st->open_measured ? cli_real(st->open_photo, 6) : json_null());
        json_object_set_new(o_json, "open_area_fit",
                            cli_real((1 - st->params.yarn_width) * (1 - st->params.yarn_width), 6));
        /* the back-lit photo's own view of the cloth (null: not measured) */
        json_object_set_new(
            o_json, "view_t",
            !st->t_related
                ? json_null()
                : json_pack("{s:b,s:o,s:o,s:[o,o],s:[o,o],s:{s:o,s:o},s:{s:o,s:o}}", "related", st->t_found, "scale",
                            cli_real(st->t_scale, 4), "rotation_deg", cli_real(st->t_rotation_deg, 3), "density_ratio",
                            cli_real(st->t_density_ratio[0], 4), cli_real(st->t_density_ratio[1], 4), "offset_mm",
                            cli_real(st->t_offset_mm[0], 4), cli_real(st->t_offset_mm[1], 4), "registration_ssim", "before",
                            cli_real(st->t_reg_ssim_before, 4), "after", cli_real(st->t_reg_ssim_after, 4),
                            "distortion_ssim", "before", cli_real(st->t_dist_ssim_before, 4), "after",
                            cli_real(st->t_dist_ssim_after, 4)));
        json_object_set_new(o_json, "mean_t",
                            json_pack("{s:{s:o,s:o},s:{s:o,s:o}}", "photo", "centre", cli_real(r->mean_t[0][0], 6),
                                      "whole", cli_real(r->mean_t[0][1], 6), "render", "centre",
                                      cli_real(r->mean_t[1][0], 6), "whole", cli_real(r->mean_t[1][1], 6)));
      }
    }
    cli_print_json(o_json);
  }
  wv_fit_state_free(&r->state);
  return 0;
}

int cmd_fit(int argc, char **argv) {
  cli_ctx c = {0, 0, "fit"};
  capture_args ca;
  cli_capture_args_init(&ca);
  CLI_PARSE(&CMD, argc, argv, &ca, &c);
  wv_error err = {0};
  wv_fit_record_job rec;
  if (ca.resume) {
    if (ca.init || ca.pattern || ca.scene || ca.out || ca.transmission || ca.transmission_scene)
      return cli_usage_error(c.cmd, "--resume DIR takes its photos, scenes, start and output from DIR");
    if (wv_fit_job_read(ca.resume, &rec, &err)) return cli_fail(&c, &err);
    if (ca.photo && !wv_same_file(ca.photo, rec.photo))
      return cli_usage_error(c.cmd, "%s was fitted to %s, not %s", ca.resume, rec.photo, ca.photo);
  } else {
    if (!ca.photo) return cli_usage_error(c.cmd, "a PHOTO is required");
    if (!ca.scene) return cli_usage_error(c.cmd, "--scene is required");
    if (!ca.out) return cli_usage_error(c.cmd, "-o DIR is required");
    if (!ca.init && !ca.pattern) return cli_usage_error(c.cmd, "give --init P.json or --pattern NAME");
    if (ca.transmission_scene && !ca.transmission)
      return cli_usage_error(c.cmd, "--transmission-scene needs --transmission T.png");
  }
  wv_fit_dir_opts o = {.photo = ca.photo, .scene = ca.scene, .init = ca.init, .pattern = ca.pattern,
                       .dir = ca.resume ? ca.resume : ca.out, .descriptor = ca.descriptor, .weights = ca.weights,
                       .drape = ca.drape, .crop = ca.crop, .resume = ca.resume ? &rec : NULL, .fit = ca.fit,
                       .iters_given = ca.iters_given, .force = ca.force, .photo_t = ca.transmission,
                       .scene_t = ca.transmission_scene};
  cli_fit_ui ui;
  o.progress = cli_fit_progress(&ui, &c);
  wv_fit_outcome out;
  int rc = wv_fit_dir_run(&o, &out, &err) ? cli_fail(&c, &err) : cli_fit_summary(&c, o.dir, NULL, &out);
  cli_progress_end(&ui.bar);
  return rc;
}
