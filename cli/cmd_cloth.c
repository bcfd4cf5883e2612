/* woven cloth: drapes a UV-mapped square with the cloth simulation (woven/cloth.h)
 * and writes it as OBJ. */
#include <limits.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "cli.h"
#include "woven/cloth.h"

typedef struct {
  wv_cloth_opts o;
  const char *out;
  int obstacle, seed;
  double radius;
} cloth_args;

static const cli_opt OPTS[] = {
    CLI_O_STR("--output", "-o", cloth_args, out, "OUT.obj", "the draped mesh"),
    CLI_O_INT("--res", NULL, cloth_args, o.res, 2, 512, "N", "cells per side (default 64: 4,225 vertices, 8,192 triangles)"),
    CLI_O_REAL("--size-mm", cloth_args, o.size_mm, 1, 1e5, 0, "S", "side of the square (default 300)"),
    CLI_O_ENUM("--obstacle", cloth_args, obstacle, "sphere|box|none",
               "sphere (default; radius 80 mm, centre 80 mm up), box (a table whose\nedge the cloth falls over) or "
               "none (the cloth lands on the floor)"),
    CLI_O_REAL("--radius-mm", cloth_args, radius, 1, 1e5, 0, "R", "sphere radius (its centre is R above the floor)"),
    CLI_O_REAL("--seconds", cloth_args, o.seconds, 0, 60, 0, "T", "simulated time (default 3)"),
    CLI_O_INT("--steps-per-second", NULL, cloth_args, o.steps_per_second, 10, 100000, "N", "time steps (default 600)"),
    CLI_O_INT("--seed", NULL, cloth_args, seed, 0, INT_MAX, "N", "the seed of the simulation"),
    CLI_O_END};

static const cli_cmd CMD = {
    "cloth",
    "usage: woven cloth -o OUT.obj [--res N] [--size-mm S] [--obstacle sphere|box|none] [--radius-mm R]\n"
    "                   [--seconds T] [--steps-per-second N] [--seed N] [--quiet] [--json]\n"
    "\n"
    "Drops a square of cloth (UVs 0..1 over it) onto an obstacle resting on the floor y = 0 and\n"
    "writes the draped mesh. Position-based dynamics: stretch, shear and bending constraints,\n"
    "collisions with friction, self-distance. Deterministic: the same options give the same file.\n",
    NULL, {{OPTS, 0}}, 0, {0}};

int cmd_cloth(int argc, char **argv) {
  cli_ctx c = {0, 0, "cloth"};
  cloth_args ca = {.out = NULL, .obstacle = -1, .seed = -1, .radius = -1};
  wv_cloth_defaults(&ca.o);
  CLI_PARSE(&CMD, argc, argv, &ca, &c);
  static const wv_obstacle OBSTACLES[] = {WV_OBSTACLE_SPHERE, WV_OBSTACLE_BOX, WV_OBSTACLE_NONE};
  wv_cloth_opts o = ca.o;
  if (ca.obstacle >= 0) o.obstacle = OBSTACLES[ca.obstacle];
  if (ca.seed >= 0) o.seed = (uint64_t)ca.seed;
  const char *out = ca.out;
  double r = ca.radius;
  if (!out) return cli_usage_error(c.cmd, "-o OUT.obj is required");
  size_t n = strlen(out);
  if (n < 5 || strcasecmp(out + n - 4, ".obj")) return cli_usage_error(c.cmd, "output '%s' must end in .obj", out);
  if (!cli_check_writable(c.cmd, out)) return WV_ERR_IO;
  if (r > 0) o.radius_mm = r, o.centre_mm[1] = r;
  wv_error err = {0};
  wv_mesh m;
  double t0 = cli_now();
  if (wv_cloth_drape(&o, &m, &err)) return cli_fail(&c, &err);
  double secs = cli_now() - t0;
  char comment[256];
  snprintf(comment, sizeof comment,
           "woven cloth: %d x %d cells, %.0f mm square, obstacle %s, %.2f s at %d steps/s, seed %llu", o.res, o.res,
           o.size_mm, o.obstacle == WV_OBSTACLE_SPHERE ? "sphere" : o.obstacle == WV_OBSTACLE_BOX ? "box" : "none",
           o.seconds, o.steps_per_second, (unsigned long long)o.seed);
  wv_status st = wv_mesh_write_obj(out, &m, comment, &err);
  int nv = m.nv, nt = m.nt;
  wv_mesh_free(&m);
  if (st) return cli_fail(&c, &err);
  cli_info(&c, "wrote %s (%d vertices, %d triangles, simulated in %.2f s)\n", out, nv, nt, secs);
  if (c.json)
    cli_print_json(json_pack("{s:o,s:i,s:i,s:o}", "output", cli_str(out), "vertices", nv, "triangles", nt, "seconds",
                             cli_real(secs, 3)));
  return 0;
}
