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

static const char *PREDICT_HELP =
    "usage: woven predict PHOTO --scene S.json|cylinder|flat45 -o P.json [--pattern NAME]\n"
    "                     [--model M] [--crop x,y,w,h] [--descriptor default|vgg19] [--vgg19-weights FILE]\n"
    "                     [--force] [--quiet] [--json]\n"
    "\n"
    "FabricNet's estimate of the fabric parameters of PHOTO taken in the scene.\n"
    "  --pattern NAME  plain, twill, satin, twill90 or satin90. Without it the pattern is chosen\n"
    "                  (the network does not predict it): the estimate is rendered with each of\n"
    "                  the five at 4 spp and the smallest fit loss (Gram + 0.2 pixel) against the\n"
    "                  photo wins (about 0.5 s more at 800 x 300 on 2 idle cores); --json gives\n"
    "                  the losses. Twill and satin are often confused (docs/fabricnet.md)\n"
    "                  The noise level Q is the pattern's prior value\n"
    "  --model M       a model from 'woven train' (default: models/fabricnet-<scene name>.bin;\n"
    "                  the directory can be changed with WOVEN_MODEL_DIR)\n"
    "  --descriptor    the texture descriptor (default: default); the model must match it\n"
    "  --force         use a model trained for another scene\n";

static const char *CAPTURE_HELP =
    "usage: woven capture PHOTO --scene S.json|cylinder|flat45 -o DIR [--pattern NAME]\n"
    "                     [--model M] [--iters N] [--crop x,y,w,h] [--iter-spp N] [--iter-scale N]\n"
    "                     [--align-radius N] [--register-radius N] [--seed N] [--threads N] [--descriptor default|vgg19]\n"
    "                     [--vgg19-weights FILE] [--force] [--quiet] [--json]\n"
    "\n"
    "The whole capture: FabricNet's estimate (as 'woven predict'), then the fit from it (as\n"
    "'woven fit', 200 iterations by default; the fit options mean what 'woven fit --help' says).\n"
    "Without --pattern the pattern is chosen as 'woven predict --help' describes; the choice and\n"
    "its losses go to fit.json, report.html and the --json summary (the fit keeps the pattern).\n"
    "Writes to DIR: network.json (the estimate), params.json (the fit), render.png, start.png\n"
    "(the network's estimate rendered), compare.png (photo | network | fit), loss.svg,\n"
    "report.html, maps/, fit.json and checkpoint.json ('woven fit --resume DIR' continues).\n";

#ifndef WOVEN_MODEL_DIR
#define WOVEN_MODEL_DIR "models"
#endif

/* models/fabricnet-<scene>.bin, in $WOVEN_MODEL_DIR or the source tree's models/. */
static void default_model(const wv_scene *s, char *buf, size_t cap) {
  const char *d = getenv("WOVEN_MODEL_DIR");
  snprintf(buf, cap, "%s/fabricnet-%s.bin", d && *d ? d : WOVEN_MODEL_DIR, s->name);
}

typedef struct {
  const char *photo, *scene_name, *pattern, *model, *descriptor, *weights, *out;
  wv_crop crop;
  int force;
} predict_args;

/* What run_predict found: the estimate, and how its pattern was chosen when not given. */
typedef struct {
  wv_params params;
  int chosen; /* the pattern was chosen (pa->pattern was NULL): choice is filled */
  wv_pattern_choice choice;
  double seconds;
} predict_result;

/* Loads what a prediction needs and runs it. On success the caller frees img and desc. */
static int run_predict(cli_ctx *c, const predict_args *pa, wv_scene *scene, wv_image *img, wv_photo_info *info,
                       wv_descriptor **desc, predict_result *res) {
  double t0 = cli_now();
  wv_error err = {0};
  memset(res, 0, sizeof *res);
  if (wv_scene_load(pa->scene_name, scene, &err)) return cli_fail(c, &err);
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
  if (!rc && res->chosen) {
    /* why: the five losses, smallest first marked */
    const wv_pattern_choice *pc = &res->choice;
    char line[512];
    int len = snprintf(line, sizeof line, "pattern %s chosen: smallest fit loss (Gram + %g pixel) of the estimate "
                                          "rendered with each pattern (%d spp, %.2f s):", wv_net_pattern(pc->best),
                       pc->w_pixel, pc->spp, pc->seconds);
    for (int i = 0; i < WV_NET_PATTERNS && len > 0 && (size_t)len < sizeof line; i++)
      len += snprintf(line + len, sizeof line - (size_t)len, "%s %s %.6f", i ? "," : "", wv_net_pattern(i),
                      pc->loss[i]);
    cli_info(c, "%s\n", line);
  }
  return rc;
}

static int parse_common(cli_args *a, const char *s, predict_args *pa, int *handled) {
  *handled = 1;
  if (cli_is(a, s, "--scene")) {
    if (!(pa->scene_name = cli_value(a, "--scene"))) return EXIT_USAGE;
  } else if (cli_is(a, s, "--pattern")) {
    if (!(pa->pattern = cli_value(a, "--pattern"))) return EXIT_USAGE;
  } else if (cli_is(a, s, "--model")) {
    if (!(pa->model = cli_value(a, "--model"))) return EXIT_USAGE;
  } else if (cli_is(a, s, "--descriptor")) {
    if (!(pa->descriptor = cli_value(a, "--descriptor"))) return EXIT_USAGE;
  } else if (cli_is(a, s, "--vgg19-weights")) {
    if (!(pa->weights = cli_value(a, "--vgg19-weights"))) return EXIT_USAGE;
  } else if (cli_is(a, s, "-o") || cli_is(a, s, "--output")) {
    if (!(pa->out = cli_value(a, "-o"))) return EXIT_USAGE;
  } else if (cli_is(a, s, "--crop")) {
    const char *cv = cli_value(a, "--crop");
    if (!cv) return EXIT_USAGE;
    if (!cli_parse_crop(cv, &pa->crop)) return cli_usage_error(a->cmd, "--crop must be x,y,w,h (non-negative integers)");
  } else if (!strcmp(s, "--force")) {
    pa->force = 1;
  } else {
    *handled = 0;
  }
  return 0;
}

