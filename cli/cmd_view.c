/* woven view: a self-contained HTML viewer of the true woven model. */
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "woven/export.h"
#include "woven/view.h"

typedef struct {
  const char *in, *out, *scene, *photo;
} view_args;

static const cli_opt OPTS[] = {
    CLI_O_STR("--output", "-o", view_args, out, "VIEWER.html", "the viewer"),
    CLI_O_STR("--scene", NULL, view_args, scene, "S", "the capture rig (overrides the fit's scene)"),
    CLI_O_STR("--photo", NULL, view_args, photo, "PHOTO", "a photo taken in that rig, for the before/after toggle"),
    CLI_O_END};

static const cli_cmd CMD = {
    "view",
    "usage: woven view DIR|P.json -o VIEWER.html [--scene S.json|cylinder|flat45] [--photo PHOTO]\n"
    "                  [--quiet] [--json]\n"
    "\n"
    "Writes one HTML file that shades the true woven model in WebGL (three.js is inside it;\n"
    "nothing is fetched when it is opened): the capture rig as its camera sees it, a flat\n"
    "swatch and a draped sheet under studio light, with an orbit camera, a movable light,\n"
    "sliders for the parameters and a before/after toggle against the photo. See docs/viewer.md.\n"
    "  DIR            a finished fit's directory: its parameters, scene.json and photo.png\n"
    "  P.json         a parameter file (the rig: --scene, default flat45)\n",
    "Page options (append to the file's URL): ?mode=rig|swatch|drape&spp=N&frames=N&w=W&h=H\n",
    {{OPTS, 0}}, 1, {offsetof(view_args, in)}};

int cmd_view(int argc, char **argv) {
  cli_ctx c = {0, 0, "view"};
  view_args va = {NULL, NULL, NULL, NULL};
  CLI_PARSE(&CMD, argc, argv, &va, &c);
  const char *in = va.in, *out = va.out, *scene_name = va.scene, *photo = va.photo;
  if (!in) return cli_usage_error(c.cmd, "a fit directory or a parameter file is required");
  if (!out) return cli_usage_error(c.cmd, "-o VIEWER.html is required");
  int rc = cli_check_output(c.cmd, out, ".html");
  if (rc) return rc;
  wv_error err = {0};
  wv_source src;
  if (wv_source_load(in, &src, &err)) return cli_fail(&c, &err);
  wv_scene scene;
  if (scene_name) {
    if (wv_scene_load(scene_name, &scene, &err)) return cli_fail(&c, &err);
  } else if (src.has_scene) {
    scene = src.scene;
  } else if (wv_scene_preset("flat45", &scene, &err)) {
    return cli_fail(&c, &err);
  }
  if (!photo && src.has_photo && !scene_name) photo = src.photo; /* the fit's photo fits the fit's scene */
  char names[4][4096];
  const char *inputs[6];
  int n_in = wv_source_inputs(in, &src, names, inputs);
  inputs[n_in++] = scene_name, inputs[n_in++] = photo;
  if ((rc = cli_check_not_input(&c, out, 0, inputs, n_in))) return rc;
  char title[200];
  snprintf(title, sizeof title, "woven: %s", src.params.pattern);
  wv_view_opts vo = {.params = &src.params, .scene = &scene, .photo = photo, .title = title};
  if (wv_view_write(out, &vo, &err)) return cli_fail(&c, &err);
  cli_info(&c, "wrote %s (%s, scene %s%s)\n", out, src.params.pattern, scene.name, photo ? ", with the photo" : "");
  if (c.json)
    cli_print_json(json_pack("{s:o,s:o,s:o,s:b}", "output", cli_str(out), "pattern", cli_str(src.params.pattern),
                             "scene", cli_str(scene.name), "photo", photo != NULL));
  return 0;
}
