/* VGG-style descriptors (SPEC section 7): 3x3 convolutions + ReLU, max-pooling
 * replaced by 2x2 average pooling, a Gram layer after every pool. Weights come
 * from a safetensors file with torchvision's names. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "descriptor/internal.h"
#include "woven/nn.h"

#define VGG_MAX_CFG 64

typedef struct {
  int ncfg;
  int cfg[VGG_MAX_CFG];
  float *w[VGG_MAX_CFG], *b[VGG_MAX_CFG]; /* per convolution entry */
  /* Sized for the current image: act[i + 1] is the output of entry i (act[0] is the input). */
  int img_h, img_w;
  float *act[VGG_MAX_CFG + 1];
  int ac[VGG_MAX_CFG + 1], ah[VGG_MAX_CFG + 1], aw[VGG_MAX_CFG + 1];
  wv_nn_conv2d cv[VGG_MAX_CFG];
  float *g0, *g1, *scratch;
} vgg_net;

static void free_buffers(vgg_net *m) {
  for (int i = 1; i <= m->ncfg; i++) free(m->act[i]), m->act[i] = NULL;
  free(m->g0), free(m->g1), free(m->scratch);
  m->g0 = m->g1 = m->scratch = NULL;
  m->img_h = m->img_w = 0;
}

static void vgg_destroy(void *impl) {
  vgg_net *m = impl;
  if (!m) return;
  free_buffers(m);
  for (int i = 0; i < m->ncfg; i++) free(m->w[i]), free(m->b[i]);
  free(m);
}

static wv_status ensure_buffers(vgg_net *m, int w, int h, wv_error *err) {
  if (m->img_w == w && m->img_h == h) return WV_OK;
  free_buffers(m);
  m->ac[0] = 3, m->ah[0] = h, m->aw[0] = w;
  size_t gmax = 0, smax = 0;
  for (int i = 0; i < m->ncfg; i++) {
    int c = m->ac[i], hh = m->ah[i], ww = m->aw[i];
    if (m->cfg[i] > 0) {
      wv_status rc = wv_nn_conv2d_init(&m->cv[i], 1, c, hh, ww, m->cfg[i], 3, 1, 1, err);
      if (rc) return rc;
      size_t s = wv_nn_conv2d_scratch_floats(&m->cv[i]);
      if (s > smax) smax = s;
      m->ac[i + 1] = m->cfg[i], m->ah[i + 1] = hh, m->aw[i + 1] = ww;
    } else {
      m->ac[i + 1] = c, m->ah[i + 1] = hh / 2, m->aw[i + 1] = ww / 2;
    }
    size_t n = (size_t)m->ac[i + 1] * m->ah[i + 1] * m->aw[i + 1];
    if (n > gmax) gmax = n;
    if (!(m->act[i + 1] = malloc(sizeof(float) * n))) goto oom;
  }
  if (!(m->g0 = malloc(sizeof(float) * gmax)) || !(m->g1 = malloc(sizeof(float) * gmax)) ||
      !(m->scratch = malloc(sizeof(float) * (smax ? smax : 1))))
    goto oom;
  m->img_w = w, m->img_h = h;
  return WV_OK;
oom:
  free_buffers(m);
  return wv_fail(err, WV_ERR_NOMEM, "out of memory for VGG activations of a %d x %d image", w, h);
}

static wv_status vgg_run(wv_descriptor *d, const float *x, int w, int h, const float *dgram,
                         float *gram, float *dx, wv_error *err) {
  vgg_net *m = d->impl;
  wv_status rc = ensure_buffers(m, w, h, err);
  if (rc) return rc;
  m->act[0] = (float *)x; /* read only */
  int layer = 0;
  for (int i = 0; i < m->ncfg; i++) {
    size_t n = (size_t)m->ac[i + 1] * m->ah[i + 1] * m->aw[i + 1];
    if (m->cfg[i] > 0) {
      wv_nn_conv2d_forward(&m->cv[i], m->act[i], m->w[i], m->b[i], m->act[i + 1], m->scratch);
      wv_nn_relu_forward(m->act[i + 1], m->act[i + 1], n);
    } else {
      int hw = m->ah[i + 1] * m->aw[i + 1];
      wv_nn_avgpool2_forward(m->act[i + 1], m->act[i], m->ac[i], m->ah[i], m->aw[i]);
      if (gram)
        wv_nn_gram_forward(gram + d->layer_off[layer], m->act[i + 1], 1, m->ac[i + 1], hw);
      layer++;
    }
  }
  if (!dgram) return WV_OK;
  /* Backward: gcur is the gradient of act[i + 1], gprev receives that of act[i]. */
  float *gcur = m->g0, *gprev = m->g1;
  int L = m->ncfg;
  memset(gcur, 0, sizeof(float) * m->ac[L] * m->ah[L] * m->aw[L]);
  for (int i = L - 1; i >= 0; i--) {
    size_t nout = (size_t)m->ac[i + 1] * m->ah[i + 1] * m->aw[i + 1];
    float *dst = i == 0 ? dx : gprev;
    memset(dst, 0, sizeof(float) * m->ac[i] * m->ah[i] * m->aw[i]);
    if (m->cfg[i] > 0) {
      wv_nn_relu_mask(gcur, m->act[i + 1], nout);
      wv_nn_conv2d_backward(&m->cv[i], m->act[i], m->w[i], gcur, dst, NULL, NULL, m->scratch);
    } else {
      layer--;
      wv_nn_gram_backward(gcur, m->act[i + 1], dgram + d->layer_off[layer], 1, m->ac[i + 1],
                          m->ah[i + 1] * m->aw[i + 1]);
      wv_nn_avgpool2_backward(dst, gcur, m->ac[i], m->ah[i], m->aw[i]);
    }
    float *t = gcur;
    gcur = gprev, gprev = t;
  }
  return WV_OK;
}

