#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

#include "cli.h"
#include "woven/io.h"
#include "woven/maps.h"
#include "woven/render.h"

static const char *RENDER_HELP =
    "usage: woven render --params P.json [--scene S.json|cylinder|flat45] -o OUT.png|OUT.exr\n"
    "                    [--spp N] [--seed N] [--threads N] [--quiet] [--json]\n"
    "\n"
    "Renders the fabric described by P.json in a capture scene (default: the cylinder preset).\n"
    "  OUT.png  the image as the scene's camera records it (exposure, clip, colour encoding,\n"
    "           falloff mask), 8-bit; compare it with a photo taken in that rig\n"
    "  OUT.exr  linear radiance (32-bit float), before the camera response\n"
    "  --spp N     samples per pixel (default: the scene's)\n"
    "  --seed N    overrides the parameter file's noise seed\n"
    "  --threads N worker threads (default: all cores)\n"
    "  --json      print a JSON summary on stdout\n";

static const char *MAPS_HELP =
    "usage: woven maps --params P.json -o DIR [--size N] [--format png|exr|both] [--quiet] [--json]\n"
    "\n"
    "Writes tileable maps of one weave repeat to DIR: normal, tangent, yarn_id, height, diffuse,\n"
    "specular, roughness (.png and/or .exr) and maps.json (tile size in mm, encodings).\n"
    "  --size N     pixels per side (default 1024)\n"
    "  --format F   png (default), exr or both\n";

static int has_ext(const char *path, const char *ext) {
  size_t n = strlen(path), e = strlen(ext);
  return n > e && !strcasecmp(path + n - e, ext);
}

int cmd_render(int argc, char **argv) {
  cli_ctx c = {0, 0, "render"};
  cli_args a;
  cli_args_init(&a, argc, argv, c.cmd);
  const char *params_path = NULL, *scene_name = "cylinder", *out = NULL;
  long spp = 0, seed = -1, threads = 0;
  int have_seed = 0;
  for (const char *s; (s = cli_next(&a));) {
    if (!strcmp(s, "--help") || !strcmp(s, "-h")) {
      fputs(RENDER_HELP, stdout);
      return 0;
    } else if (cli_is(&a, s, "--params")) {
      if (!(params_path = cli_value(&a, "--params"))) return EXIT_USAGE;
    } else if (cli_is(&a, s, "--scene")) {
      if (!(scene_name = cli_value(&a, "--scene"))) return EXIT_USAGE;
    } else if (cli_is(&a, s, "-o") || cli_is(&a, s, "--output")) {
      if (!(out = cli_value(&a, "-o"))) return EXIT_USAGE;
    } else if (cli_is(&a, s, "--spp")) {
      if (!cli_int(&a, "--spp", 1, WV_SCENE_MAX_SPP, &spp)) return EXIT_USAGE;
    } else if (cli_is(&a, s, "--seed")) {
      if (!cli_int(&a, "--seed", 0, 2147483647L, &seed)) return EXIT_USAGE;
      have_seed = 1;
    } else if (cli_is(&a, s, "--threads")) {
      if (!cli_int(&a, "--threads", 1, 1024, &threads)) return EXIT_USAGE;
    } else if (cli_common_flag(&c, s)) {
      /* --quiet, -q, --json */
    } else {
      return cli_usage_error(c.cmd, "unknown argument '%s'", s);
    }
  }
  if (!params_path) return cli_usage_error(c.cmd, "--params is required");
  if (!out) return cli_usage_error(c.cmd, "-o OUT.png or OUT.exr is required");
  int exr = has_ext(out, ".exr");
  if (!exr && !has_ext(out, ".png")) return cli_usage_error(c.cmd, "output '%s' must end in .png or .exr", out);
  if (!cli_check_writable_dir(c.cmd, out)) return WV_ERR_IO;

  wv_error err = {0};
  wv_params p;
  wv_scene s;
  if (wv_params_read(params_path, &p, &err)) return cli_fail(&c, &err);
  if (have_seed) p.seed = seed;
  if (wv_scene_load(scene_name, &s, &err)) return cli_fail(&c, &err);
  cli_progress bar;
  cli_progress_start(&bar, &c, "render");
  wv_render_opts opt = {(int)spp, (int)threads, cli_progress_update, &bar, NULL};
  wv_image cap, rad;
  double t0 = cli_now();
  wv_status st = wv_render(&s, &p, &opt, &cap, &rad, &err);
  cli_progress_end(&bar);
  if (st) return cli_fail(&c, &err);
  double ms = (cli_now() - t0) * 1e3;
  if (exr) /* linear radiance with the scene's exposure, no clip, encoding or mask */
    for (size_t i = 0; i < (size_t)rad.w * rad.h * 3; i++) rad.data[i] *= (float)s.exposure;
  st = wv_image_write(out, exr ? &rad : &cap, &err);
  int used_spp = spp ? (int)spp : s.spp;
  double mean = wv_image_mean(&cap);
  wv_image_free(&cap);
  wv_image_free(&rad);
  if (st) return cli_fail(&c, &err);
  cli_info(&c, "wrote %s (%d x %d, %d spp, %.0f ms)\n", out, s.width, s.height, used_spp, ms);
  if (c.json)
    printf("{\"output\": \"%s\", \"width\": %d, \"height\": %d, \"spp\": %d, \"ms\": %.1f, \"mean\": %.6f}\n", out,
           s.width, s.height, used_spp, ms, mean);
  return 0;
}

