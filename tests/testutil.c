#include "testutil.h"

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