wv_status wv_descriptor_create_vgg(const char *weights_path, const int *cfg, int ncfg,
                                   wv_descriptor **out, wv_error *err) {
  *out = NULL;
  if (!weights_path)
    return wv_fail(err, WV_ERR_INVALID, "VGG descriptor: no weights file given");
  if (ncfg < 1 || ncfg > VGG_MAX_CFG || cfg[ncfg - 1] != 0)
    return wv_fail(err, WV_ERR_INVALID,
                   "VGG descriptor: the layer list must have 1 .. %d entries and end with a pool",
                   VGG_MAX_CFG);
  int chans[WV_DESC_MAX_LAYERS], npool = 0, c = 3;
  for (int i = 0; i < ncfg; i++) {
    if (cfg[i] < 0 || cfg[i] > 4096)
      return wv_fail(err, WV_ERR_INVALID, "VGG descriptor: invalid layer width %d", cfg[i]);
    if (cfg[i] > 0) {
      c = cfg[i];
    } else {
      if (npool == WV_DESC_MAX_LAYERS)
        return wv_fail(err, WV_ERR_INVALID, "VGG descriptor: more than %d pools",
                       WV_DESC_MAX_LAYERS);
      chans[npool++] = c;
    }
  }
  vgg_net *m = calloc(1, sizeof *m);
  if (!m) return wv_fail(err, WV_ERR_NOMEM, "out of memory for a VGG descriptor");
  m->ncfg = ncfg;
  memcpy(m->cfg, cfg, sizeof(int) * ncfg);
  wv_safetensors st;
  wv_status rc = wv_st_open(&st, weights_path, err);
  if (rc) {
    vgg_destroy(m);
    return rc;
  }
  int idx = 0; /* torchvision module index */
  c = 3;
  for (int i = 0; i < ncfg && !rc; i++) {
    if (cfg[i] == 0) {
      idx++;
      continue;
    }
    char wn[64], bn[64];
    snprintf(wn, sizeof wn, "features.%d.weight", idx);
    snprintf(bn, sizeof bn, "features.%d.bias", idx);
    int64_t ws[4] = {cfg[i], c, 3, 3}, bs[1] = {cfg[i]};
    m->w[i] = malloc(sizeof(float) * cfg[i] * c * 9);
    m->b[i] = malloc(sizeof(float) * cfg[i]);
    if (!m->w[i] || !m->b[i])
      rc = wv_fail(err, WV_ERR_NOMEM, "out of memory for VGG weights");
    else if (!(rc = wv_st_read_f32(&st, wn, 4, ws, m->w[i], err)))
      rc = wv_st_read_f32(&st, bn, 1, bs, m->b[i], err);
    c = cfg[i];
    idx += 2; /* the convolution and its ReLU */
  }
  wv_st_close(&st);
  wv_descriptor *d = NULL;
  if (!rc) rc = wv_descriptor_alloc(&d, "vgg", npool, chans, err);
  if (rc) {
    vgg_destroy(m);
    return rc;
  }
  d->impl = m;
  d->destroy = vgg_destroy;
  d->run = vgg_run;
  d->min_side = 1 << npool; /* every pool needs two rows and columns */
  *out = d;
  return WV_OK;
}

wv_status wv_descriptor_create_vgg19(const char *weights_path, wv_descriptor **out,
                                     wv_error *err) {
  static const int cfg[] = {64,  64,  0,   128, 128, 0,   256, 256, 256, 256, 0,
                            512, 512, 512, 512, 0,   512, 512, 512, 512, 0};
  wv_status rc = wv_descriptor_create_vgg(weights_path, cfg, (int)(sizeof cfg / sizeof cfg[0]),
                                          out, err);
  if (!rc) snprintf((*out)->name, sizeof (*out)->name, "vgg19");
  return rc;
}
