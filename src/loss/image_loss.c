/* woven: the combined image loss of include/woven/loss.h: the texture (Gram), pixel,
 * structure and detail-colour terms of one photo, evaluated on renders with their joint
 * adjoint. The fit iterates on it; the pattern choice ranks candidates with it. */
#include <stdlib.h>
#include <string.h>

#include "woven/descriptor.h"
#include "woven/imgops.h"
#include "woven/loss.h"

struct wv_image_loss {
  wv_loss_weights w;
  wv_descriptor *d;
  int width, height;
  size_t ng;
  float *gram_photo, *gram, *dgram;
  wv_image photo_down, down, ddown, dpix;
  wv_spectrum_loss *spec;
  wv_colour_loss *colour;
  const float *last; /* the pixels of the render last evaluated (wv_image_loss_grad) */
};

void wv_image_loss_free(wv_image_loss *l) {
  if (!l) return;
  free(l->gram_photo), free(l->gram), free(l->dgram);
  wv_image_free(&l->photo_down), wv_image_free(&l->down), wv_image_free(&l->ddown), wv_image_free(&l->dpix);
  wv_spectrum_loss_free(l->spec);
  wv_colour_loss_free(l->colour);
  free(l);
}

wv_status wv_image_loss_create(const wv_image *photo, wv_descriptor *d, const float *gram_photo,
                               const wv_loss_weights *w, wv_image_loss **out, wv_error *err) {
  *out = NULL;
  wv_image_loss *l = calloc(1, sizeof *l);
  if (!l) return wv_fail(err, WV_ERR_NOMEM, "out of memory for the image loss");
  l->w = *w, l->d = d, l->width = photo->w, l->height = photo->h;
  l->ng = wv_descriptor_size(d);
  l->gram_photo = malloc(sizeof(float) * l->ng);
  l->gram = malloc(sizeof(float) * l->ng);
  l->dgram = malloc(sizeof(float) * l->ng);
  wv_status st = WV_OK;
  if (!l->gram_photo || !l->gram || !l->dgram) st = wv_fail(err, WV_ERR_NOMEM, "out of memory for Gram matrices");
  if (!st && gram_photo) memcpy(l->gram_photo, gram_photo, sizeof(float) * l->ng);
  if (!st && !gram_photo) st = wv_descriptor_forward(d, photo, l->gram_photo, err);
  if (!st) st = wv_image_downsample(photo, w->down_w, w->down_h, &l->photo_down, err);
  if (!st) st = wv_image_alloc(&l->ddown, w->down_w, w->down_h, 3, err);
  if (!st && w->w_struct > 0) st = wv_spectrum_loss_create(photo, &l->spec, err);
  if (!st && w->w_colour > 0) st = wv_colour_loss_create(photo, &l->colour, err);
  if (st) {
    wv_image_loss_free(l);
    return st;
  }
  *out = l;
  return WV_OK;
}

/* The terms for render, from the descriptor's forward pass when forward is set, else from
 * the one kept of the last call (the same render: the gradient of a value taken without it). */
static wv_status loss_run(wv_image_loss *l, const wv_image *render, int forward, wv_loss_terms *t, wv_image *dcap,
                          wv_error *err) {
  if (render->w != l->width || render->h != l->height)
    return wv_fail(err, WV_ERR_INVALID, "the render is %d x %d but the photo %d x %d", render->w, render->h,
                   l->width, l->height);
  wv_status st = WV_OK;
  if (forward) l->last = NULL; /* until this evaluation is whole */
  /* L_g = mean |G_render - G_photo| */
  if (forward && (st = wv_descriptor_forward(l->d, render, l->gram, err))) return st;
  memset(t, 0, sizeof *t);
  t->gram = wv_loss_gram(l->gram, l->gram_photo, l->ng, dcap ? l->dgram : NULL);
  /* L_c = mean |down(render) - down(photo)| */
  if (forward) {
    wv_image_free(&l->down);
    if ((st = wv_image_downsample(render, l->w.down_w, l->w.down_h, &l->down, err))) return st;
  }
  t->pixel = wv_image_l1(&l->down, &l->photo_down, dcap ? &l->ddown : NULL);
  if (dcap) {
    /* dL/dcapture: descriptor backward (it overwrites dcap), the pixel term through the
     * downsampling; the spectrum and detail-colour terms then add theirs, each from the
     * one evaluation that also gives its value */
    if ((st = wv_descriptor_backward(l->d, render, l->dgram, NULL, dcap, err))) return st;
    wv_image_free(&l->dpix);
    if ((st = wv_image_downsample_backward(render->w, render->h, &l->ddown, &l->dpix, err))) return st;
    size_t n = (size_t)render->w * render->h * 3;
    for (size_t i = 0; i < n; i++) dcap->data[i] += (float)l->w.w_pixel * l->dpix.data[i];
  }
  /* L_s: the weave's spectrum */
  t->structure = l->spec ? wv_spectrum_loss_eval(l->spec, render, dcap, (float)l->w.w_struct) : 0.0;
  /* L_k: the detail's colour */
  if (l->colour && (st = wv_colour_loss_eval(l->colour, render, dcap, (float)l->w.w_colour, &t->colour, err)))
    return st;
  t->total = t->gram + l->w.w_pixel * t->pixel + l->w.w_struct * t->structure + l->w.w_colour * t->colour;
  if (forward) l->last = render->data;
  return WV_OK;
}

wv_status wv_image_loss_eval(wv_image_loss *l, const wv_image *render, wv_loss_terms *t, wv_image *dcap,
                             wv_error *err) {
  return loss_run(l, render, 1, t, dcap, err);
}

wv_status wv_image_loss_grad(wv_image_loss *l, const wv_image *render, wv_image *dcap, wv_error *err) {
  if (!l->last || l->last != render->data)
    return wv_fail(err, WV_ERR_INVALID, "the loss's gradient asked for a render it did not evaluate last");
  wv_loss_terms t;
  return loss_run(l, render, 0, &t, dcap, err);
}
