/* woven scene: renders a mesh scene file (woven/scene3d.h) to PNG or EXR. */
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

#include "cli.h"
#include "woven/io.h"
#include "woven/scene3d.h"

static const char *SCENE_HELP =
    "usage: woven scene SCENE.json -o OUT.png|OUT.exr [--params P.json] [--spp N] [--threads N]\n"
    "                   [--size WxH] [--seed N] [--mesh-limit-mb N] [--quiet] [--json]\n"
    "\n"
    "Renders a scene of meshes (the fabric on a draped cloth, under an environment and lights)\n"
    "with a path tracer; the scene format is in docs/scene.md.\n"
    "  OUT.png  the image after the scene's camera response (exposure, clip, encoding), 8-bit\n"
    "  OUT.exr  linear radiance times the exposure (32-bit float)\n"
    "  --params P.json    replaces the parameters of every fabric material in the scene\n"
    "  --spp N            camera rays per pixel (default: the scene's image.spp)\n"
    "  --threads N        worker threads (default: all cores)\n"
    "  --size WxH         image size instead of the scene's (same camera and field of view: a preview)\n"
    "  --seed N           overrides the scene's render.seed\n"
    "  --mesh-limit-mb N  memory limit for the meshes and the ray tracer (default: the scene's, else 2048)\n"
    "  --json             print a JSON summary on stdout\n";

static int ends_with(const char *s, const char *ext) {
  size_t n = strlen(s), e = strlen(ext);
  return n > e && !strcasecmp(s + n - e, ext);
}

int cmd_scene(int argc, char **argv) {
  cli_ctx c = {0, 0, "scene"};
  cli_args a;
  cli_args_init(&a, argc, argv, c.cmd);
  const char *scene_path = NULL, *out = NULL, *params_path = NULL;
  long spp = 0, threads = 0, seed = -1, limit_mb = 0;
  int width = 0, height = 0;
  for (const char *s; (s = cli_next(&a));) {
    if (!strcmp(s, "--help") || !strcmp(s, "-h")) {
      fputs(SCENE_HELP, stdout);
      return 0;
    } else if (cli_is(&a, s, "-o") || cli_is(&a, s, "--output")) {
      if (!(out = cli_value(&a, "-o"))) return EXIT_USAGE;
    } else if (cli_is(&a, s, "--params")) {
      if (!(params_path = cli_value(&a, "--params"))) return EXIT_USAGE;
    } else if (cli_is(&a, s, "--spp")) {
      if (!cli_int(&a, "--spp", 1, WV_SCENE_MAX_SPP, &spp)) return EXIT_USAGE;
    } else if (cli_is(&a, s, "--threads")) {
      if (!cli_int(&a, "--threads", 1, 1024, &threads)) return EXIT_USAGE;
    } else if (cli_is(&a, s, "--size")) {
      const char *v = cli_value(&a, "--size");
      char x = 0, end = 0;
      if (!v) return EXIT_USAGE;
      if (sscanf(v, "%d%c%d%c", &width, &x, &height, &end) != 3 || (x != 'x' && x != 'X') || width < 1 ||
          height < 1 || width > WV_SCENE_MAX_SIDE || height > WV_SCENE_MAX_SIDE)
        return cli_usage_error(c.cmd, "--size: '%s' is not WIDTHxHEIGHT with sides in 1..%d", v, WV_SCENE_MAX_SIDE);
    } else if (cli_is(&a, s, "--seed")) {
      if (!cli_int(&a, "--seed", 0, 2147483647L, &seed)) return EXIT_USAGE;
    } else if (cli_is(&a, s, "--mesh-limit-mb")) {
      if (!cli_int(&a, "--mesh-limit-mb", 1, 1L << 20, &limit_mb)) return EXIT_USAGE;
    } else if (cli_common_flag(&c, s)) {
      /* --quiet, -q, --json */
    } else if (s[0] == '-' && s[1]) {
      return cli_usage_error(c.cmd, "unknown option '%s'", s);
    } else if (!scene_path) {
      scene_path = s;
    } else {
      return cli_usage_error(c.cmd, "unexpected argument '%s'", s);
    }
  }
  if (!scene_path) return cli_usage_error(c.cmd, "a scene file is required");
  if (!out) return cli_usage_error(c.cmd, "-o OUT.png or OUT.exr is required");
  int exr = ends_with(out, ".exr");
  if (!exr && !ends_with(out, ".png")) return cli_usage_error(c.cmd, "output '%s' must end in .png or .exr", out);
  if (!cli_check_writable(c.cmd, out)) return WV_ERR_IO;

  wv_error err = {0};
  wv_scene3d sc;
  wv_params p;
  if (params_path && wv_params_read(params_path, &p, &err)) return cli_fail(&c, &err);
  if (wv_scene3d_read(scene_path, &sc, &err)) return cli_fail(&c, &err);
  if (seed >= 0) sc.seed = (uint64_t)seed;
  if (limit_mb) sc.mesh_limit_bytes = (size_t)limit_mb << 20;
  if (width) sc.width = sc.response.width = width, sc.height = sc.response.height = height;
  double t0 = cli_now();
  wv_world *w = NULL;
  if (wv_world_load(&sc, params_path ? &p : NULL, (int)threads, &w, &err)) {
    wv_scene3d_free(&sc);
    return cli_fail(&c, &err);
  }
  double t_load = cli_now() - t0;
  cli_progress bar;
  cli_progress_start(&bar, &c, "scene");
  wv_scene3d_opts opt = {(int)spp, (int)threads, cli_progress_update, &bar};
  wv_image cap, rad;
  wv_scene3d_stats stats = {0};
  double t1 = cli_now();
  wv_status st = wv_scene3d_render(&sc, w, &opt, &cap, &rad, &stats, &err);
  double t_render = cli_now() - t1;
  cli_progress_end(&bar);
  long long tris, verts;
  wv_world_size(w, &tris, &verts);
  wv_world_free(w);
  if (st) {
    wv_scene3d_free(&sc);
    return cli_fail(&c, &err);
  }
  if (exr)
    for (size_t i = 0; i < (size_t)rad.w * rad.h * 3; i++) rad.data[i] *= (float)sc.response.exposure;
  st = wv_image_write(out, exr ? &rad : &cap, &err);
  double mean = wv_image_mean(&cap);
  wv_image_free(&cap), wv_image_free(&rad);
  int W = sc.width, H = sc.height;
  wv_scene3d_free(&sc);
  if (st) return cli_fail(&c, &err);
  cli_info(&c, "wrote %s (%d x %d, %d spp, %lld triangles, load %.2f s, render %.2f s, %.2f Mrays/s)\n", out, W, H,
           stats.spp, tris, t_load, t_render, stats.rays / t_render * 1e-6);
  if (c.json)
    printf("{\"output\": \"%s\", \"width\": %d, \"height\": %d, \"spp\": %d, \"triangles\": %lld, \"load_s\": %.3f, "
           "\"render_s\": %.3f, \"rays\": %.0f, \"rays_per_s\": %.0f, \"fabric_points_shaded\": %.0f, \"mean\": %.6f}\n",
           out, W, H, stats.spp, tris, t_load, t_render, stats.rays, stats.rays / t_render, stats.shade_calls, mean);
  return 0;
}
