/* woven cloth: drapes a UV-mapped square with the cloth simulation (woven/cloth.h)
 * and writes it as OBJ. */
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "cli.h"
#include "woven/cloth.h"

static const char *CLOTH_HELP =
    "usage: woven cloth -o OUT.obj [--res N] [--size-mm S] [--obstacle sphere|box|none] [--radius-mm R]\n"
    "                   [--seconds T] [--steps-per-second N] [--seed N] [--quiet] [--json]\n"
    "\n"
    "Drops a square of cloth (UVs 0..1 over it) onto an obstacle resting on the floor y = 0 and\n"
    "writes the draped mesh. Position-based dynamics: stretch, shear and bending constraints,\n"
    "collisions with friction, self-distance. Deterministic: the same options give the same file.\n"
    "  --res N          cells per side (default 64: 4,225 vertices, 8,192 triangles)\n"
    "  --size-mm S      side of the square (default 300)\n"
    "  --obstacle O     sphere (default; radius 80 mm, centre 80 mm up), box (a table whose edge\n"
    "                   the cloth falls over) or none (the cloth lands on the floor)\n"
    "  --radius-mm R    sphere radius (its centre is R above the floor)\n"
    "  --seconds T      simulated time (default 3)\n"
    "  --steps-per-second N  time steps (default 600)\n";

static int parse_double(cli_args *a, const char *name, double lo, double hi, double *out) {
  const char *v = cli_value(a, name);
  if (!v) return 0;
  char *end;
  double x = strtod(v, &end);
  if (!*v || *end || !(x >= lo && x <= hi)) {
    cli_usage_error(a->cmd, "%s: '%s' is not a number in %g..%g", name, v, lo, hi);
    return 0;
  }
  *out = x;
  return 1;
}

int cmd_cloth(int argc, char **argv) {
  cli_ctx c = {0, 0, "cloth"};
  cli_args a;
  cli_args_init(&a, argc, argv, c.cmd);
  wv_cloth_opts o;
  wv_cloth_defaults(&o);
  const char *out = NULL;
  long v;
  double r = -1;
  for (const char *s; (s = cli_next(&a));) {
    if (!strcmp(s, "--help") || !strcmp(s, "-h")) {
      fputs(CLOTH_HELP, stdout);
      return 0;
    } else if (cli_is(&a, s, "-o") || cli_is(&a, s, "--output")) {
      if (!(out = cli_value(&a, "-o"))) return EXIT_USAGE;
    } else if (cli_is(&a, s, "--res")) {
      if (!cli_int(&a, "--res", 2, 512, &v)) return EXIT_USAGE;
      o.res = (int)v;
    } else if (cli_is(&a, s, "--size-mm")) {
      if (!parse_double(&a, "--size-mm", 1, 1e5, &o.size_mm)) return EXIT_USAGE;
    } else if (cli_is(&a, s, "--radius-mm")) {
      if (!parse_double(&a, "--radius-mm", 1, 1e5, &r)) return EXIT_USAGE;
    } else if (cli_is(&a, s, "--seconds")) {
      if (!parse_double(&a, "--seconds", 0, 60, &o.seconds)) return EXIT_USAGE;
    } else if (cli_is(&a, s, "--steps-per-second")) {
      if (!cli_int(&a, "--steps-per-second", 10, 100000, &v)) return EXIT_USAGE;
      o.steps_per_second = (int)v;
    } else if (cli_is(&a, s, "--seed")) {
      if (!cli_int(&a, "--seed", 0, 2147483647L, &v)) return EXIT_USAGE;
      o.seed = (uint64_t)v;
    } else if (cli_is(&a, s, "--obstacle")) {
      const char *ob = cli_value(&a, "--obstacle");
      if (!ob) return EXIT_USAGE;
      if (!strcmp(ob, "sphere")) o.obstacle = WV_OBSTACLE_SPHERE;
      else if (!strcmp(ob, "box")) o.obstacle = WV_OBSTACLE_BOX;
      else if (!strcmp(ob, "none")) o.obstacle = WV_OBSTACLE_NONE;
      else return cli_usage_error(c.cmd, "--obstacle must be sphere, box or none");
    } else if (cli_common_flag(&c, s)) {
      /* --quiet, -q, --json */
    } else {
      return cli_usage_error(c.cmd, "unknown argument '%s'", s);
    }
  }
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
    printf("{\"output\": \"%s\", \"vertices\": %d, \"triangles\": %d, \"seconds\": %.3f}\n", out, nv, nt, secs);
  return 0;
}
