/* The centre window of a scene and the matching pixels of a full-size image
 * (include/woven/metrics.h): what a search renders and compares when the whole image
 * would cost too much (the fit's alignment and registration, the weave analysis). */
#include "woven/metrics.h"

#include <math.h>
#include <string.h>

void wv_scene_centre_window(const wv_scene *s, int w, int h, wv_scene *out) {
  *out = *s;
  double t = tan(0.5 * s->vfov_deg * 3.14159265358979323846 / 180.0) * h / s->height;
  out->vfov_deg = 2.0 * atan(t) * 180.0 / 3.14159265358979323846;
  out->width = w, out->height = h;
}

wv_status wv_image_centre_crop(const wv_image *full, int w, int h, wv_image *out, wv_error *err) {
  wv_status rc = wv_image_alloc(out, w, h, 3, err);
  if (rc) return rc;
  int x0 = (full->w - w) / 2, y0 = (full->h - h) / 2;
  for (int y = 0; y < h; y++)
    memcpy(wv_image_px(out, 0, y), wv_image_px(full, x0, y0 + y), sizeof(float) * 3 * (size_t)w);
  return WV_OK;
}

