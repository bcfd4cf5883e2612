/* woven: capture woven fabric materials from one photo. A thin front end: every
 * subcommand parses its options and calls the library. */
#include <stdio.h>
#include <string.h>

#include "cli.h"

static const struct {
  const char *name;
  int (*fn)(int, char **);
  const char *help;
} COMMANDS[] = {
    {"render", cmd_render, "render fabric parameters in a capture scene"},
    {"maps", cmd_maps, "write tileable texture maps (normal, tangent, albedo, ...)"},
    {"fit", cmd_fit, "refine fabric parameters from a photo (differentiable rendering)"},
    {"compare", cmd_compare, "SSIM and mean absolute difference of two images"},
    {"dataset", cmd_dataset, "render FabricNet's synthetic training set (resumable)"},
    {"train", cmd_train, "train FabricNet on a dataset"},
    {"predict", cmd_predict, "FabricNet's estimate of the parameters of a photo"},
    {"capture", cmd_capture, "photo -> parameters: network estimate, then the fit, all outputs"},
    {"scene", cmd_scene, "render the fabric on meshes (a draped cloth) under new light, with edits"},
    {"cloth", cmd_cloth, "drape a UV-mapped square with the cloth simulation and write it as OBJ"},
    {"export", cmd_export, "write a glTF 2.0 binary with the fabric baked into PBR textures"},
    {"view", cmd_view, "write a self-contained HTML viewer of the true model (WebGL)"},
};

static void usage(FILE *f) {
  fprintf(f, "usage: woven <command> [options]\n\ncommands:\n");
  for (size_t i = 0; i < sizeof COMMANDS / sizeof COMMANDS[0]; i++)
    fprintf(f, "  %-10s %s\n", COMMANDS[i].name, COMMANDS[i].help);
  fprintf(f, "\n'woven <command> --help' describes a command.\n"
             "Exit codes: 0 ok, 1 usage, 2 invalid value, 3 I/O error, 4 malformed file, 5 too large.\n");
}

int main(int argc, char **argv) {
  if (argc < 2) {
    usage(stderr);
    return EXIT_USAGE;
  }
  if (!strcmp(argv[1], "--help") || !strcmp(argv[1], "-h") || !strcmp(argv[1], "help")) {
    usage(stdout);
    return 0;
  }
  for (size_t i = 0; i < sizeof COMMANDS / sizeof COMMANDS[0]; i++)
    if (!strcmp(argv[1], COMMANDS[i].name)) return COMMANDS[i].fn(argc - 1, argv + 1);
  fprintf(stderr, "woven: unknown command '%s'\n", argv[1]);
  usage(stderr);
  return EXIT_USAGE;
}
