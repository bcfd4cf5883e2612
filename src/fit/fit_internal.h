/* Shared between the fit's source files; not public. */
#ifndef WOVEN_FIT_INTERNAL_H
#define WOVEN_FIT_INTERNAL_H

#include "woven/image.h"
#include "woven/scene.h"

/* The centre w x h window of a scene (same pixels as the full image there). */
void wv_fit_centre_window(const wv_scene *s, int w, int h, wv_scene *out);
/* Copies the matching centre w x h pixels of a full-size image. */
wv_status wv_fit_centre_crop(const wv_image *full, int w, int h, wv_image *out, wv_error *err);

/* wv_image_detail (metrics.h), with the Hann window (hann = 1) or without it (0). */
wv_status wv_image_detail_window(const wv_image *img, int x0, int y0, int w, int h, int hann, float *out,
                                 wv_error *err);

#endif
