/* woven predict and woven capture: FabricNet's estimate of a photo's parameters, and
 * the whole pipeline (estimate, then the fit from it, then every output of the fit). */
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "cli.h"
#include "woven/descriptor.h"
#include "woven/fabricnet.h"
#include "woven/io.h"
#include "woven/photo.h"

static const cli_cmd PREDICT_CMD = {
    "predict",
    "usage: woven predict PHOTO --scene S.json|cylinder|flat45 -o P.json [--pattern NAME]\n"
    "                     [--model M] [--crop x,y,w,h] [--descriptor default|vgg19] [--vgg19-weights FILE]\n"
    "                     [--force] [--quiet] [--json]\n"
    "\n"
    "FabricNet's estimate of the fabric parameters of PHOTO taken in the scene.\n"
    "Without --pattern the pattern is chosen over the whole library (the network does not\n"
    "predict it): the weave analysis finds the lattice of the photo's spectral peaks, explains\n"
    "it for each built-in by densities and an orientation, and ranks the built-ins by how well\n"
    "their own render (4 spp, centre 256 x 256) shows the photo's peaks; near ties go to the\n"
    "fit's loss (Gram + 0.2 pixel), which also decides alone when the photo shows no weave\n"
    "lattice. The chosen pattern starts from its lattice densities; --json gives the analysis\n"
    "(docs/analysis.md). The noise level Q is the pattern's prior value. The model must match\n"
    "the descriptor; --force uses a model trained for another scene.\n",
    NULL, {{CLI_PHOTO_OPTS, 0}, {CLI_MODEL_OPTS, 0}}, 1, {offsetof(capture_args, photo)}};

static const cli_cmd CAPTURE_CMD = {
    "capture",
    "usage: woven capture PHOTO --scene S.json|cylinder|flat45 -o DIR [--pattern NAME]\n"
    "                     [--model M] [--iters N] [--crop x,y,w,h] [--iter-spp N] [--iter-scale N]\n"
    "                     [--align-radius N] [--register-radius N] [--seed N] [--threads N] [--descriptor default|vgg19]\n"
    "                     [--drape S.json|none]\n"
    "                     [--vgg19-weights FILE] [--force] [--quiet] [--json]\n"
    "\n"
    "The whole capture: FabricNet's estimate (as 'woven predict'), then the fit from it (as\n"
    "'woven fit', 200 iterations by default; the fit options mean what 'woven fit --help' says).\n"
    "Without --pattern the pattern is chosen as 'woven predict --help' describes; the choice and\n"
    "its losses go to fit.json, report.html and the --json summary (the fit keeps the pattern).\n",
    "Writes to DIR: network.json (the estimate), params.json (the fit), render.png, start.png\n"
    "(the network's estimate rendered), compare.png (photo | network | fit), loss.svg,\n"
    "report.html, viewer.html, drape.png (the fit on the bundled draped cloth, --drape), maps/,\n"
    "fit.json and checkpoint.json ('woven fit --resume DIR' continues).\n",
    {{CLI_PHOTO_OPTS, 0}, {CLI_MODEL_OPTS, 0}, {CLI_FIT_OPTS, 0}}, 1, {offsetof(capture_args, photo)}};

#ifndef WOVEN_MODEL_DIR
#define WOVEN_MODEL_DIR "models"
#endif

/* models/fabricnet-<scene>.bin, in $WOVEN_MODEL_DIR or the source tree's models/. */
static void default_model(const wv_scene *s, char *buf, size_t cap) {
  const char *d = getenv("WOVEN_MODEL_DIR");
  snprintf(buf, cap, "%s/fabricnet-%s.bin", d && *d ? d : WOVEN_MODEL_DIR, s->name);
}

