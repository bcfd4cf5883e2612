/* woven: FabricNet's estimate of a photo's parameters (woven predict, and the front half
 * of woven capture): the scene, the model and the descriptor loaded, the photo through
 * the network, and the pattern chosen over the built-in library (woven/pattern.h) unless
 * given; the estimate keeps what a fit from it needs. */
#ifndef WOVEN_ESTIMATE_H
#define WOVEN_ESTIMATE_H

#include "woven/descriptor.h"
#include "woven/error.h"
#include "woven/image.h"
#include "woven/params.h"
#include "woven/pattern.h"
#include "woven/photo.h"
#include "woven/scene.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
  const char *photo, *scene, *model; /* model NULL: models/fabricnet-<scene name>.bin ($WOVEN_MODEL_DIR) */
  const char *pattern;               /* a built-in; NULL: chosen over the library (wv_fabricnet_predict_pattern) */
  const char *descriptor, *weights;  /* NULL descriptor: "default" */
  wv_crop crop;
  int any_scene; /* use a model trained for another scene */
} wv_estimate_opts;
typedef struct {
  wv_params params;
  int chosen; /* the pattern was chosen: choice is filled */
  wv_pattern_choice choice;
  double seconds;
  /* What the fit from the estimate needs (wv_estimate_free releases them). */
  wv_scene scene; /* with the chosen pattern's lattice orientation (wv_pattern_choice_scene) */
  wv_image photo;
  wv_photo_info info;
  wv_descriptor *desc;
} wv_estimate;
wv_status wv_estimate_run(const wv_estimate_opts *o, wv_estimate *e, wv_error *err);
/* The same in the scene s, already loaded from o->scene (a caller that checks the scene
 * before the network runs loads it once). */
wv_status wv_estimate_run_scene(const wv_estimate_opts *o, const wv_scene *s, wv_estimate *e, wv_error *err);
/* The pair model for a photo pair in the scenes s (front-lit) and ts (back-lit), a model from
 * woven dataset --transmission-scene: model, or when NULL the default,
 * models/fabricnet-<s>+<ts>.bin ($WOVEN_MODEL_DIR). *found is 0 when model is NULL and there
 * is no default (the transmission colours then start from the prior). A found model is read
 * and checked (a pair model made for s and ts, else refused naming the file), so that a
 * capture refuses it before the slow steps; path receives its path. */
wv_status wv_estimate_pair_model(const wv_scene *s, const wv_scene *ts, const char *model, char *path, size_t cap,
                                 int *found, wv_error *err);
/* A photo pair's transmission colours: e's photo and photo_t (brought to the back-lit scene
 * scene_t) through the pair model at path, which sets the k_t of e->params and leaves the
 * rest as the one-photo model made them. */
wv_status wv_estimate_transmission(wv_estimate *e, const wv_scene *scene_t, const wv_image *photo_t, const char *path,
                                   wv_error *err);
void wv_estimate_free(wv_estimate *e);

#ifdef __cplusplus
}
#endif
#endif
