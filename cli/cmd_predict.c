/* woven predict and woven capture: FabricNet's estimate of a photo's parameters, and
 * the whole pipeline (estimate, then the fit from it, then every output of the fit); the
 * jobs are the library's (woven/estimate.h, woven/capture.h), this file parses and prints. */
#include <string.h>

#include "cli.h"
#include "woven/estimate.h"

static const cli_cmd PREDICT_CMD = {
    "predict",
    "usage: woven predict PHOTO --scene S.json|cylinder|flat45 -o P.json [--pattern NAME]\n"
    "                     [--model M] [--crop x,y,w,h] [--descriptor default|vgg19] [--vgg19-weights FILE]\n"
    "                     [--force] [--quiet] [--json]\n"
    "\n"
    "FabricNet's estimate of the fabric parameters of PHOTO taken in the scene.\n"
    "Without --pattern the pattern is chosen over the whole library: the weave analysis finds\n"
    "the lattice of the photo's spectral peaks, explains it for each built-in by densities and\n"
    "an orientation, and ranks the built-ins by how well their own render (4 spp, centre\n"
    "256 x 256) shows the photo's peaks, mixed with the network's pattern probabilities; near\n"
    "ties go to the fit's loss (Gram + 0.2 pixel). When the photo shows no weave lattice, the\n"
    "network's most probable pattern is chosen (that loss, for a model without a pattern\n"
    "head). The chosen pattern starts from its lattice densities; --json gives the analysis\n"
    "(docs/analysis.md). The noise level Q is the pattern's prior value. The model must match\n"
    "the descriptor; --force uses a model trained for another scene.\n",
    NULL, {{CLI_PHOTO_OPTS, 0}, {CLI_MODEL_OPTS, 0}}, 1, {offsetof(capture_args, photo)}};

static const cli_cmd CAPTURE_CMD = {
    "capture",
    "usage: woven capture PHOTO --scene S.json|cylinder|flat45 -o DIR [--pattern NAME]\n"
    "                     [--model M] [--iters N] [--lr X] [--crop x,y,w,h] [--iter-spp N] [--iter-scale N]\n"
    "                     [--[no-]schedule] [--patience N]\n"
    "                     [--align-radius N] [--register-radius N] [--distort-degree N] [--seed N] [--threads N] [--descriptor default|vgg19]\n"
    "                     [--drape S.json|none] [--transmission T.png [--transmission-scene S] [--pair-model M]]\n"
    "                     [--vgg19-weights FILE] [--force] [--quiet] [--json]\n"
    "\n"
    "The whole capture: FabricNet's estimate (as 'woven predict'), then the fit from it (as\n"
    "'woven fit', 200 iterations by default; the fit options mean what 'woven fit --help' says).\n"
    "Without --pattern the pattern is chosen as 'woven predict --help' describes; the choice and\n"
    "its losses go to fit.json, report.html and the --json summary (the fit keeps the pattern).\n",
    "Writes to DIR: network.json (the estimate), params.json (the fit), render.png, start.png\n"
    "(the network's estimate rendered), compare.png (photo | network | fit), loss.svg,\n"
    "report.html, viewer.html, drape.png (the fit on the bundled draped cloth, --drape), maps/,\n"
    "fit.json and checkpoint.json ('woven fit --resume DIR' continues); with --transmission also\n"
    "photo_t.png, render_t.png and scene_t.json (the back-lit photo, the fit in the back-lit scene\n"
    "as that photo sees the cloth, and that scene).\n",
    {{CLI_PHOTO_OPTS, 0}, {CLI_MODEL_OPTS, 0}, {CLI_PAIR_OPTS, 0}, {CLI_PAIR_MODEL_OPTS, 0}, {CLI_FIT_OPTS, 0}},
    1,
    {offsetof(capture_args, photo)}};