/* Why the pattern was chosen: the weave analysis and the deciding scores, on stderr. */
static void cli_print_choice(cli_ctx *c, const wv_pattern_choice *pc) {
  const wv_lattice *l = &pc->lattice;
  const char *name = wv_weave_builtin_name(pc->best);
  if (l->found) {
    const wv_lattice_fit *f = &l->fit[l->best];
    cli_info(c, "weave analysis: %d spectral peaks; best lattice %s: %.1f x %.1f yarns/inch (%.2f x %.2f px), "
                "angle %.1f deg, skew %.1f deg, repeat %d, shear %+d (%.2f s)\n",
             l->n_peaks, wv_weave_builtin_name(l->best), f->density[0], f->density[1], l->spacing_px[0],
             l->spacing_px[1], f->angle_deg, f->skew_deg, l->repeat, l->shear, l->seconds);
    char line[512];
    int len = snprintf(line, sizeof line, "pattern %s chosen (%s; %s family): render match", name, pc->method,
                       wv_weave_family(name));
    for (int k = 0; k < 4 && len > 0 && (size_t)len < sizeof line; k++) {
      int i = pc->ranking.order[k];
      len += snprintf(line + len, sizeof line - (size_t)len, "%s %s %.3f", k ? "," : "", wv_weave_builtin_name(i),
                      pc->ranking.score[i]);
      if (pc->evaluated[i] && len > 0 && (size_t)len < sizeof line)
        len += snprintf(line + len, sizeof line - (size_t)len, " (loss %.5f)", pc->loss[i]);
    }
    cli_info(c, "%s (%.2f s)\n", line, pc->seconds);
  } else {
    cli_info(c, "weave analysis: %s\n", l->reason);
    cli_info(c, "pattern %s chosen (%s; %s family): %s (%.2f s)\n", name, pc->method, wv_weave_family(name),
             !strcmp(pc->method, "network") ? "the network's most probable pattern"
                                            : "the smallest fit loss of the estimate rendered with each built-in",
             pc->seconds);
  }
}

/* What run_predict found: the estimate, and how its pattern was chosen when not given. */
typedef struct {
  wv_params params;
  int chosen; /* the pattern was chosen (pa->pattern was NULL): choice is filled */
  wv_pattern_choice choice;
  double seconds;
} predict_result;

/* Loads what a prediction needs and runs it. On success the caller frees img and desc. */
static int run_predict(cli_ctx *c, const capture_args *pa, wv_scene *scene, wv_image *img, wv_photo_info *info,
                       wv_descriptor **desc, predict_result *res) {
  double t0 = cli_now();
  wv_error err = {0};
  memset(res, 0, sizeof *res);
  if (wv_scene_load(pa->scene, scene, &err)) return cli_fail(c, &err);
  wv_params probe; /* the pattern is checked before the slow steps */
  if (pa->pattern && wv_params_default(pa->pattern, &probe, &err)) return cli_fail(c, &err);
  if (pa->pattern && !strcmp(pa->pattern, "custom"))
    return cli_usage_error(c->cmd, "--pattern must be a built-in pattern");
  char mpath[4096];
  if (pa->model)
    snprintf(mpath, sizeof mpath, "%s", pa->model);
  else
    default_model(scene, mpath, sizeof mpath);
  struct stat sb;
  if (!pa->model && stat(mpath, &sb) != 0) {
    fprintf(stderr, "woven %s: error: no default model for scene '%s' (%s); train one with 'woven dataset' and "
                    "'woven train' (docs/fabricnet.md) and pass --model\n", c->cmd, scene->name, mpath);
    return WV_ERR_IO;
  }
  wv_fabricnet net;
  if (wv_fabricnet_load(mpath, &net, &err)) return cli_fail(c, &err);
  int rc = 0;
  if (wv_descriptor_create(pa->descriptor ? pa->descriptor : "default", pa->weights, desc, &err)) {
    rc = cli_fail(c, &err);
  } else if (wv_fabricnet_check(&net, mpath, wv_descriptor_name(*desc), wv_descriptor_size(*desc),
                                pa->force ? NULL : scene, &err)) {
    rc = cli_fail(c, &err);
  } else if (wv_photo_load(pa->photo, scene, &pa->crop, img, info, &err)) {
    rc = cli_fail(c, &err);
  }
  float y[WV_NET_OUT];
  if (!rc && !pa->pattern) {
    res->chosen = 1;
    if (wv_fabricnet_predict_pattern(&net, *desc, scene, img, NULL, y, &res->choice, &err))
      rc = cli_fail(c, &err);
    else
      res->params = res->choice.params[res->choice.best];
  } else if (!rc) {
    float *feat = malloc(sizeof(float) * (size_t)net.n_in);
    if (!feat) rc = cli_usage_error(c->cmd, "out of memory");
    else if (wv_fabricnet_predict(&net, *desc, img, feat, y, NULL, &err) ||
             wv_fabricnet_params(&net, y, pa->pattern, &res->params, &err))
      rc = cli_fail(c, &err);
    free(feat);
  }
  wv_fabricnet_free(&net);
  if (rc) {
    wv_image_free(img);
    wv_descriptor_free(*desc);
    *desc = NULL;
  }
  res->seconds = cli_now() - t0;
  if (!rc && res->chosen) cli_print_choice(c, &res->choice);
  return rc;
}

static int check_required(const char *cmd, const capture_args *pa) {
  if (!pa->photo) return cli_usage_error(cmd, "a PHOTO is required");
  if (!pa->scene) return cli_usage_error(cmd, "--scene is required");
  if (!pa->out) return cli_usage_error(cmd, "-o is required");
  return 0;
}

