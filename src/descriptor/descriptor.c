/* The descriptor object: input checks, ImageNet normalisation (both networks see
 * the same input, as VGG expects), per-layer weights, and dispatch. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "descriptor/internal.h"
#include "woven/nn.h"

/* ImageNet statistics used by torchvision's VGG (SPEC section 7). */
static const float k_mean[3] = {0.485f, 0.456f, 0.406f};
static const float k_std[3] = {0.229f, 0.224f, 0.225f};

wv_status wv_descriptor_alloc(wv_descriptor **out, const char *name, int nlayers,
                              const int *channels, wv_error *err) {
  *out = NULL;
  if (nlayers < 1 || nlayers > WV_DESC_MAX_LAYERS)
    return wv_fail(err, WV_ERR_INVALID, "descriptor '%s': %d Gram layers (1 .. %d allowed)", name,
                   nlayers, WV_DESC_MAX_LAYERS);
  wv_descriptor *d = calloc(1, sizeof *d);
  if (!d) return wv_fail(err, WV_ERR_NOMEM, "out of memory for descriptor '%s'", name);
  snprintf(d->name, sizeof d->name, "%s", name);
  d->nlayers = nlayers;
  for (int l = 0; l < nlayers; l++) {
    d->layer_c[l] = channels[l];
    d->layer_off[l] = d->size;
    d->layer_w[l] = 1.0f;
    d->size += (size_t)channels[l] * channels[l];
  }
  *out = d;
  return WV_OK;
}

void wv_descriptor_free(wv_descriptor *d) {
  if (!d) return;
  if (d->destroy) d->destroy(d->impl);
  free(d->x);
  free(d->dx);
  free(d->dgram);
  free(d);
}

wv_status wv_descriptor_create(const char *name, const char *weights_path, wv_descriptor **out,
                               wv_error *err) {
  *out = NULL;
  if (!name || !strcmp(name, "default")) return wv_descriptor_create_default(out, err);
  if (!strcmp(name, "vgg19")) {
    if (!weights_path || !*weights_path)
      return wv_fail(err, WV_ERR_INVALID,
                     "descriptor vgg19 needs a weights file (--vgg19-weights FILE, a safetensors "
                     "file with torchvision's features.N tensors; see docs/descriptor.md)");
    return wv_descriptor_create_vgg19(weights_path, out, err);
  }
  return wv_fail(err, WV_ERR_INVALID, "unknown descriptor '%s' (expected default or vgg19)", name);
}

const char *wv_descriptor_name(const wv_descriptor *d) { return d->name; }
size_t wv_descriptor_size(const wv_descriptor *d) { return d->size; }
int wv_descriptor_layer_count(const wv_descriptor *d) { return d->nlayers; }
int wv_descriptor_min_side(const wv_descriptor *d) { return d->min_side; }

wv_status wv_descriptor_layer_info(const wv_descriptor *d, int layer, int *channels,
                                   size_t *offset, wv_error *err) {
  if (layer < 0 || layer >= d->nlayers)
    return wv_fail(err, WV_ERR_INVALID, "descriptor %s has no layer %d (it has %d)", d->name,
                   layer, d->nlayers);
  if (channels) *channels = d->layer_c[layer];
  if (offset) *offset = d->layer_off[layer];
  return WV_OK;
}

wv_status wv_descriptor_set_layer_weights(wv_descriptor *d, const float *w, wv_error *err) {
  for (int l = 0; l < d->nlayers; l++)
    if (!isfinite(w[l]))
      return wv_fail(err, WV_ERR_INVALID, "descriptor %s: layer weight %d is not finite", d->name,
                     l);
  for (int l = 0; l < d->nlayers; l++) d->layer_w[l] = w[l];
  return WV_OK;
}

static wv_status check_image(const wv_descriptor *d, const wv_image *img, wv_error *err) {
  if (!img || !img->data || img->c != 3)
    return wv_fail(err, WV_ERR_INVALID, "descriptor %s needs an RGB image (3 channels, got %d)",
                   d->name, img && img->data ? img->c : 0);
  if (img->w < d->min_side || img->h < d->min_side)
    return wv_fail(err, WV_ERR_INVALID,
                   "descriptor %s needs an image of at least %d x %d pixels (got %d x %d)",
                   d->name, d->min_side, d->min_side, img->w, img->h);
  if ((long)img->w * img->h > WV_IMAGE_MAX_PIXELS)
    return wv_fail(err, WV_ERR_NOMEM, "image of %d x %d pixels is too large", img->w, img->h);
  return WV_OK;
}