/* Why the pattern was chosen: the weave analysis and the deciding scores, on stderr. */
static void print_choice(cli_ctx *c, const wv_pattern_choice *pc) {
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
    if (pc->start_refined)
      cli_info(c, "start from the network's %.1f x %.1f yarns/inch, refined from the photo's peaks to %.1f x %.1f, "
                  "the cloth turned %.2f deg and %.2f deg out of square (peak match: the lattice's %.3f, refined "
                  "%.3f)\n",
               pc->unrefined[0], pc->unrefined[1], pc->start_fit.density[0], pc->start_fit.density[1],
               pc->start_fit.angle_deg, pc->start_fit.skew_deg, pc->refine_match[0], pc->refine_match[1]);
  } else {
    cli_info(c, "weave analysis: %s\n", l->reason);
    cli_info(c, "pattern %s chosen (%s; %s family): %s (%.2f s)\n", name, pc->method, wv_weave_family(name),
             !strcmp(pc->method, "network") ? "the network's most probable pattern"
                                            : "the smallest fit loss of the estimate rendered with each built-in",
             pc->seconds);
    const double *d0 = pc->start_refine_tried ? pc->unrefined : pc->params[pc->best].density;
    if (pc->start_compared)
      cli_info(c, "start densities %.1f x %.1f yarns/inch from the %s (peak match: network %.3f, weak %s lattice "
                  "%.3f)\n",
               d0[0], d0[1], pc->lattice_densities ? "weak lattice" : "network", pc->start_match[0], name,
               pc->start_match[1]);
    if (pc->start_refined)
      cli_info(c, "refined from the photo's peaks to %.1f x %.1f yarns/inch, the cloth turned %.2f deg and %.2f deg "
                  "out of square (peak match %.3f -> %.3f)\n",
               pc->start_fit.density[0], pc->start_fit.density[1], pc->start_fit.angle_deg, pc->start_fit.skew_deg,
               pc->refine_match[0], pc->refine_match[1]);
    else if (pc->start_refine_tried)
      cli_info(c, "start densities kept: %s\n",
               pc->start_refine_moved ? "the refined lattice's render matched the photo's peaks worse"
                   : "no refinement near them explains the photo's peaks better");
  }
}

void cli_capture_opts(const capture_args *a, wv_capture_opts *o) {
  memset(o, 0, sizeof *o);
  o->estimate = (wv_estimate_opts){.photo = a->photo,
                                   .scene = a->scene,
                                   .model = a->model,
                                   .pattern = a->pattern,
                                   .descriptor = a->descriptor,
                                   .weights = a->weights,
                                   .crop = a->crop,
                                   .any_scene = a->force};
  o->fit = a->fit, o->iters_given = a->iters_given, o->align_given = a->align_given;
  o->dir = a->out, o->drape = a->drape, o->force = a->force;
  o->photo_t = a->transmission, o->scene_t = a->transmission_scene, o->pair_model = a->pair_model;
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
  wv_capture_opts co;
  cli_capture_opts(&pa, &co);
  wv_estimate res;
  wv_error err = {0};
  if (wv_estimate_run(&co.estimate, &res, &err)) return cli_fail(&c, &err);
  if (res.chosen) print_choice(&c, &res.choice);
  if (wv_params_write(pa.out, &res.params, &err)) rc = cli_fail(&c, &err);
  if (!rc) {
    cli_info(&c, "%s: network estimate written to %s in %.2f s\n", pa.photo, pa.out, res.seconds);
    if (c.json)
      cli_print_json(json_pack("{s:o,s:o,s:s,s:o,s:o}", "output", cli_str(pa.out), "seconds",
                               cli_real(res.seconds, 4), "pattern", res.params.pattern, "pattern_choice",
                               res.chosen ? cli_json_text(wv_pattern_choice_to_json(&res.choice)) : json_null(),
                               "params", cli_json_text(wv_params_to_json(&res.params))));
  }
  wv_estimate_free(&res);
  return rc;
}

static void on_estimate(void *user, const wv_estimate *e) {
  cli_fit_ui *u = user;
  if (e->chosen) print_choice(u->c, &e->choice);
  cli_info(u->c, "network estimate in %.2f s\n", e->seconds);
  cli_progress_start(&u->bar, u->c, "fit"); /* the fit's time left counts from here */
}

int cmd_capture(int argc, char **argv) {
  cli_ctx c = {0, 0, "capture"};
  capture_args pa;
  cli_capture_args_init(&pa);
  CLI_PARSE(&CAPTURE_CMD, argc, argv, &pa, &c);
  int rc = check_required(c.cmd, &pa);
  if (rc) return rc;
  if (pa.pair_model && !pa.transmission) return cli_usage_error(c.cmd, "--pair-model needs --transmission T.png");
  wv_capture_opts co;
  cli_capture_opts(&pa, &co);
  cli_fit_ui ui;
  co.progress = cli_fit_progress(&ui, &c);
  co.on_estimate = on_estimate;
  wv_estimate est;
  wv_fit_outcome out;
  wv_error err = {0};
  if (wv_capture_run(&co, &est, &out, &err)) {
    rc = cli_fail(&c, &err);
  } else {
    rc = cli_fit_summary(&c, pa.out, est.chosen ? &est.choice : NULL, &out);
    wv_estimate_free(&est);
  }
  cli_progress_end(&ui.bar);
  return rc;
}
