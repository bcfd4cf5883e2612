/* woven export: a fabric as a glTF 2.0 binary with baked standard PBR textures. */
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "woven/export.h"

typedef struct {
  const char *in, *out;
  int mesh, size_mm;
  wv_bake_opts bo;
} export_args;

static const cli_opt OPTS[] = {
    CLI_O_STR("--gltf", "-o", export_args, out, "OUT.glb", "the glTF binary"),
    CLI_O_ENUM("--mesh", export_args, mesh, "quad|drape",
               "quad (default): a flat square; drape: a sheet draped over a sphere"),
    CLI_O_INT("--size-mm", NULL, export_args, size_mm, 1, 100000, "N",
              "the quad's side or the sheet's side (default 100 quad, 600 drape)"),
    CLI_O_INT("--texture", NULL, export_args, bo.texture_size, 8, 1024, "N", "texels per tile side, 8..1024 (default 64)"),
    CLI_O_INT("--samples", NULL, export_args, bo.samples, 1, 8, "N", "woven samples per texel side, 1..8 (default 3)"),
    CLI_O_INT("--directions", NULL, export_args, bo.directions, 8, 256, "N",
              "light/view direction pairs of the fit, 8..256 (default 48)"),
    CLI_O_INT("--threads", NULL, export_args, bo.threads, 1, 1024, "N", "worker threads (default: all cores)"),
    CLI_O_END};

static const cli_cmd CMD = {
    "export",
    "usage: woven export DIR|P.json --gltf OUT.glb [--mesh quad|drape] [--size-mm N]\n"
    "                    [--texture N] [--samples N] [--directions N] [--threads N] [--quiet] [--json]\n"
    "\n"
    "Writes a glTF 2.0 binary: a mesh with the fabric baked into standard PBR textures over one\n"
    "weave tile (base colour, normal, metallic-roughness, KHR_materials_anisotropy,\n"
    "KHR_materials_sheen), tiled by KHR_texture_transform at the tile's physical size. Each\n"
    "texel is a least-squares fit of that material to the woven BRDF over light/view direction\n"
    "pairs; the residual is printed and stored in the material's extras (docs/export.md). The\n"
    "light through the cloth: KHR_materials_diffuse_transmission (woven's diffuse transmission\n"
    "per texel) and, where yarns leave open gaps, KHR_materials_transmission (their area).\n"
    "  DIR            a finished fit's directory (its params.json), or P.json a parameter file\n",
    NULL, {{OPTS, 0}}, 1, {offsetof(export_args, in)}};

int cmd_export(int argc, char **argv) {
  cli_ctx c = {0, 0, "export"};
  export_args ea = {NULL, NULL, 0, 0, {0}};
  wv_bake_opts_default(&ea.bo);
  CLI_PARSE(&CMD, argc, argv, &ea, &c);
  const char *in = ea.in, *out = ea.out, *mesh_name = ea.mesh ? "drape" : "quad";
  wv_bake_opts bo = ea.bo;
  long size_mm = ea.size_mm;
  if (!in) return cli_usage_error(c.cmd, "a fit directory or a parameter file is required");
  if (!out) return cli_usage_error(c.cmd, "--gltf OUT.glb is required");
  int rc = cli_check_output(c.cmd, out, ".glb");
  if (rc) return rc;

  wv_error err = {0};
  wv_source src;
  if (wv_source_load(in, &src, &err)) return cli_fail(&c, &err);
  char names[4][4096];
  const char *inputs[4];
  int n_in = wv_source_inputs(in, &src, names, inputs);
  if ((rc = cli_check_not_input(&c, out, 0, inputs, n_in))) return rc;
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
    cli_print_json(json_pack(
        "{s:o,s:s,s:i,s:i,s:[o,o],s:{s:o,s:o,s:o,s:i},s:o}", "output", cli_str(out), "mesh", mesh_name, "vertices", verts,
        "texture_size", bo.texture_size, "tile_mm", cli_real(bake.tile_mm[0], 6), cli_real(bake.tile_mm[1], 6), "fit",
        "rms", cli_real(bake.rms, 6), "target_rms", cli_real(bake.target_rms, 6), "relative", cli_real(bake.relative, 6),
        "direction_pairs", bake.directions, "ms", cli_real(ms, 1)));
  wv_bake_free(&bake);
  return 0;
}
