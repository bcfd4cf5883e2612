/* woven export: a fabric as a glTF 2.0 binary with baked standard PBR textures. */
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "woven/export.h"

static const char *HELP =
    "usage: woven export DIR|P.json --gltf OUT.glb [--mesh quad|drape] [--size-mm N]\n"
    "                    [--texture N] [--samples N] [--directions N] [--threads N] [--quiet] [--json]\n"
    "\n"
    "Writes a glTF 2.0 binary: a mesh with the fabric baked into standard PBR textures over one\n"
    "weave tile (base colour, normal, metallic-roughness, KHR_materials_anisotropy,\n"
    "KHR_materials_sheen), tiled by KHR_texture_transform at the tile's physical size. Each\n"
    "texel is a least-squares fit of that material to the woven BRDF over light/view direction\n"
    "pairs; the residual is printed and stored in the material's extras (docs/export.md).\n"
    "  DIR            a finished fit's directory (its params.json), or P.json a parameter file\n"
    "  --mesh M       quad (default): a flat square; drape: a sheet draped over a sphere\n"
    "  --size-mm N    the quad's side or the sheet's side (default 100 quad, 600 drape)\n"
    "  --texture N    texels per tile side, 8..1024 (default 64)\n"
    "  --samples N    woven samples per texel side, 1..8 (default 3)\n"
    "  --directions N light/view direction pairs of the fit, 8..256 (default 48)\n"
    "  --threads N    worker threads (default: all cores)\n";

int cmd_export(int argc, char **argv) {
  cli_ctx c = {0, 0, "export"};
  cli_args a;
  cli_args_init(&a, argc, argv, c.cmd);
  const char *in = NULL, *out = NULL, *mesh_name = "quad";
  wv_bake_opts bo;
  wv_bake_opts_default(&bo);
  long v, size_mm = 0;
  for (const char *s; (s = cli_next(&a));) {
    if (!strcmp(s, "--help") || !strcmp(s, "-h")) {
      fputs(HELP, stdout);
      return 0;
    } else if (cli_is(&a, s, "--gltf") || cli_is(&a, s, "-o")) {
      if (!(out = cli_value(&a, "--gltf"))) return EXIT_USAGE;
    } else if (cli_is(&a, s, "--mesh")) {
      if (!(mesh_name = cli_value(&a, "--mesh"))) return EXIT_USAGE;
      if (strcmp(mesh_name, "quad") && strcmp(mesh_name, "drape"))
        return cli_usage_error(c.cmd, "--mesh must be quad or drape, not '%s'", mesh_name);
    } else if (cli_is(&a, s, "--size-mm")) {
      if (!cli_int(&a, "--size-mm", 1, 100000, &size_mm)) return EXIT_USAGE;
    } else if (cli_is(&a, s, "--texture")) {
      if (!cli_int(&a, "--texture", 8, 1024, &v)) return EXIT_USAGE;
      bo.texture_size = (int)v;
    } else if (cli_is(&a, s, "--samples")) {
      if (!cli_int(&a, "--samples", 1, 8, &v)) return EXIT_USAGE;
      bo.samples = (int)v;
    } else if (cli_is(&a, s, "--directions")) {
      if (!cli_int(&a, "--directions", 8, 256, &v)) return EXIT_USAGE;
      bo.directions = (int)v;
    } else if (cli_is(&a, s, "--threads")) {
      if (!cli_int(&a, "--threads", 1, 1024, &v)) return EXIT_USAGE;
      bo.threads = (int)v;
    } else if (cli_common_flag(&c, s)) {
      /* --quiet, -q, --json */
    } else if (s[0] == '-' && s[1]) {
      return cli_usage_error(c.cmd, "unknown option '%s'", s);
    } else if (!in) {
      in = s;
    } else {
      return cli_usage_error(c.cmd, "unexpected argument '%s'", s);
    }
  }
  if (!in) return cli_usage_error(c.cmd, "a fit directory or a parameter file is required");
  if (!out) return cli_usage_error(c.cmd, "--gltf OUT.glb is required");
  int rc = cli_check_output(c.cmd, out, ".glb");
  if (rc) return rc;

  wv_error err = {0};
  wv_source src;
  if (wv_source_load(in, &src, &err)) return cli_fail(&c, &err);
  int drape = !strcmp(mesh_name, "drape");
  wv_tri_mesh mesh;
  wv_status st = drape ? wv_tri_mesh_drape(size_mm ? (double)size_mm : 600.0, 150.0, 96, &mesh, &err)
                       : wv_tri_mesh_quad(size_mm ? (double)size_mm : 100.0, &mesh, &err);
  if (st) return cli_fail(&c, &err);
  cli_info(&c, "baking %s at %d x %d texels, %d direction pairs\n", src.params.pattern, bo.texture_size,
           bo.texture_size, bo.directions);
  double t0 = cli_now();
  wv_bake bake;
  if (!(st = wv_bake_fabric(&src.params, &bo, &bake, &err))) {
    st = wv_gltf_write(out, &mesh, &bake, &src.params, &err);
    if (st) wv_bake_free(&bake);
  }
  int verts = mesh.vertex_count;
  wv_tri_mesh_free(&mesh);
  if (st) return cli_fail(&c, &err);
  double ms = (cli_now() - t0) * 1e3;
  cli_info(&c, "wrote %s (%s, %d vertices, tile %.3f x %.3f mm); fit residual RMS %.5f = %.1f%% of the woven RMS %.5f\n",
           out, mesh_name, verts, bake.tile_mm[0], bake.tile_mm[1], bake.rms, 100 * bake.relative, bake.target_rms);
  if (c.json)
    printf("{\"output\": \"%s\", \"mesh\": \"%s\", \"vertices\": %d, \"texture_size\": %d, \"tile_mm\": [%.6f, %.6f], "
           "\"fit\": {\"rms\": %.6f, \"target_rms\": %.6f, \"relative\": %.6f, \"direction_pairs\": %d}, \"ms\": %.1f}\n",
           out, mesh_name, verts, bo.texture_size, bake.tile_mm[0], bake.tile_mm[1], bake.rms, bake.target_rms,
           bake.relative, bake.directions, ms);
  wv_bake_free(&bake);
  return 0;
}
