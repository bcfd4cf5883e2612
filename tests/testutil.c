/* Shared helpers of the cmocka tests (testutil.h): preset windows and scratch directories. */
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

const char *tu_tmpdir(const char *name) {
  static char path[512];
  snprintf(path, sizeof path, "tmp_%s", name);
  char cmd[600];
  int n = snprintf(cmd, sizeof cmd, "rm -rf '%s' && mkdir -p '%s'", path, path);
  if (n < 0 || (size_t)n >= sizeof cmd) return NULL;
  if (system(cmd) != 0) return NULL;
  return path;
}

void tu_centre_window(wv_scene *s, const char *preset, int w, int h, int spp) {
  wv_scene_preset(preset, s, NULL);
  const double deg = 3.14159265358979323846 / 180.0;
  s->vfov_deg = 2.0 * atan(tan(0.5 * s->vfov_deg * deg) * h / s->height) / deg;
  s->width = w, s->height = h;
  s->spp = spp;
}
