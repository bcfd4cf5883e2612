/* Where an export or a viewer starts: a parameter file or a finished fit's directory. */
#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

#include "io/io_internal.h"
#include "woven/export.h"

wv_status wv_source_load(const char *path, wv_source *src, wv_error *err) {
  memset(src, 0, sizeof *src);
  struct stat sb;
  char eb[128];
  if (stat(path, &sb) != 0)
    return wv_fail(err, WV_ERR_IO, "%s: cannot open: %s", path, wv_io_strerror(errno, eb, sizeof eb));
  if (!S_ISDIR(sb.st_mode)) return wv_params_read(path, &src->params, err);
  char p[4096];
  if ((size_t)snprintf(p, sizeof p, "%s/params.json", path) >= sizeof p)
    return wv_fail(err, WV_ERR_INVALID, "%s: path too long", path);
  if (stat(p, &sb) != 0)
    return wv_fail(err, WV_ERR_INVALID, "%s holds no finished fit (no params.json): run woven fit or capture first",
                   path);
  wv_status st = wv_params_read(p, &src->params, err);
  if (st) return st;
  src->is_fit = 1;
  snprintf(p, sizeof p, "%s/scene.json", path);
  if (stat(p, &sb) == 0) {
    if ((st = wv_scene_read(p, &src->scene, err))) return st;
    src->has_scene = 1;
  }
  snprintf(src->photo, sizeof src->photo, "%s/photo.png", path);
  src->has_photo = stat(src->photo, &sb) == 0 && S_ISREG(sb.st_mode);
  if (!src->has_photo) src->photo[0] = '\0';
  return WV_OK;
}

int wv_source_inputs(const char *path, const wv_source *src, char names[4][4096], const char **paths) {
  static const char *const own[] = {"params.json", "scene.json", "photo.png"};
  int n = 0;
  snprintf(names[n], sizeof names[n], "%s", path);
  paths[n] = names[n], n++;
  for (int i = 0; src->is_fit && i < 3; i++) {
    snprintf(names[n], sizeof names[n], "%s/%s", path, own[i]);
    paths[n] = names[n], n++;
  }
  return n;
}
