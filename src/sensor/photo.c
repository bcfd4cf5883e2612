/* Loading a photo for comparison with a capture-scene render (woven/photo.h):
 * read, crop, a linear photo through the scene's sensor response, area-average
 * to the scene's size. */
#include "woven/photo.h"

#include <string.h>

#include "sensor/sensor.h"
#include "woven/imgops.h"
#include "woven/io.h"

wv_status wv_photo_load(const char *path, const wv_scene *s, const wv_crop *crop, wv_image *out,
                        wv_photo_info *info, wv_error *err) {
  wv_image raw;
  wv_image_info ii;
  out->data = NULL;
  wv_status st = wv_image_read(path, &raw, &ii, err);
  if (st) return st;
  int x0, y0, cw, ch, rw = raw.w, rh = raw.h;
  if (crop && (crop->w != 0 || crop->h != 0)) {
    x0 = crop->x, y0 = crop->y, cw = crop->w, ch = crop->h;
    /* in 64 bits: x0 + cw can exceed INT_MAX */
    if (x0 < 0 || y0 < 0 || cw < 1 || ch < 1 || (long long)x0 + cw > rw || (long long)y0 + ch > rh) {
      wv_image_free(&raw);
      return wv_fail(err, WV_ERR_INVALID, "%s: crop %d,%d,%d,%d lies outside the %d x %d photo", path, x0, y0, cw,
                     ch, rw, rh);
    }
  } else { /* largest centred rectangle with the scene's aspect */
    double aspect = (double)s->width / s->height;
    cw = raw.w, ch = (int)(raw.w / aspect + 0.5);
    if (ch > raw.h) ch = raw.h, cw = (int)(raw.h * aspect + 0.5);
    if (cw > raw.w) cw = raw.w;
    x0 = (raw.w - cw) / 2, y0 = (raw.h - ch) / 2;
  }
  if (cw < 0.9 * s->width || ch < 0.9 * s->height) {
    wv_image_free(&raw);
    return wv_fail(err, WV_ERR_INVALID,
                   "%s: the photo (%d x %d after cropping) is much smaller than the scene's image (%d x %d); "
                   "use a larger photo or a scene with a smaller image",
                   path, cw, ch, s->width, s->height);
  }
  wv_image cropped;
  if ((st = wv_image_alloc(&cropped, cw, ch, 3, err))) {
    wv_image_free(&raw);
    return st;
  }
  for (int y = 0; y < ch; y++)
    memcpy(wv_image_px(&cropped, 0, y), wv_image_px(&raw, x0, y0 + y), sizeof(float) * 3 * (size_t)cw);
  wv_image_free(&raw);
  if (ii.is_float) /* linear photo: apply the camera response the scene describes (no mask) */
    for (int y = 0; y < ch; y++) {
      float *row = wv_image_px(&cropped, 0, y);
      wv_respond_n(s, NULL, cw, 3, row, row, NULL);
    }
  if (cw == s->width && ch == s->height) {
    *out = cropped;
  } else {
    st = wv_image_downsample(&cropped, s->width, s->height, out, err);
    wv_image_free(&cropped);
    if (st) {
      wv_error_prefix(err, "%s", path);
      return st;
    }
  }
  if (info) {
    info->width = rw, info->height = rh;
    info->crop[0] = x0, info->crop[1] = y0, info->crop[2] = cw, info->crop[3] = ch;
    info->bit_depth = ii.bit_depth, info->is_float = ii.is_float;
  }
  return WV_OK;
}
