/* woven render and woven maps: parameters to an image in a capture scene, and to
 * tileable texture maps. */
#include <libgen.h>
#include <limits.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

#include "cli.h"
#include "woven/io.h"
#include "woven/maps.h"
#include "woven/render.h"

typedef struct {
  const char *params, *scene, *out;
  int spp, seed, threads;
} render_args;

static const cli_opt RENDER_OPTS[] = {
    CLI_O_STR("--params", NULL, render_args, params, "P.json", "the fabric parameters"),
    CLI_O_STR("--scene", NULL, render_args, scene, "S", "a scene file, cylinder (default), flat45 or flat45-back"),
    CLI_O_STR("--output", "-o", render_args, out, "OUT",
     "OUT.png: the image as the scene's camera records it (exposure, clip,\ncolour encoding, falloff mask), 8-bit; "
     "compare it with a photo taken\nin that rig. OUT.exr: linear radiance (32-bit float), before the\ncamera response"),
    CLI_O_INT("--spp", NULL, render_args, spp, 1, WV_SCENE_MAX_SPP, "N", "samples per pixel (default: the scene's)"),
    CLI_O_INT("--seed", NULL, render_args, seed, 0, INT_MAX, "N", "overrides the parameter file's noise seed"),
    CLI_O_INT("--threads", NULL, render_args, threads, 1, 1024, "N", "worker threads (default: all cores)"),
    CLI_O_END};

static const cli_cmd RENDER_CMD = {
    "render",
    "usage: woven render --params P.json [--scene S.json|cylinder|flat45] -o OUT.png|OUT.exr\n"
    "                    [--spp N] [--seed N] [--threads N] [--quiet] [--json]\n"
    "\n"
    "Renders the fabric described by P.json in a capture scene (default: the cylinder preset).\n",
    NULL, {{RENDER_OPTS, 0}}, 0, {0}};

typedef struct {
  const char *params, *out;
  int size, format;
} maps_args;

static const char *const MAPS_FORMATS[] = {"png", "exr", "both"};
static const cli_opt MAPS_OPTS[] = {
    CLI_O_STR("--params", NULL, maps_args, params, "P.json", "the fabric parameters"),
    CLI_O_STR("--output", "-o", maps_args, out, "DIR", "the maps' directory"),
    CLI_O_INT("--size", NULL, maps_args, size, 1, 8192, "N", "pixels per side (default 1024)"),
    CLI_O_ENUM("--format", maps_args, format, "png|exr|both", "png (default), exr or both"),
    CLI_O_END};

static const cli_cmd MAPS_CMD = {
    "maps",
    "usage: woven maps --params P.json -o DIR [--size N] [--format png|exr|both] [--quiet] [--json]\n"
    "\n"
    "Writes tileable maps of one weave repeat to DIR: normal, tangent, yarn_id, height, diffuse,\n"
    "specular, roughness (.png and/or .exr) and maps.json (tile size in mm, encodings).\n",
    NULL, {{MAPS_OPTS, 0}}, 0, {0}};

static int has_ext(const char *path, const char *ext) {
  size_t n = strlen(path), e = strlen(ext);
  return n > e && !strcasecmp(path + n - e, ext);
}

int cmd_render(int argc, char **argv) {
  cli_ctx c = {0, 0, "render"};
  render_args ra = {NULL, "cylinder", NULL, 0, -1, 0};
  CLI_PARSE(&RENDER_CMD, argc, argv, &ra, &c);
  const char *params_path = ra.params, *scene_name = ra.scene, *out = ra.out;
  if (!params_path) return cli_usage_error(c.cmd, "--params is required");
  if (!out) return cli_usage_error(c.cmd, "-o OUT.png or OUT.exr is required");
  int exr = has_ext(out, ".exr");
  if (!exr && !has_ext(out, ".png")) return cli_usage_error(c.cmd, "output '%s' must end in .png or .exr", out);
  if (!cli_check_writable(c.cmd, out)) return WV_ERR_IO;
  const char *inputs[2] = {params_path, scene_name};
  int rc = cli_check_not_input(&c, out, 0, inputs, 2);
  if (rc) return rc;
  cli_clean_temps_beside(out);

  wv_error err = {0};
  wv_params p;
  wv_scene s;
  if (wv_params_read(params_path, &p, &err)) return cli_fail(&c, &err);
  if (ra.seed >= 0) p.seed = ra.seed;
  if (wv_scene_load(scene_name, &s, &err)) return cli_fail(&c, &err);
  cli_progress bar;
  cli_progress_start(&bar, &c, "render");
  wv_render_opts opt = {.spp = ra.spp, .threads = ra.threads, .progress = cli_progress_update, .progress_user = &bar};
  wv_image cap, rad;
  double t0 = cli_now();
  wv_status st = wv_render(&s, &p, &opt, &cap, &rad, &err);
  cli_progress_end(&bar);
  if (st) return cli_fail(&c, &err);
  double ms = (cli_now() - t0) * 1e3;
  if (exr) /* linear radiance with the scene's exposure, no clip, encoding or mask */
    for (size_t i = 0; i < (size_t)rad.w * rad.h * 3; i++) rad.data[i] *= (float)s.exposure;
  st = wv_image_write(out, exr ? &rad : &cap, &err);
  int used_spp = ra.spp ? ra.spp : s.spp;
  double mean = wv_image_mean(&cap);
  wv_image_free(&cap);
  wv_image_free(&rad);
  if (st) return cli_fail(&c, &err);
  cli_info(&c, "wrote %s (%d x %d, %d spp, %.0f ms)\n", out, s.width, s.height, used_spp, ms);
  if (c.json)
    cli_print_json(json_pack("{s:o,s:i,s:i,s:i,s:o,s:o}", "output", cli_str(out), "width", s.width, "height", s.height, "spp",
                             used_spp, "ms", cli_real(ms, 1), "mean", cli_real(mean, 6)));
  return 0;
}

int cmd_maps(int argc, char **argv) {
  cli_ctx c = {0, 0, "maps"};
  maps_args ma = {NULL, NULL, 1024, 0};
  CLI_PARSE(&MAPS_CMD, argc, argv, &ma, &c);
  const char *params_path = ma.params, *out = ma.out, *format = MAPS_FORMATS[ma.format];
  int size = ma.size;
  if (!params_path) return cli_usage_error(c.cmd, "--params is required");
  if (!out) return cli_usage_error(c.cmd, "-o DIR is required");
  int rc = cli_check_not_input(&c, out, 1, &params_path, 1);
  if (rc) return rc;
  wv_error err = {0};
  wv_params p;
  if (wv_params_read(params_path, &p, &err)) return cli_fail(&c, &err);
  wv_maps m;
  if (wv_maps_generate(&p, size, &m, &err)) return cli_fail(&c, &err);
  wv_status st = wv_maps_write(&m, out, format, &err);
  double tw = m.tile_mm[0], th = m.tile_mm[1];
  wv_maps_free(&m);
  if (st) return cli_fail(&c, &err);
  cli_info(&c, "wrote %d x %d maps to %s (tile %.3f x %.3f mm)\n", size, size, out, tw, th);
  if (c.json)
    cli_print_json(json_pack("{s:o,s:I,s:s,s:[o,o]}", "output", cli_str(out), "size", (json_int_t)size, "format", format,
                             "tile_mm", cli_real(tw, 6), cli_real(th, 6)));
  return 0;
}