int cmd_maps(int argc, char **argv) {
  cli_ctx c = {0, 0, "maps"};
  cli_args a;
  cli_args_init(&a, argc, argv, c.cmd);
  const char *params_path = NULL, *out = NULL, *format = "png";
  long size = 1024;
  for (const char *s; (s = cli_next(&a));) {
    if (!strcmp(s, "--help") || !strcmp(s, "-h")) {
      fputs(MAPS_HELP, stdout);
      return 0;
    } else if (cli_is(&a, s, "--params")) {
      if (!(params_path = cli_value(&a, "--params"))) return EXIT_USAGE;
    } else if (cli_is(&a, s, "-o") || cli_is(&a, s, "--output")) {
      if (!(out = cli_value(&a, "-o"))) return EXIT_USAGE;
    } else if (cli_is(&a, s, "--size")) {
      if (!cli_int(&a, "--size", 1, 8192, &size)) return EXIT_USAGE;
    } else if (cli_is(&a, s, "--format")) {
      if (!(format = cli_value(&a, "--format"))) return EXIT_USAGE;
      if (strcmp(format, "png") && strcmp(format, "exr") && strcmp(format, "both"))
        return cli_usage_error(c.cmd, "--format must be png, exr or both");
    } else if (cli_common_flag(&c, s)) {
      /* --quiet, -q, --json */
    } else {
      return cli_usage_error(c.cmd, "unknown argument '%s'", s);
    }
  }
  if (!params_path) return cli_usage_error(c.cmd, "--params is required");
  if (!out) return cli_usage_error(c.cmd, "-o DIR is required");
  wv_error err = {0};
  wv_params p;
  if (wv_params_read(params_path, &p, &err)) return cli_fail(&c, &err);
  wv_maps m;
  if (wv_maps_generate(&p, (int)size, &m, &err)) return cli_fail(&c, &err);
  wv_status st = wv_maps_write(&m, out, format, &err);
  double tw = m.tile_mm[0], th = m.tile_mm[1];
  wv_maps_free(&m);
  if (st) return cli_fail(&c, &err);
  cli_info(&c, "wrote %ld x %ld maps to %s (tile %.3f x %.3f mm)\n", size, size, out, tw, th);
  if (c.json)
    printf("{\"output\": \"%s\", \"size\": %ld, \"format\": \"%s\", \"tile_mm\": [%.6f, %.6f]}\n", out, size, format,
           tw, th);
  return 0;
}
