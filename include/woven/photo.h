/* woven: loading a photo for comparison with a capture-scene render. */
#ifndef WOVEN_PHOTO_H
#define WOVEN_PHOTO_H

#include "woven/error.h"
#include "woven/image.h"
#include "woven/scene.h"

typedef struct {
  int x, y, w, h; /* pixel rectangle of the photo; w = h = 0: centre crop to the scene's aspect */
} wv_crop;

typedef struct {
  int width, height;     /* of the file */
  int crop[4];           /* the rectangle used */
  int bit_depth, is_float;
} wv_photo_info;

/* Reads a JPEG, PNG (8/16-bit, grey or colour) or EXR photo and brings it to the
 * scene's image: crop (given, or the centred largest rectangle of the scene's
 * aspect), then area-average to the scene's width x height. Integer images are
 * taken as stored in the scene's encoding; float (EXR) images as linear, so they
 * get the scene's exposure, clip and encoding (not the falloff: a photo has its
 * own). A crop smaller than 90% of the scene's size is refused: upsampling
 * would invent detail the fit would then try to match. */
wv_status wv_photo_load(const char *path, const wv_scene *s, const wv_crop *crop, wv_image *out,
                        wv_photo_info *info, wv_error *err);

#endif