int cmd_predict(int argc, char **argv) {
  cli_ctx c = {0, 0, "predict"};
  capture_args pa;
  cli_capture_args_init(&pa);
  CLI_PARSE(&PREDICT_CMD, argc, argv, &pa, &c);
  int rc = check_required(c.cmd, &pa);
  if (rc) return rc;
  const char *inputs[] = {pa.photo, pa.scene, pa.model, pa.weights};
  if ((rc = cli_check_not_input(&c, pa.out, 0, inputs, 4))) return rc;
  cli_clean_temps_beside(pa.out);
  wv_scene scene;
  wv_image img = {0};
  wv_photo_info info;
  wv_descriptor *desc = NULL;
  predict_result res;
  if ((rc = run_predict(&c, &pa, &scene, &img, &info, &desc, &res))) return rc;
  wv_error err = {0};
  if (wv_params_write(pa.out, &res.params, &err)) rc = cli_fail(&c, &err);
  if (!rc) {
    cli_info(&c, "%s: network estimate written to %s in %.2f s\n", pa.photo, pa.out, res.seconds);
    if (c.json)
      cli_print_json(json_pack("{s:o,s:o,s:s,s:o,s:o}", "output", cli_str(pa.out), "seconds",
                               cli_real(res.seconds, 4), "pattern", res.params.pattern, "pattern_choice",
                               res.chosen ? cli_json_text(wv_pattern_choice_to_json(&res.choice)) : json_null(),
                               "params", cli_json_text(wv_params_to_json(&res.params))));
  }
  wv_image_free(&img);
  wv_descriptor_free(desc);
  return rc;
}

int cmd_capture(int argc, char **argv) {
  cli_ctx c = {0, 0, "capture"};
  capture_args pa;
  cli_capture_args_init(&pa);
  CLI_PARSE(&CAPTURE_CMD, argc, argv, &pa, &c);
  return cli_capture_run(&c, &pa, NULL);
}

int cli_capture_run(cli_ctx *cp, const capture_args *pap, fit_result *result) {
  cli_ctx c = *cp;
  const capture_args pa = *pap;
  fit_job job;
  memset(&job, 0, sizeof job);
  job.opts = pa.fit, job.drape = pa.drape;
  int iters_given = pa.iters_given;
  int rc = check_required(c.cmd, &pa);
  if (rc) return rc;
  /* Everything is checked before anything is written; the directory first (cheap). */
  job.dir = pa.out, job.resume = 0, job.force = pa.force;
  const char *inputs[] = {pa.photo, pa.scene, pa.model, pa.weights};
  memcpy(job.inputs, inputs, sizeof inputs);
  if ((rc = fit_check_dir(&c, &job))) return rc;
  wv_scene scene;
  wv_image img = {0};
  wv_photo_info info;
  wv_descriptor *desc = NULL;
  predict_result res;
  wv_error err = {0};
  wv_scene probe; /* the fit's size limits, before the network runs */
  if (wv_scene_load(pa.scene, &probe, &err)) return cli_fail(&c, &err);
  if (wv_fit_check_sizes(&probe, NULL, &job.opts, &err)) return cli_fail(&c, &err);
  if ((rc = run_predict(&c, &pa, &scene, &img, &info, &desc, &res))) return rc;
  cli_info(&c, "network estimate in %.2f s\n", res.seconds);
  char *network = wv_params_to_json(&res.params), *nl = network ? realloc(network, strlen(network) + 2) : NULL;
  if (nl) strcat(nl, "\n"), network = nl; /* as wv_params_write writes it */
  if (wv_fit_check_sizes(&scene, desc, &job.opts, &err)) {
    rc = cli_fail(&c, &err);
  } else if (!network) {
    rc = cli_fail(&c, &(wv_error){WV_ERR_NOMEM, "out of memory"});
  } else {
    job.crop = (wv_crop){info.crop[0], info.crop[1], info.crop[2], info.crop[3]};
    job.weights = pa.weights;
    job.extra_name = "network.json", job.extra_text = network;
    job.scene = &scene, job.photo = &img, job.desc = desc, job.start = &res.params;
    job.pattern_choice = res.chosen ? &res.choice : NULL;
    job.photo_path = pa.photo, job.iters_given = iters_given;
    job.start_label = "network";
    job.title = "woven capture";
    job.result = result;
    rc = fit_pipeline(&c, &job);
  }
  free(network);
  wv_descriptor_free(desc);
  wv_image_free(&img);
  return rc;
}