/* Planar, normalised copy of the image in d->x; buffers follow the image size. */
static wv_status prepare(wv_descriptor *d, const wv_image *img, int need_grad, wv_error *err) {
  size_t n = (size_t)img->w * img->h;
  if (d->cur_w != img->w || d->cur_h != img->h) {
    free(d->x);
    free(d->dx);
    d->dx = NULL;
    d->cur_w = d->cur_h = 0;
    if (!(d->x = malloc(sizeof(float) * 3 * n)))
      return wv_fail(err, WV_ERR_NOMEM, "out of memory for a %d x %d image", img->w, img->h);
    d->cur_w = img->w, d->cur_h = img->h;
  }
  if (need_grad && !d->dx && !(d->dx = malloc(sizeof(float) * 3 * n)))
    return wv_fail(err, WV_ERR_NOMEM, "out of memory for a %d x %d image", img->w, img->h);
  int bad = 0;
  float *x = d->x;
  const float *src = img->data;
#pragma omp parallel for schedule(static) reduction(| : bad)
  for (size_t i = 0; i < n; i++)
    for (int c = 0; c < 3; c++) {
      float v = src[3 * i + c];
      bad |= !isfinite(v);
      x[(size_t)c * n + i] = (v - k_mean[c]) * (1.0f / k_std[c]);
    }
  if (bad) return wv_fail(err, WV_ERR_INVALID, "image contains NaN or infinite values");
  return WV_OK;
}

static void apply_layer_weights(const wv_descriptor *d, float *g, const float *src) {
  for (int l = 0; l < d->nlayers; l++) {
    size_t o = d->layer_off[l], m = (size_t)d->layer_c[l] * d->layer_c[l];
    float w = d->layer_w[l];
    for (size_t i = 0; i < m; i++) g[o + i] = src[o + i] * w;
  }
}

wv_status wv_descriptor_forward(wv_descriptor *d, const wv_image *img, float *gram_out,
                                wv_error *err) {
  wv_status rc;
  if (!gram_out) return wv_fail(err, WV_ERR_INVALID, "descriptor %s: no output buffer", d->name);
  if ((rc = check_image(d, img, err)) || (rc = prepare(d, img, 0, err))) return rc;
  if ((rc = d->run(d, d->x, img->w, img->h, NULL, gram_out, NULL, err))) return rc;
  apply_layer_weights(d, gram_out, gram_out);
  return WV_OK;
}

wv_status wv_descriptor_backward(wv_descriptor *d, const wv_image *img, const float *dgram,
                                 float *gram_out, wv_image *dimg, wv_error *err) {
  wv_status rc;
  if (!dgram || !dimg || !dimg->data)
    return wv_fail(err, WV_ERR_INVALID, "descriptor %s: missing dgram or gradient image", d->name);
  if ((rc = check_image(d, img, err))) return rc;
  if (dimg->w != img->w || dimg->h != img->h || dimg->c != img->c)
    return wv_fail(err, WV_ERR_INVALID,
                   "descriptor %s: gradient image is %d x %d x %d, the image %d x %d x %d", d->name,
                   dimg->w, dimg->h, dimg->c, img->w, img->h, img->c);
  if ((rc = prepare(d, img, 1, err))) return rc;
  if (!d->dgram && !(d->dgram = malloc(sizeof(float) * d->size)))
    return wv_fail(err, WV_ERR_NOMEM, "out of memory for descriptor %s", d->name);
  apply_layer_weights(d, d->dgram, dgram); /* d(w G)/dG = w */
  /* Without gram_out the Gram matrices are not computed: the gradient needs dG and the
   * features, not G. */
  if ((rc = d->run(d, d->x, img->w, img->h, d->dgram, gram_out, d->dx, err))) return rc;
  if (gram_out) apply_layer_weights(d, gram_out, gram_out);
  /* Back through the normalisation, to the interleaved layout. */
  size_t n = (size_t)img->w * img->h;
  for (int c = 0; c < 3; c++) {
    float s = 1.0f / k_std[c];
    const float *src = d->dx + (size_t)c * n;
    float *dst = dimg->data + c;
    for (size_t i = 0; i < n; i++) dst[3 * i] = src[i] * s;
  }
  return WV_OK;
}
