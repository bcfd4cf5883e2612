/* Internal to the export module: the one door through which the baker reaches
 * the woven shading. */
#ifndef WOVEN_EXPORT_INTERNAL_H
#define WOVEN_EXPORT_INTERNAL_H

#include "woven/error.h"
#include "woven/params.h"
#include "woven/yarn.h"

typedef struct wv_export_fabric wv_export_fabric;

/* The fabric as the renderer prepares it, with two changes for a texture tile:
 * segment noise repeats with the weave (the tile joins seamlessly) and the
 * glints are at their mean (U_s = 1: a repeating tile cannot carry them). */
wv_status wv_export_fabric_create(const wv_params *p, wv_export_fabric **out, wv_error *err);
void wv_export_fabric_free(wv_export_fabric *f);
/* Its yarn geometry (for the normal and fibre maps). */
const wv_yarn_model *wv_export_fabric_yarns(const wv_export_fabric *f);

/* The woven BRDF times the cosine at fabric point (fx, fy) mm for light direction
 * wi and view direction wo (fabric tangent space, unit, z the macro normal):
 * the reflected radiance per unit of light intensity / distance^2. It calls the
 * renderer's per-sample shading (wv_shade); when the shading becomes one kernel,
 * this adapter is what switches to it. */
void wv_export_woven_eval(const wv_export_fabric *f, float fx, float fy, const float wi[3], const float wo[3],
                          float out[3]);

#endif
