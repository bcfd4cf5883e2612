/* woven scene: renders a mesh scene file (woven/scene3d.h) to PNG or EXR. */
#include <limits.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

#include "cli.h"
#include "woven/io.h"
#include "woven/mesh.h"
#include "woven/scene3d.h"

typedef struct {
  const char *scene, *out, *params;
  int spp, threads, seed, limit_mb, size[2], opaque;
} scene_args;

/* WIDTHxHEIGHT */
static int parse_size(const char *cmd, const cli_opt *o, const char *v, void *base) {
  int *wh = (int *)((char *)base + o->off), w, h;
  char x = 0, end = 0;
  if (sscanf(v, "%d%c%d%c", &w, &x, &h, &end) != 3 || (x != 'x' && x != 'X') || w < 1 || h < 1 ||
      w > WV_SCENE_MAX_SIDE || h > WV_SCENE_MAX_SIDE)
    return cli_usage_error(cmd, "--size: '%s' is not WIDTHxHEIGHT with sides in 1..%d", v, WV_SCENE_MAX_SIDE);
  wh[0] = w, wh[1] = h;
  return 0;
}

static const cli_opt OPTS[] = {
    CLI_O_STR("--output", "-o", scene_args, out, "OUT",
              "OUT.png: the image after the scene's camera response (exposure,\nclip, encoding), 8-bit; OUT.exr: "
              "linear radiance times the exposure\n(32-bit float)"),
    CLI_O_STR("--params", NULL, scene_args, params, "P.json", "replaces the parameters of every fabric material in the scene"),
    CLI_O_INT("--spp", NULL, scene_args, spp, 1, WV_SCENE_MAX_SPP, "N", "camera rays per pixel (default: the scene's image.spp)"),
    CLI_O_INT("--threads", NULL, scene_args, threads, 1, 1024, "N", "worker threads (default: all cores)"),
    CLI_O_CUSTOM("--size", scene_args, size, 0, 0, parse_size, "WxH",
                 "image size instead of the scene's (same camera and field of view:\na preview)"),
    CLI_O_INT("--seed", NULL, scene_args, seed, 0, INT_MAX, "N", "overrides the scene's render.seed"),
    CLI_O_FLAG("--no-transmission", scene_args, opaque,
               "the cloth reflects only (no light through it): as the scene's\nrender.transmission false"),
    CLI_O_INT("--mesh-limit-mb", NULL, scene_args, limit_mb, 1, 1 << 20, "N",
              "memory limit of the job: meshes, ray tracer, edit maps,\nenvironment (default 2048; the scene's limits.mesh_mb may\nlower it, never raise it)"),
    CLI_O_END};

static const cli_cmd CMD = {
    "scene",
    "usage: woven scene SCENE.json -o OUT.png|OUT.exr [--params P.json] [--spp N] [--threads N]\n"
    "                   [--size WxH] [--seed N] [--no-transmission] [--mesh-limit-mb N] [--quiet] [--json]\n"
    "\n"
    "Renders a scene of meshes (the fabric on a draped cloth, under an environment and lights)\n"
    "with a path tracer; the scene format is in docs/scene.md.\n",
    NULL, {{OPTS, 0}}, 1, {offsetof(scene_args, scene)}};

static int ends_with(const char *s, const char *ext) {
  size_t n = strlen(s), e = strlen(ext);
  return n > e && !strcasecmp(s + n - e, ext);
}

int cmd_scene(int argc, char **argv) {
  cli_ctx c = {0, 0, "scene"};
  scene_args sa = {NULL, NULL, NULL, 0, 0, -1, 0, {0, 0}, 0};
  CLI_PARSE(&CMD, argc, argv, &sa, &c);
  const char *scene_path = sa.scene, *out = sa.out, *params_path = sa.params;
  long spp = sa.spp, threads = sa.threads, seed = sa.seed, limit_mb = sa.limit_mb;
  int width = sa.size[0], height = sa.size[1];
  if (!scene_path) return cli_usage_error(c.cmd, "a scene file is required");
  if (!out) return cli_usage_error(c.cmd, "-o OUT.png or OUT.exr is required");
  int exr = ends_with(out, ".exr");
  if (!exr && !ends_with(out, ".png")) return cli_usage_error(c.cmd, "output '%s' must end in .png or .exr", out);
  if (!cli_check_writable(c.cmd, out)) return WV_ERR_IO;

  wv_error err = {0};
  wv_scene3d sc;
  wv_params p;
  if (params_path && wv_params_read(params_path, &p, &err)) {
    wv_error_excerpt(&err, WV_EXCERPT_CHARS);
    return cli_fail(&c, &err);
  }
  if (wv_scene3d_read(scene_path, &sc, &err)) return cli_fail(&c, &err);
  if (seed >= 0) sc.seed = (uint64_t)seed;
  if (sa.opaque) sc.opaque = 1;
  /* the scene's own limit may lower the command line's, never raise it */
  size_t limit_cap = (size_t)(limit_mb ? limit_mb : WV_MESH_DEFAULT_LIMIT_MB) << 20;
  if (!sc.mesh_limit_bytes || sc.mesh_limit_bytes > limit_cap) sc.mesh_limit_bytes = limit_cap;
  const char *inputs[4 * WV_SCENE3D_MAX_ITEMS + 2] = {scene_path, params_path};
  int n_in = 2 + wv_scene3d_inputs(&sc, inputs + 2, 4 * WV_SCENE3D_MAX_ITEMS);
  if (cli_check_not_input(&c, out, 0, inputs, n_in)) {
    wv_scene3d_free(&sc);
    return WV_ERR_INVALID;
  }
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
  wv_scene3d_opts opt = {
      .spp = (int)spp, .threads = (int)threads, .progress = cli_progress_update, .progress_user = &bar};
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
    cli_print_json(json_pack("{s:o,s:i,s:i,s:i,s:I,s:o,s:o,s:o,s:o,s:o,s:o}", "output", cli_str(out), "width", W,
                             "height", H, "spp", stats.spp, "triangles", (json_int_t)tris, "load_s", cli_real(t_load, 3),
                             "render_s", cli_real(t_render, 3), "rays", cli_count(stats.rays), "rays_per_s",
                             cli_count(stats.rays / t_render), "fabric_points_shaded", cli_count(stats.shade_calls),
                             "mean", cli_real(mean, 6)));
  return 0;
}
