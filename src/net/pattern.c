/* woven: choosing the weave pattern FabricNet does not predict, by rendering each
 * built-in pattern with the network's estimate and comparing textures with the photo. */
#include <jansson.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "woven/descriptor.h"
#include "woven/fabricnet.h"
#include "woven/imgops.h"
#include "woven/loss.h"
#include "woven/render.h"

void wv_pattern_opts_default(wv_pattern_opts *o) {
  o->spp = WV_PATTERN_SPP;
  o->threads = 0;
  o->w_pixel = WV_PATTERN_W_PIXEL;
}

wv_status wv_fabricnet_choose_pattern(const wv_fabricnet *n, wv_descriptor *d, const wv_scene *s,
                                      const wv_image *photo, const float *gram_photo, const float *y,
                                      const wv_pattern_opts *o, wv_pattern_choice *out, wv_error *err) {
  memset(out, 0, sizeof *out);
  wv_pattern_opts def;
  wv_pattern_opts_default(&def);
  if (!o) o = &def;
  size_t ng = wv_descriptor_size(d);
  if (ng != (size_t)n->n_in)
    return wv_fail(err, WV_ERR_INVALID, "descriptor gives %zu features, the model takes %d", ng, n->n_in);
  if (photo->w != s->width || photo->h != s->height)
    return wv_fail(err, WV_ERR_INVALID, "the photo is %d x %d but the scene renders %d x %d", photo->w, photo->h,
                   s->width, s->height);
  double t0 = omp_get_wtime();
  wv_scene sc = *s;
  sc.spp = o->spp > 0 ? o->spp : WV_PATTERN_SPP;
  out->spp = sc.spp, out->w_pixel = o->w_pixel;
  wv_render_opts ro = {sc.spp, o->threads, NULL, NULL, NULL};
  /* the fit's image loss: Gram and pixel terms (the criterion keeps its own pixel weight) */
  wv_loss_weights lw = {o->w_pixel, 0.0, WV_LOSS_DOWN_W, WV_LOSS_DOWN_H};
  wv_image_loss *loss = NULL;
  wv_status st = wv_image_loss_create(photo, d, gram_photo, &lw, &loss, err);
  for (int i = 0; i < WV_NET_PATTERNS && !st; i++) {
    wv_image img = {0};
    if ((st = wv_fabricnet_params(n, y, wv_net_pattern(i), &out->params[i], err))) break;
    /* the same render seed for every candidate: the losses then differ by the pattern, not the noise draw */
    if ((st = wv_render(&sc, &out->params[i], &ro, &img, NULL, err))) break;
    wv_loss_terms t;
    st = wv_image_loss_eval(loss, &img, &t, NULL, err);
    wv_image_free(&img);
    if (st) break;
    out->gram[i] = t.gram, out->pixel[i] = t.pixel;
    out->loss[i] = t.total;
    if (out->loss[i] < out->loss[out->best]) out->best = i;
  }
  wv_image_loss_free(loss);
  out->seconds = omp_get_wtime() - t0;
  return st;
}

wv_status wv_fabricnet_predict_pattern(const wv_fabricnet *n, wv_descriptor *d, const wv_scene *s,
                                       const wv_image *photo, const wv_pattern_opts *o, float *y,
                                       wv_pattern_choice *out, wv_error *err) {
  size_t ng = wv_descriptor_size(d);
  if (ng != (size_t)n->n_in)
    return wv_fail(err, WV_ERR_INVALID, "descriptor gives %zu features, the model takes %d", ng, n->n_in);
  float *gram = malloc(sizeof(float) * ng * 2);
  if (!gram) return wv_fail(err, WV_ERR_NOMEM, "out of memory for Gram vectors");
  float *feat = gram + ng;
  wv_status st = wv_descriptor_forward(d, photo, gram, err);
  if (!st) {
    /* the network preprocesses its input in place; the choice needs the raw Gram */
    memcpy(feat, gram, sizeof(float) * ng);
    st = wv_fabricnet_predict_features(n, feat, y, NULL, err);
  }
  if (!st) st = wv_fabricnet_choose_pattern(n, d, s, photo, gram, y, o, out, err);
  free(gram);
  return st;
}

static json_t *per_pattern(const double *v) {
  json_t *o = json_object();
  for (int i = 0; i < WV_NET_PATTERNS; i++) json_object_set_new(o, wv_net_pattern(i), json_real(v[i]));
  return o;
}

char *wv_pattern_choice_to_json(const wv_pattern_choice *c) {
  json_t *o = json_pack("{s:s,s:s,s:i,s:f,s:f,s:o,s:o,s:o}", "chosen", wv_net_pattern(c->best), "criterion",
                        "smallest gram + w_pixel * pixel loss of the network's estimate rendered with each built-in "
                        "pattern",
                        "spp", c->spp, "w_pixel", c->w_pixel, "seconds", c->seconds, "loss", per_pattern(c->loss),
                        "gram_loss", per_pattern(c->gram), "pixel_loss", per_pattern(c->pixel));
  char *s = o ? json_dumps(o, JSON_PRESERVE_ORDER | JSON_REAL_PRECISION(6)) : NULL;
  json_decref(o);
  return s;
}
