/* woven dataset: FabricNet's synthetic training set (SPEC section 7), resumable; the
 * job is the library's (wv_dataset_build), this file parses and prints. */
#include <limits.h>

#include "cli.h"
#include "woven/dataset.h"
#include "woven/dist.h"

typedef struct {
  const char *scene, *tscene, *dir, *descriptor, *weights;
  int per, seed, spp, no_augment, photo_draws, jobs;
} dataset_args;

static const cli_opt OPTS[] = {
    CLI_O_STR("--scene", NULL, dataset_args, scene, "S", "a scene file, cylinder or flat45"),
    CLI_O_STR("--transmission-scene", NULL, dataset_args, tscene, "S",
              "a back-lit scene (a file or flat45-back): a photo-pair set,\neach sample also rendered lit from behind"),
    CLI_O_INT("--per-pattern", NULL, dataset_args, per, 1, WV_DATASET_MAX_PER_PATTERN, "N", "samples per pattern"),
    CLI_O_STR("--output", "-o", dataset_args, dir, "DIR", "the dataset's directory"),
    CLI_O_INT("--seed", NULL, dataset_args, seed, 0, INT_MAX, "N",
              "dataset seed (default 1); sample parameters are a function of\n(seed, pattern, i)"),
    CLI_O_INT("--spp", NULL, dataset_args, spp, 1, WV_SCENE_MAX_SPP, "N", "samples per pixel (default: the scene's)"),
    CLI_O_FLAG("--no-augment", dataset_args, no_augment, "store the renders as they are (8-bit), without the camera"),
    CLI_O_FLAG("--photo-draws", dataset_args, photo_draws,
               "cloths as the flat45 rig's photos show them: yarns 1 to 2.5 pixels\napart at the image centre, any noise level, and the camera's blur\nup to 1.5 pixels (docs/fabricnet.md)"),
    CLI_O_INT("--jobs", NULL, dataset_args, jobs, 1, 1024, "N", "samples rendered at once, one thread each (default: all cores)"),
    CLI_O_STR("--descriptor", NULL, dataset_args, descriptor, "default|vgg19", "the texture descriptor (default: default)"),
    CLI_O_STR("--vgg19-weights", NULL, dataset_args, weights, "FILE", "the VGG-19 weights (--descriptor vgg19)"),
    CLI_O_END};

static const cli_cmd CMD = {
    "dataset",
    "usage: woven dataset --scene S.json|cylinder|flat45 --per-pattern N -o DIR [--seed N] [--spp N]\n"
    "                     [--transmission-scene S.json|flat45-back] [--no-augment] [--photo-draws] [--jobs N] [--descriptor default|vgg19] [--vgg19-weights FILE]\n"
    "                     [--quiet] [--json]\n"
    "\n"
    "Renders N samples for each built-in weave pattern (plain, basket, the twills, the satins and\n"
    "their 90-degree variants), parameters drawn from the SPEC section 5 priors, passes each\n"
    "through a camera (glints, defocus, exposure and white balance, sensor noise, JPEG), and\n"
    "caches their descriptor features. With --transmission-scene each sample is also rendered\n"
    "lit from behind, for a model that reads a photo pair.\n",
    "Writes DIR/dataset.json and DIR/samples/<pattern>_<i>.{json,png,feat} (docs/fabricnet.md),\n"
    "and <pattern>_<i>.t.png for a pair set.\n"
    "Run the same command again to resume after an interruption: finished samples are kept,\n"
    "a larger --per-pattern extends the set; a DIR made with other settings is refused.\n"
    "Under 'mpirun -n N' the processes share the samples (docs/mpi.md); the directory is the same\n"
    "as one process makes. One job at a time per DIR (DIR/woven.lock).\n",
    {{OPTS, 0}}, 0, {0}};

typedef struct {
  const cli_ctx *c;
  cli_progress bar;
  int last_report;
} dataset_ui;

static void on_note(void *user, const char *text) {
  dataset_ui *u = user;
  cli_info(u->c, "%s\n", text);
}

static int on_progress(void *user, int done, int todo, double el) {
  dataset_ui *u = user;
  double f = (double)done / todo;
  cli_progress_update(&u->bar, f);
  /* without a terminal (logs, nohup): a line every 5% */
  if (!u->bar.enabled && !u->c->quiet && !u->c->json && (int)(f * 20) > u->last_report) {
    u->last_report = (int)(f * 20);
    fprintf(stderr, "dataset %d/%d  %.2f samples/s  %.0fs, %.0fs left\n", done, todo, done / el, el, el * (1 - f) / f);
  }
  return 0;
}

int cmd_dataset(int argc, char **argv) {
  cli_ctx c = {0, 0, "dataset"};
  dataset_args da = {NULL, NULL, NULL, "default", NULL, 0, 1, 0, 0, 0, 0};
  CLI_PARSE(&CMD, argc, argv, &da, &c);
  if (!da.scene) return cli_usage_error(c.cmd, "--scene is required");
  if (!da.dir) return cli_usage_error(c.cmd, "-o DIR is required");
  if (!da.per) return cli_usage_error(c.cmd, "--per-pattern N is required");
  wv_error err = {0};
  wv_dist dist;
  if (wv_dist_begin(&dist, &err)) return cli_fail(&c, &err);
  if (dist.rank > 0) c.quiet = 1, c.json = 0;
  dataset_ui ui = {&c, {0}, 0};
  wv_dataset_build_opts o;
  wv_dataset_build_opts_default(&o);
  o.scene = da.scene, o.transmission_scene = da.tscene, o.dir = da.dir, o.per_pattern = da.per, o.seed = (uint64_t)da.seed, o.spp = da.spp;
  o.augment = !da.no_augment, o.draws = da.photo_draws ? WV_DRAWS_PHOTO : WV_DRAWS_PRIOR, o.jobs = da.jobs, o.descriptor = da.descriptor, o.weights = da.weights;
  o.on_note = on_note, o.on_progress = on_progress, o.user = &ui;
  cli_progress_start(&ui.bar, &c, "dataset");
  wv_dataset_build_result r;
  wv_status st = wv_dataset_build(&dist, &o, &r, &err);
  cli_progress_end(&ui.bar);
  int rc = 0;
  if (st) {
    rc = err.msg[0] ? cli_fail(&c, &err) : (int)st;
  } else {
    double el = r.seconds;
    cli_info(&c, "%d samples rendered in %.1f s (%.3f samples/s); %s has %d of %d\n", r.rendered, el,
             el > 0 ? r.rendered / el : 0.0, da.dir, r.done_before + r.rendered, r.samples);
    if (c.json)
      cli_print_json(json_pack("{s:o,s:i,s:i,s:i,s:o,s:o,s:i,s:i,s:i,s:I,s:i}", "dir", cli_str(da.dir), "samples",
                               r.samples, "done_before", r.done_before, "rendered", r.rendered, "seconds",
                               cli_real(el, 3), "samples_per_s", cli_real(el > 0 ? r.rendered / el : 0.0, 4), "spp",
                               r.spp, "width", r.width, "height", r.height, "jobs", (json_int_t)r.jobs, "processes",
                               dist.size));
  }
  wv_dist_end(&dist);
  return rc;
}
