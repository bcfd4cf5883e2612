/* woven: FabricNet's estimate of a photo (woven/estimate.h): the scene's default model or
 * the one given, checked against the descriptor and the scene, run on the photo, with
 * the pattern given or chosen over the built-in library. */
#include "woven/estimate.h"

#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "woven/fabricnet.h"

#ifndef WOVEN_MODEL_DIR
#define WOVEN_MODEL_DIR "models"
#endif

/* models/fabricnet-<scene>.bin (a pair model: fabricnet-<scene>+<back-lit scene>.bin), in
 * $WOVEN_MODEL_DIR or the source tree's models/. */
static void default_model(const wv_scene *s, const wv_scene *ts, char *buf, size_t cap) {
  const char *d = getenv("WOVEN_MODEL_DIR");
  snprintf(buf, cap, "%s/fabricnet-%s%s%s.bin", d && *d ? d : WOVEN_MODEL_DIR, s->name, ts ? "+" : "",
           ts ? ts->name : "");
}

void wv_estimate_free(wv_estimate *e) {
  wv_image_free(&e->photo);
  wv_descriptor_free(e->desc);
  e->desc = NULL;
}

wv_status wv_estimate_run(const wv_estimate_opts *o, wv_estimate *e, wv_error *err) {
  wv_scene s;
  memset(e, 0, sizeof *e);
  wv_status rc = wv_scene_load(o->scene, &s, err);
  return rc ? rc : wv_estimate_run_scene(o, &s, e, err);
}

wv_status wv_estimate_run_scene(const wv_estimate_opts *o, const wv_scene *s, wv_estimate *e, wv_error *err) {
  double t0 = omp_get_wtime();
  memset(e, 0, sizeof *e);
  e->scene = *s;
  wv_status rc;
  wv_params probe; /* the pattern is checked before the slow steps */
  if (o->pattern && (rc = wv_params_default(o->pattern, &probe, err))) return rc;
  if (o->pattern && !strcmp(o->pattern, "custom"))
    return wv_fail(err, WV_ERR_INVALID, "the pattern must be a built-in pattern, not 'custom'");
  char mpath[4096];
  if (o->model)
    snprintf(mpath, sizeof mpath, "%s", o->model);
  else
    default_model(&e->scene, NULL, mpath, sizeof mpath);
  struct stat sb;
  if (!o->model && stat(mpath, &sb) != 0)
    return wv_fail(err, WV_ERR_IO,
                   "no default model for scene '%s' (%s); train one with 'woven dataset' and "
                   "'woven train' (docs/fabricnet.md) and pass --model",
                   e->scene.name, mpath);
  wv_fabricnet net;
  if ((rc = wv_fabricnet_load(mpath, &net, err))) return rc;
  if (!(rc = wv_descriptor_create(o->descriptor ? o->descriptor : "default", o->weights, &e->desc, err)) &&
      !(rc = wv_fabricnet_check_pair(&net, mpath, NULL, err)) &&
      !(rc = wv_fabricnet_check(&net, mpath, wv_descriptor_name(e->desc), wv_descriptor_size(e->desc),
                                o->any_scene ? NULL : &e->scene, err)))
    rc = wv_photo_load(o->photo, &e->scene, &o->crop, &e->photo, &e->info, err);
  float y[WV_NET_OUT_MAX];
  if (!rc && !o->pattern) {
    e->chosen = 1;
    if (!(rc = wv_fabricnet_predict_pattern(&net, e->desc, &e->scene, &e->photo, NULL, y, &e->choice, err))) {
      e->params = e->choice.params[e->choice.best];
      wv_pattern_choice_scene(&e->choice, &e->scene, e->choice.best, &e->scene); /* the cloth's orientation */
    }
  } else if (!rc) {
    float *feat = malloc(sizeof(float) * (size_t)net.n_in);
    if (!feat)
      rc = wv_fail(err, WV_ERR_NOMEM, "out of memory");
    else if (!(rc = wv_fabricnet_predict(&net, e->desc, &e->photo, feat, y, NULL, err)))
      rc = wv_fabricnet_params(&net, y, o->pattern, &e->params, err);
    free(feat);
  }
  wv_fabricnet_free(&net);
  if (rc) wv_estimate_free(e);
  e->seconds = omp_get_wtime() - t0;
  return rc;
}

wv_status wv_estimate_pair_model(const wv_scene *s, const wv_scene *ts, const char *model, char *path, size_t cap,
                                 int *found, wv_error *err) {
  *found = 0;
  if (model)
    snprintf(path, cap, "%s", model);
  else
    default_model(s, ts, path, cap);
  struct stat sb;
  if (!model && stat(path, &sb) != 0) return WV_OK; /* no pair model: the prior's k_t */
  wv_fabricnet net;
  wv_status rc = wv_fabricnet_load(path, &net, err);
  if (rc) return rc;
  if (!(rc = wv_fabricnet_check_pair(&net, path, ts, err)) &&
      (strcmp(net.scene, s->name) || net.scene_w != s->width || net.scene_h != s->height))
    rc = wv_fail(err, WV_ERR_INVALID, "%s: pair model trained on renders of scene '%s' (%d x %d), not '%s' (%d x %d)",
                 path, net.scene, net.scene_w, net.scene_h, s->name, s->width, s->height);
  wv_fabricnet_free(&net);
  if (!rc) *found = 1;
  return rc;
}

wv_status wv_estimate_transmission(wv_estimate *e, const wv_scene *scene_t, const wv_image *photo_t, const char *path,
                                   wv_error *err) {
  double t0 = omp_get_wtime();
  wv_fabricnet net;
  wv_status rc = wv_fabricnet_load(path, &net, err);
  if (rc) return rc;
  size_t nd = wv_descriptor_size(e->desc);
  float *feat = NULL, y[WV_NET_OUT_MAX];
  if (!(rc = wv_fabricnet_check_pair(&net, path, scene_t, err)) &&
      !(rc = wv_fabricnet_check(&net, path, wv_descriptor_name(e->desc), 2 * nd, &e->scene, err)) &&
      !(feat = malloc(sizeof(float) * 2 * nd)))
    rc = wv_fail(err, WV_ERR_NOMEM, "out of memory");
  /* the reflection photo's features, then the transmission photo's, as the pair set has them */
  if (!rc) rc = wv_descriptor_forward(e->desc, &e->photo, feat, err);
  if (!rc) rc = wv_descriptor_forward(e->desc, photo_t, feat + nd, err);
  if (!rc) rc = wv_fabricnet_predict_features(&net, feat, y, NULL, err);
  if (!rc) rc = wv_fabricnet_transmission(&net, y, &e->params, err);
  free(feat);
  wv_fabricnet_free(&net);
  e->seconds += omp_get_wtime() - t0;
  return rc;
}
