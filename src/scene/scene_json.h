/* woven: the camera response of a scene file (internal): the "response" and "falloff"
 * blocks, read and checked the same way for the capture scenes (src/scene) and the
 * mesh scenes (src/scene3d). */
#ifndef WOVEN_SCENE_JSON_H
#define WOVEN_SCENE_JSON_H

#include <jansson.h>

#include "woven/scene.h"

/* root's "response" and "falloff" (both optional) into s: exposure, clip, encoding,
 * gamma, the camera blur "psf_sigma_px" (a key only when psf is set: the mesh renderer
 * applies no blur) and the falloff. Absent keys leave the defaults: exposure 1, clip 1,
 * sRGB, gamma 2.2, no blur, no falloff. Keys and types only: the ranges are
 * wv_scene_check_response's. */
wv_status wv_scene_read_response(json_t *root, int psf, wv_scene *s, wv_error *err);

/* The ranges of those values (docs/scenes.md), in the order wv_scene_validate checks them. */
wv_status wv_scene_check_response(const wv_scene *s, wv_error *err);

#endif