static int check_required(const char *cmd, const predict_args *pa) {
  if (!pa->photo) return cli_usage_error(cmd, "a PHOTO is required");
  if (!pa->scene_name) return cli_usage_error(cmd, "--scene is required");
  if (!pa->out) return cli_usage_error(cmd, "-o is required");
  return 0;
}

int cmd_predict(int argc, char **argv) {
  cli_ctx c = {0, 0, "predict"};
  cli_args a;
  cli_args_init(&a, argc, argv, c.cmd);
  predict_args pa;
  memset(&pa, 0, sizeof pa);
  for (const char *s; (s = cli_next(&a));) {
    int handled, rc;
    if (!strcmp(s, "--help") || !strcmp(s, "-h")) {
      fputs(PREDICT_HELP, stdout);
      return 0;
    }
    if ((rc = parse_common(&a, s, &pa, &handled))) return rc;
    if (handled) continue;
    if (cli_common_flag(&c, s)) {
      /* --quiet, -q, --json */
    } else if (s[0] == '-' && s[1]) {
      return cli_usage_error(c.cmd, "unknown option '%s'", s);
    } else if (!pa.photo) {
      pa.photo = s;
    } else {
      return cli_usage_error(c.cmd, "unexpected argument '%s'", s);
    }
  }
  int rc = check_required(c.cmd, &pa);
  if (rc) return rc;
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
    if (c.json) {
      char *pj = wv_params_to_json(&res.params);
      char *pc = res.chosen ? wv_pattern_choice_to_json(&res.choice) : NULL;
      printf("{\"output\": \"%s\", \"seconds\": %.4f, \"pattern\": \"%s\", \"pattern_choice\": %s, \"params\": %s}\n",
             pa.out, res.seconds, res.params.pattern, pc ? pc : "null", pj ? pj : "null");
      free(pj), free(pc);
    }
  }
  wv_image_free(&img);
  wv_descriptor_free(desc);
  return rc;
}

int cmd_capture(int argc, char **argv) {
  cli_ctx c = {0, 0, "capture"};
  cli_args a;
  cli_args_init(&a, argc, argv, c.cmd);
  predict_args pa;
  memset(&pa, 0, sizeof pa);
  fit_job job;
  memset(&job, 0, sizeof job);
  wv_fit_opts_default(&job.opts);
  int iters_given = 0;
  for (const char *s; (s = cli_next(&a));) {
    int handled, rc;
    if (!strcmp(s, "--help") || !strcmp(s, "-h")) {
      fputs(CAPTURE_HELP, stdout);
      return 0;
    }
    if ((rc = parse_common(&a, s, &pa, &handled))) return rc;
    if (handled) continue;
    if (cli_parse_fit_opt(&a, s, &job.opts, &iters_given, &handled)) return EXIT_USAGE;
    if (handled) continue;
    if (cli_common_flag(&c, s)) {
      /* --quiet, -q, --json */
    } else if (s[0] == '-' && s[1]) {
      return cli_usage_error(c.cmd, "unknown option '%s'", s);
    } else if (!pa.photo) {
      pa.photo = s;
    } else {
      return cli_usage_error(c.cmd, "unexpected argument '%s'", s);
    }
  }
  int rc = check_required(c.cmd, &pa);
  if (rc) return rc;
  wv_scene scene;
  wv_image img = {0};
  wv_photo_info info;
  wv_descriptor *desc = NULL;
  predict_result res;
  if ((rc = run_predict(&c, &pa, &scene, &img, &info, &desc, &res))) return rc;
  cli_info(&c, "network estimate in %.2f s\n", res.seconds);
  /* Everything is checked before anything is written. */
  rc = fit_prepare_dir(c.cmd, pa.out, pa.force, 0);
  wv_error err = {0};
  char path[4096];
  snprintf(path, sizeof path, "%s/network.json", pa.out);
  if (!rc && wv_params_write(path, &res.params, &err)) rc = cli_fail(&c, &err);
  wv_crop used = {info.crop[0], info.crop[1], info.crop[2], info.crop[3]};
  if (!rc && fit_write_job(pa.out, pa.photo, &used, &scene, wv_descriptor_name(desc), pa.weights,
                          res.chosen ? &res.choice : NULL, &err))
    rc = cli_fail(&c, &err);
  if (!rc) {
    job.scene = &scene, job.photo = &img, job.desc = desc, job.start = &res.params;
    job.pattern_choice = res.chosen ? &res.choice : NULL;
    job.dir = pa.out, job.photo_path = pa.photo, job.resume = 0, job.iters_given = iters_given;
    job.start_label = "network";
    job.title = "woven capture";
    rc = fit_pipeline(&c, &job);
  }
  wv_descriptor_free(desc);
  wv_image_free(&img);
  return rc;
}
