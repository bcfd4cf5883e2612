/* woven: FabricNet, the fully connected head of SPEC section 7 with its pattern head,
 * and its files (model and training checkpoint). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "util/half.h"
#include "woven/descriptor.h"
#include "woven/fabricnet.h"
#include "woven/io.h"
#include "woven/nn.h"
#include "woven/weave.h"

/* ---- outputs ---- */

void wv_fabricnet_output_range(int k, double *lo, double *hi) {
  if (k < 2) { /* densities: the full range of SPEC section 5 */
    *lo = 20, *hi = 250;
    return;
  }
  wv_param_range(k - 2, lo, hi);
}

const char *wv_fabricnet_output_name(int k) {
  return k == 0 ? "density.warp" : k == 1 ? "density.weft" : wv_param_name(k - 2);
}

static double clamp01(double v) { return v < 0 ? 0 : v > 1 ? 1 : v; }

void wv_fabricnet_targets(const wv_params *p, int n_out, float *y) {
  for (int k = 0; k < n_out && k < WV_NET_OUT_MAX; k++) {
    double lo, hi;
    wv_fabricnet_output_range(k, &lo, &hi);
    double v = k < 2 ? p->density[k] : wv_param_get(p, k - 2);
    y[k] = (float)clamp01((v - lo) / (hi - lo));
  }
}

/* Output k in the parameter file's units: the model's range, never wider than the program's. */
static double output_value(const wv_fabricnet *n, const float *y, int k) {
  double plo, phi;
  wv_fabricnet_output_range(k, &plo, &phi);
  double v = n->range[k][0] + clamp01(y[k]) * (n->range[k][1] - n->range[k][0]);
  return v < plo ? plo : v > phi ? phi : v;
}

wv_status wv_fabricnet_params(const wv_fabricnet *n, const float *y, const char *pattern, wv_params *p,
                              wv_error *err) {
  wv_status st = wv_params_default(pattern, p, err);
  if (st) return st;
  for (int k = 0; k < WV_NET_OUT; k++) {
    double v = output_value(n, y, k);
    if (k < 2)
      p->density[k] = floor(v + 0.5);
    else
      wv_param_set(p, k - 2, v);
  }
  wv_params_transmission_default(p); /* not predicted: the prior mean given the predicted colours */
  if (n->n_out == WV_NET_OUT_PAIR) return wv_fabricnet_transmission(n, y, p, err); /* k_t predicted */
  return wv_params_validate(p, err);
}

wv_status wv_fabricnet_transmission(const wv_fabricnet *n, const float *y, wv_params *p, wv_error *err) {
  if (n->n_out != WV_NET_OUT_PAIR)
    return wv_fail(err, WV_ERR_INVALID, "a one-photo model does not predict the transmission colours");
  for (int k = WV_NET_OUT; k < WV_NET_OUT_PAIR; k++) wv_param_set(p, k - 2, output_value(n, y, k));
  return wv_params_validate(p, err);
}

/* ---- the network ---- */

static size_t tensor_len(const wv_fabricnet *n, int i) {
  const int outs[4] = {WV_NET_HIDDEN, WV_NET_HIDDEN, n->n_out, n->n_cls};
  int in = i / 2 == 0 ? n->n_in : WV_NET_HIDDEN;
  return i % 2 ? (size_t)outs[i / 2] : (size_t)outs[i / 2] * in;
}

size_t wv_fabricnet_param_count(const wv_fabricnet *n) {
  size_t s = 0;
  for (int i = 0; i < WV_NET_TENSORS; i++) s += tensor_len(n, i);
  return s;
}

void wv_fabricnet_tensors(wv_fabricnet *n, float **t, size_t *len) {
  float *all[WV_NET_TENSORS] = {n->w1, n->b1, n->w2, n->b2, n->w3, n->b3, n->w4, n->b4};
  for (int i = 0; i < WV_NET_TENSORS; i++) t[i] = all[i], len[i] = tensor_len(n, i);
}

void wv_fabricnet_free(wv_fabricnet *n) {
  if (!n) return;
  free(n->w1); /* one block holds every array (alloc_net) */
  n->mean = n->std = n->w1 = n->b1 = n->w2 = n->b2 = n->w3 = n->b3 = n->w4 = n->b4 = NULL;
}

/* All arrays in one block: stats, then the six tensors in file order. */
static wv_status alloc_net(wv_fabricnet *n, wv_error *err) {
  if (n->n_in < 1 || n->n_in > (1 << 24)) return wv_fail(err, WV_ERR_INVALID, "feature count %d out of range", n->n_in);
  size_t p = wv_fabricnet_param_count(n);
  float *b = calloc(p + 2 * (size_t)n->n_in, sizeof(float));
  if (!b) return wv_fail(err, WV_ERR_NOMEM, "out of memory for the network (%zu weights)", p);
  n->w1 = b;
  n->b1 = n->w1 + tensor_len(n, 0);
  n->w2 = n->b1 + tensor_len(n, 1);
  n->b2 = n->w2 + tensor_len(n, 2);
  n->w3 = n->b2 + tensor_len(n, 3);
  n->b3 = n->w3 + tensor_len(n, 4);
  n->w4 = n->b3 + tensor_len(n, 5);
  n->b4 = n->w4 + tensor_len(n, 6);
  n->mean = n->b4 + tensor_len(n, 7);
  n->std = n->mean + n->n_in;
  return WV_OK;
}

static uint32_t scene_crc(const wv_scene *s) {
  char *j = wv_scene_to_json(s);
  uint32_t c = j ? crc32_z(0, (const unsigned char *)j, strlen(j)) : 0;
  free(j);
  return c;
}

wv_status wv_fabricnet_init(wv_fabricnet *n, const char *descriptor, int n_in, const wv_scene *s, const wv_scene *ts,
                            uint64_t seed, wv_error *err) {
  memset(n, 0, sizeof *n);
  snprintf(n->descriptor, sizeof n->descriptor, "%s", descriptor);
  snprintf(n->scene, sizeof n->scene, "%s", s->name);
  n->n_in = n_in, n->scene_w = s->width, n->scene_h = s->height, n->scene_crc = scene_crc(s);
  n->n_out = WV_NET_OUT;
  if (ts) {
    if (!ts->name[0]) return wv_fail(err, WV_ERR_INVALID, "a pair model's back-lit scene needs a name");
    snprintf(n->tscene, sizeof n->tscene, "%s", ts->name);
    n->tscene_w = ts->width, n->tscene_h = ts->height, n->tscene_crc = scene_crc(ts);
    n->n_out = WV_NET_OUT_PAIR;
  }
  if (wv_weave_builtin_count() != WV_NET_CLASSES)
    return wv_fail(err, WV_ERR_INTERNAL, "the weave library has %d built-ins, FabricNet's pattern head %d",
                   wv_weave_builtin_count(), WV_NET_CLASSES);
  n->n_cls = WV_NET_CLASSES;
  for (int k = 0; k < n->n_out; k++) wv_fabricnet_output_range(k, &n->range[k][0], &n->range[k][1]);
  wv_status st = alloc_net(n, err);
  if (st) return st;
  wv_rng r;
  wv_rng_seed(&r, seed);
  float *t[WV_NET_TENSORS];
  size_t len[WV_NET_TENSORS];
  wv_fabricnet_tensors(n, t, len);
  for (int i = 0; i < WV_NET_TENSORS; i++) {
    float b = 1.0f / sqrtf((float)(i / 2 == 0 ? n_in : WV_NET_HIDDEN));
    wv_rng_fill_uniform(&r, t[i], len[i], -b, b);
  }
  for (int i = 0; i < n_in; i++) n->std[i] = 1.0f;
  return WV_OK;
}

void wv_fabricnet_preprocess(const wv_fabricnet *n, float *x, int batch) {
  for (int b = 0; b < batch; b++) {
    float *r = x + (size_t)b * n->n_in;
    for (int i = 0; i < n->n_in; i++) {
      /* Gram entries span orders of magnitude: compress before standardising */
      float v = r[i], l = v < 0 ? -log1pf(-v) : log1pf(v);
      l = (l - n->mean[i]) / n->std[i];
      r[i] = l < -WV_NET_CLIP ? -WV_NET_CLIP : l > WV_NET_CLIP ? WV_NET_CLIP : l; /* outliers stay bounded */
    }
  }
}

wv_status wv_fabricnet_acts_alloc(wv_fabricnet_acts *a, int batch, wv_error *err) {
  size_t h = (size_t)batch * WV_NET_HIDDEN, o = (size_t)batch * WV_NET_OUT_MAX, k = (size_t)batch * WV_NET_CLASSES;
  float *b = calloc(4 * h + 2 * o + 2 * h + 3 * k, sizeof(float));
  if (!b) return wv_fail(err, WV_ERR_NOMEM, "out of memory for activations");
  a->cap = batch;
  a->h1 = b, a->a1 = b + h, a->h2 = b + 2 * h, a->a2 = b + 3 * h, a->out = b + 4 * h;
  a->d_out = a->out + o, a->d_a2 = a->d_out + o, a->d_h2 = a->d_a2 + h;
  a->d_a1 = a->d_a2; /* d_a2 is dead once d_h2 is computed, so d_a1 reuses its slot */
  a->logits = a->d_h2 + h, a->prob = a->logits + k, a->d_logits = a->prob + k;
  return WV_OK;
}

void wv_fabricnet_acts_free(wv_fabricnet_acts *a) {
  free(a->h1);
  memset(a, 0, sizeof *a);
}

void wv_fabricnet_forward(const wv_fabricnet *n, const float *x, int batch, wv_fabricnet_acts *a) {
  size_t h = (size_t)batch * WV_NET_HIDDEN;
  wv_nn_fc_forward(a->h1, x, n->w1, n->b1, batch, n->n_in, WV_NET_HIDDEN);
  wv_nn_leaky_relu_forward(a->a1, a->h1, WV_NET_SLOPE, h);
  wv_nn_fc_forward(a->h2, a->a1, n->w2, n->b2, batch, WV_NET_HIDDEN, WV_NET_HIDDEN);
  wv_nn_leaky_relu_forward(a->a2, a->h2, WV_NET_SLOPE, h);
  wv_nn_fc_forward(a->out, a->a2, n->w3, n->b3, batch, WV_NET_HIDDEN, n->n_out);
  wv_nn_sigmoid_forward(a->out, a->out, (size_t)batch * n->n_out);
  if (n->n_cls > 0) {
    wv_nn_fc_forward(a->logits, a->a2, n->w4, n->b4, batch, WV_NET_HIDDEN, n->n_cls);
    wv_nn_softmax_xent_forward(a->prob, a->logits, NULL, batch, n->n_cls);
  }
}

float wv_fabricnet_backward(const wv_fabricnet *n, const float *x, const float *y, const int *labels,
                            float ce_weight, int batch, wv_fabricnet_acts *a, float *const *g, float *l1_out,
                            float *ce_out) {
  size_t h = (size_t)batch * WV_NET_HIDDEN, o = (size_t)batch * n->n_out;
  wv_fabricnet_forward(n, x, batch, a);
  float l1 = wv_nn_l1_forward(a->out, y, o), ce = 0;
  int head = n->n_cls > 0 && labels;
  if (head) ce = wv_nn_softmax_xent_forward(NULL, a->logits, labels, batch, n->n_cls);
  if (l1_out) *l1_out = l1;
  if (ce_out) *ce_out = ce;
  /* dL/dout, then through the sigmoid in place (backward accumulates: zero first) */
  memset(a->d_out, 0, o * sizeof(float));
  wv_nn_l1_backward(a->d_out, a->out, y, 1.0f, o);
  for (size_t i = 0; i < o; i++) a->d_out[i] *= a->out[i] * (1.0f - a->out[i]);
  memset(a->d_a2, 0, h * sizeof(float));
  wv_nn_fc_backward(a->d_a2, g[4], g[5], a->d_out, a->a2, n->w3, batch, WV_NET_HIDDEN, n->n_out);
  if (head) { /* the pattern head adds its share to d_a2 */
    memset(a->d_logits, 0, (size_t)batch * n->n_cls * sizeof(float));
    wv_nn_softmax_xent_backward(a->d_logits, a->prob, labels, ce_weight, batch, n->n_cls);
    wv_nn_fc_backward(a->d_a2, g[6], g[7], a->d_logits, a->a2, n->w4, batch, WV_NET_HIDDEN, n->n_cls);
  }
  memset(a->d_h2, 0, h * sizeof(float));
  wv_nn_leaky_relu_backward(a->d_h2, a->h2, a->d_a2, WV_NET_SLOPE, h);
  memset(a->d_a1, 0, h * sizeof(float));
  wv_nn_fc_backward(a->d_a1, g[2], g[3], a->d_h2, a->a1, n->w2, batch, WV_NET_HIDDEN, WV_NET_HIDDEN);
  memset(a->d_h2, 0, h * sizeof(float)); /* reused as d_h1 */
  wv_nn_leaky_relu_backward(a->d_h2, a->h1, a->d_a1, WV_NET_SLOPE, h);
  wv_nn_fc_backward(NULL, g[0], g[1], a->d_h2, x, n->w1, batch, n->n_in, WV_NET_HIDDEN);
  return l1 + ce_weight * ce;
}

wv_status wv_fabricnet_predict(const wv_fabricnet *n, wv_descriptor *d, const wv_image *img, float *feat, float *y,
                               float *probs, wv_error *err) {
  if (wv_descriptor_size(d) != (size_t)n->n_in)
    return wv_fail(err, WV_ERR_INVALID, "descriptor gives %zu features, the model takes %d", wv_descriptor_size(d),
                   n->n_in);
  wv_status st = wv_descriptor_forward(d, img, feat, err);
  return st ? st : wv_fabricnet_predict_features(n, feat, y, probs, err);
}

wv_status wv_fabricnet_predict_features(const wv_fabricnet *n, float *feat, float *y, float *probs, wv_error *err) {
  wv_fabricnet_preprocess(n, feat, 1);
  wv_fabricnet_acts a;
  wv_status st = wv_fabricnet_acts_alloc(&a, 1, err);
  if (st) return st;
  wv_fabricnet_forward(n, feat, 1, &a);
  memcpy(y, a.out, (size_t)n->n_out * sizeof(float));
  if (probs) {
    int nb = wv_weave_builtin_count();
    for (int i = 0; i < nb; i++) probs[i] = n->n_cls == nb ? a.prob[i] : 1.0f / (float)nb;
  }
  wv_fabricnet_acts_free(&a);
  return WV_OK;
}

wv_status wv_fabricnet_check(const wv_fabricnet *n, const char *path, const char *descriptor, size_t n_in,
                             const wv_scene *s, wv_error *err) {
  if (strcmp(n->descriptor, descriptor) || (size_t)n->n_in != n_in)
    return wv_fail(err, WV_ERR_INVALID, "%s: model made for descriptor '%s' (%d features), not '%s' (%zu features)",
                   path, n->descriptor, n->n_in, descriptor, n_in);
  if (s && (strcmp(n->scene, s->name) || n->scene_w != s->width || n->scene_h != s->height))
    return wv_fail(err, WV_ERR_INVALID,
                   "%s: model trained on renders of scene '%s' (%d x %d), not '%s' (%d x %d); a network is "
                   "scene-specific: train one for this scene or pass --force",
                   path, n->scene, n->scene_w, n->scene_h, s->name, s->width, s->height);
  return WV_OK;
}

wv_status wv_fabricnet_check_pair(const wv_fabricnet *n, const char *path, const wv_scene *ts, wv_error *err) {
  if (!ts && n->tscene[0])
    return wv_fail(err, WV_ERR_INVALID,
                   "%s: a pair model (reflection and transmission photos, back-lit scene '%s'): it needs both photos",
                   path, n->tscene);
  if (ts && !n->tscene[0])
    return wv_fail(err, WV_ERR_INVALID, "%s: a one-photo model, not a model for a photo pair", path);
  if (ts && (strcmp(n->tscene, ts->name) || n->tscene_w != ts->width || n->tscene_h != ts->height))
    return wv_fail(err, WV_ERR_INVALID, "%s: pair model made for the back-lit scene '%s' (%d x %d), not '%s' (%d x %d)",
                   path, n->tscene, n->tscene_w, n->tscene_h, ts->name, ts->width, ts->height);
  return WV_OK;
}

/* ---- files ---- */

/* Header sizes and the offsets that moved when version 2 added the pattern classes and
 * version 3 (pair models) room for their outputs and back-lit scene (docs/fabricnet.md):
 * version 1 is 504 bytes, version 2 512, version 3 684. */
typedef struct {
  size_t hdr, cls, cls_crc, pl_size, pl_crc, hdr_crc, tscene;
} layout;
static const layout LAYOUT_V1 = {504, 0, 0, 488, 496, 500, 0};
static const layout LAYOUT_V2 = {512, 488, 492, 496, 504, 508, 0};
/* 27 output ranges from 152; tscene: name (64 bytes), width, height, CRC-32 of its JSON */
static const layout LAYOUT_V3 = {684, 584, 588, 668, 676, 680, 592};
enum { KIND_MODEL = 1, KIND_CHECKPOINT = 2 };
#define PREPROC_SLOG1P_STD 1
#define TRAINSTATE_BYTES 32

static void put32(unsigned char *b, uint32_t v) {
  for (int i = 0; i < 4; i++) b[i] = (unsigned char)(v >> (8 * i));
}
static void put64(unsigned char *b, uint64_t v) {
  for (int i = 0; i < 8; i++) b[i] = (unsigned char)(v >> (8 * i));
}
static uint32_t get32(const unsigned char *b) {
  return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}
static uint64_t get64(const unsigned char *b) { return (uint64_t)get32(b) | (uint64_t)get32(b + 4) << 32; }
static void putf(unsigned char *b, float f) {
  uint32_t u;
  memcpy(&u, &f, 4);
  put32(b, u);
}
static float getf(const unsigned char *b) {
  uint32_t u = get32(b);
  float f;
  memcpy(&f, &u, 4);
  return f;
}

/* Payload size: stats f32; weights f16 (model) or f32 (checkpoint); biases f32;
 * a checkpoint adds the Adam moments and the trainer state. */
static size_t payload_bytes(const wv_fabricnet *n, int kind) {
  size_t s = 8 * (size_t)n->n_in;
  for (int i = 0; i < WV_NET_TENSORS; i++) s += tensor_len(n, i) * (i % 2 == 0 && kind == KIND_MODEL ? 2 : 4);
  if (kind == KIND_CHECKPOINT) s += 8 * wv_fabricnet_param_count(n) + TRAINSTATE_BYTES;
  return s;
}

/* CRC-32 of the first k built-in names, each followed by a newline: a model's classes
 * must be the library's. */
static uint32_t classes_crc(int k) {
  uint32_t c = 0;
  for (int i = 0; i < k; i++) {
    const char *name = wv_weave_builtin_name(i);
    c = crc32_z(c, (const unsigned char *)(name ? name : ""), name ? strlen(name) : 0);
    c = crc32_z(c, (const unsigned char *)"\n", 1);
  }
  return c;
}

static wv_status save(const char *path, const wv_fabricnet *n, int kind, const float *m, const float *v,
                      const wv_fabricnet_trainstate *ts, wv_error *err) {
  /* a one-photo model in version 2, which older programs read too; a pair model in 3 */
  int pair = n->tscene[0] != 0;
  const layout *L2 = pair ? &LAYOUT_V3 : &LAYOUT_V2;
  const size_t HDR = L2->hdr;
  size_t pl = payload_bytes(n, kind), len = HDR + pl;
  unsigned char *b = calloc(len, 1);
  if (!b) return wv_fail(err, WV_ERR_NOMEM, "out of memory writing %s", path);
  memcpy(b, WV_NET_MAGIC, 8);
  put32(b + 8, pair ? 3 : 2);
  put32(b + 12, (uint32_t)kind);
  memcpy(b + 16, n->descriptor, strnlen(n->descriptor, 31));
  put32(b + 48, (uint32_t)n->n_in);
  memcpy(b + 52, n->scene, strnlen(n->scene, 63));
  put32(b + 116, (uint32_t)n->scene_w);
  put32(b + 120, (uint32_t)n->scene_h);
  put32(b + 124, n->scene_crc);
  const uint32_t layers[4] = {(uint32_t)n->n_in, WV_NET_HIDDEN, WV_NET_HIDDEN, (uint32_t)n->n_out};
  for (int i = 0; i < 4; i++) put32(b + 128 + 4 * i, layers[i]);
  put32(b + 144, PREPROC_SLOG1P_STD);
  put32(b + 148, (uint32_t)n->n_out);
  if (pair) {
    memcpy(b + L2->tscene, n->tscene, strnlen(n->tscene, 63));
    put32(b + L2->tscene + 64, (uint32_t)n->tscene_w);
    put32(b + L2->tscene + 68, (uint32_t)n->tscene_h);
    put32(b + L2->tscene + 72, n->tscene_crc);
  }
  for (int k = 0; k < n->n_out; k++)
    for (int j = 0; j < 2; j++) {
      uint64_t u;
      memcpy(&u, &n->range[k][j], 8);
      put64(b + 152 + 16 * k + 8 * j, u);
    }
  put32(b + L2->cls, (uint32_t)n->n_cls);
  put32(b + L2->cls_crc, classes_crc(n->n_cls));
  put64(b + L2->pl_size, pl);
  unsigned char *p = b + HDR;
  for (int i = 0; i < n->n_in; i++, p += 4) putf(p, n->mean[i]);
  for (int i = 0; i < n->n_in; i++, p += 4) putf(p, n->std[i]);
  const float *t[WV_NET_TENSORS] = {n->w1, n->b1, n->w2, n->b2, n->w3, n->b3, n->w4, n->b4};
  for (int i = 0; i < WV_NET_TENSORS; i++) {
    size_t L = tensor_len(n, i);
    if (i % 2 == 0 && kind == KIND_MODEL) {
      for (size_t j = 0; j < L; j++, p += 2) {
        uint16_t h = wv_f32_to_f16(t[i][j]);
        p[0] = (unsigned char)h, p[1] = (unsigned char)(h >> 8);
      }
    } else {
      for (size_t j = 0; j < L; j++, p += 4) putf(p, t[i][j]);
    }
  }
  if (kind == KIND_CHECKPOINT) {
    size_t P = wv_fabricnet_param_count(n);
    for (size_t j = 0; j < P; j++, p += 4) putf(p, m[j]);
    for (size_t j = 0; j < P; j++, p += 4) putf(p, v[j]);
    put32(p, (uint32_t)ts->epoch);
    put32(p + 4, (uint32_t)ts->best_epoch);
    put64(p + 8, (uint64_t)ts->adam_t);
    put64(p + 16, ts->rng);
    putf(p + 24, ts->best_val);
    p += TRAINSTATE_BYTES;
  }
  put32(b + L2->pl_crc, crc32_z(0, b + HDR, pl));
  put32(b + L2->hdr_crc, crc32_z(0, b, L2->hdr_crc));
  wv_status st = wv_write_file_atomic(path, b, len, err);
  free(b);
  return st;
}

wv_status wv_fabricnet_save(const char *path, const wv_fabricnet *n, wv_error *err) {
  return save(path, n, KIND_MODEL, NULL, NULL, NULL, err);
}

wv_status wv_fabricnet_checkpoint_save(const char *path, const wv_fabricnet *n, const float *adam_m,
                                       const float *adam_v, const wv_fabricnet_trainstate *ts, wv_error *err) {
  return save(path, n, KIND_CHECKPOINT, adam_m, adam_v, ts, err);
}

static int str_field(const unsigned char *b, int cap, char *out) {
  if (memchr(b, 0, (size_t)cap) == NULL) return 0; /* must be NUL-terminated inside its field */
  memcpy(out, b, (size_t)cap);
  return out[0] != 0;
}

static wv_status load(const char *path, int kind, wv_fabricnet *n, float **m, float **v, wv_fabricnet_trainstate *ts,
                      wv_error *err) {
  memset(n, 0, sizeof *n);
  char *data;
  size_t len;
  wv_status st = wv_read_file(path, &data, &len, err);
  if (st) return st;
  const unsigned char *b = (const unsigned char *)data;
  const char *what = kind == KIND_MODEL ? "FabricNet model" : "FabricNet training checkpoint";
#define BAD(...) do { st = wv_fail(err, WV_ERR_FORMAT, __VA_ARGS__); goto done; } while (0)
  if (len < 8 || memcmp(b, WV_NET_MAGIC, 8)) BAD("%s: not a %s (bad magic)", path, what);
  if (len < 12) BAD("%s: truncated %s (%zu bytes)", path, what, len);
  uint32_t version = get32(b + 8);
  if (version < 1 || version > WV_NET_VERSION)
    BAD("%s: %s format version %u; this program reads versions 1 to %d", path, what, version, WV_NET_VERSION);
  const layout *lay = version == 1 ? &LAYOUT_V1 : version == 2 ? &LAYOUT_V2 : &LAYOUT_V3;
  const size_t HDR = lay->hdr;
  if (len < HDR) BAD("%s: truncated %s (%zu bytes, header is %zu)", path, what, len, HDR);
  if (get32(b + lay->hdr_crc) != crc32_z(0, b, lay->hdr_crc)) BAD("%s: header checksum mismatch (corrupt file)", path);
  if (get32(b + 12) != (uint32_t)kind) {
    if (get32(b + 12) != KIND_MODEL && get32(b + 12) != KIND_CHECKPOINT)
      BAD("%s: unknown FabricNet file kind %u (1 is a model, 2 a training checkpoint)", path, get32(b + 12));
    BAD("%s: is a %s, not a %s", path, get32(b + 12) == KIND_MODEL ? "FabricNet model" : "training checkpoint", what);
  }
  if (!str_field(b + 16, 32, n->descriptor) || !str_field(b + 52, 64, n->scene))
    BAD("%s: descriptor or scene name missing in the header", path);
  n->n_in = (int)get32(b + 48);
  n->scene_w = (int)get32(b + 116), n->scene_h = (int)get32(b + 120), n->scene_crc = get32(b + 124);
  n->n_out = (int)get32(b + 148);
  if (lay->tscene) { /* version 3: a pair model */
    if (!str_field(b + lay->tscene, 64, n->tscene)) BAD("%s: back-lit scene name missing in the header", path);
    n->tscene_w = (int)get32(b + lay->tscene + 64), n->tscene_h = (int)get32(b + lay->tscene + 68);
    n->tscene_crc = get32(b + lay->tscene + 72);
  }
  int want_out = n->tscene[0] ? WV_NET_OUT_PAIR : WV_NET_OUT;
  if (n->n_in < 1 || n->n_in > (1 << 24) || get32(b + 128) != (uint32_t)n->n_in || get32(b + 132) != WV_NET_HIDDEN ||
      get32(b + 136) != WV_NET_HIDDEN || get32(b + 140) != (uint32_t)want_out || n->n_out != want_out)
    BAD("%s: layer sizes %u-%u-%u-%u; this program's FabricNet is features-%d-%d-%d", path, get32(b + 128),
        get32(b + 132), get32(b + 136), get32(b + 140), WV_NET_HIDDEN, WV_NET_HIDDEN, want_out);
  if (n->tscene[0] && (n->tscene_w < 1 || n->tscene_h < 1 || n->tscene_w > WV_SCENE_MAX_SIDE ||
                       n->tscene_h > WV_SCENE_MAX_SIDE))
    BAD("%s: invalid back-lit scene size %d x %d", path, n->tscene_w, n->tscene_h);
  if (get32(b + 144) != PREPROC_SLOG1P_STD) BAD("%s: unknown feature preprocessing %u", path, get32(b + 144));
  if (n->scene_w < 1 || n->scene_h < 1 || n->scene_w > WV_SCENE_MAX_SIDE || n->scene_h > WV_SCENE_MAX_SIDE)
    BAD("%s: invalid scene size %d x %d", path, n->scene_w, n->scene_h);
  n->n_cls = version == 1 ? 0 : (int)get32(b + lay->cls);
  if (n->n_cls != 0 && n->n_cls != WV_NET_CLASSES)
    BAD("%s: pattern head of %d classes; this program's library has %d built-ins", path, n->n_cls, WV_NET_CLASSES);
  if (n->n_cls && get32(b + lay->cls_crc) != classes_crc(n->n_cls))
    BAD("%s: the model's pattern classes are not this program's built-in weave library (train it again)", path);
  for (int k = 0; k < n->n_out; k++) {
    uint64_t u0 = get64(b + 152 + 16 * k), u1 = get64(b + 160 + 16 * k);
    memcpy(&n->range[k][0], &u0, 8), memcpy(&n->range[k][1], &u1, 8);
    if (!isfinite(n->range[k][0]) || !isfinite(n->range[k][1]) || !(n->range[k][0] < n->range[k][1]))
      BAD("%s: invalid range for output %d (%s)", path, k, wv_fabricnet_output_name(k));
  }
  size_t pl = payload_bytes(n, kind);
  if (get64(b + lay->pl_size) != pl)
    BAD("%s: payload size %llu does not match the header's layer sizes (%zu)", path,
        (unsigned long long)get64(b + lay->pl_size), pl);
  if (len < HDR + pl) BAD("%s: truncated (%zu of %zu bytes)", path, len, HDR + pl);
  if (len > HDR + pl) BAD("%s: %zu unexpected bytes after the payload", path, len - HDR - pl);
  if (get32(b + lay->pl_crc) != crc32_z(0, b + HDR, pl)) BAD("%s: payload checksum mismatch (corrupt file)", path);
  if ((st = alloc_net(n, err))) goto done;
  const unsigned char *p = b + HDR;
  for (int i = 0; i < n->n_in; i++, p += 4) n->mean[i] = getf(p);
  for (int i = 0; i < n->n_in; i++, p += 4) n->std[i] = getf(p);
  float *t[WV_NET_TENSORS];
  size_t L[WV_NET_TENSORS];
  wv_fabricnet_tensors(n, t, L);
  for (int i = 0; i < WV_NET_TENSORS; i++) {
    if (i % 2 == 0 && kind == KIND_MODEL)
      for (size_t j = 0; j < L[i]; j++, p += 2) t[i][j] = wv_nn_f16_to_f32((uint16_t)(p[0] | p[1] << 8));
    else
      for (size_t j = 0; j < L[i]; j++, p += 4) t[i][j] = getf(p);
  }
  for (int i = 0; i < n->n_in; i++)
    if (!isfinite(n->mean[i]) || !(n->std[i] > 0) || !isfinite(n->std[i])) BAD("%s: invalid feature statistics", path);
  static const char *tensor_names[WV_NET_TENSORS] = {
      "layer 1 weights", "layer 1 biases", "layer 2 weights",      "layer 2 biases",
      "layer 3 weights", "layer 3 biases", "pattern head weights", "pattern head biases"};
  for (int i = 0; i < WV_NET_TENSORS; i++)
    for (size_t j = 0; j < L[i]; j++)
      if (!isfinite(t[i][j])) BAD("%s: %s hold NaN or infinite values (corrupt %s)", path, tensor_names[i], what);
  if (kind == KIND_CHECKPOINT) {
    size_t P = wv_fabricnet_param_count(n);
    *m = malloc(P * sizeof(float)), *v = malloc(P * sizeof(float));
    if (!*m || !*v) {
      st = wv_fail(err, WV_ERR_NOMEM, "out of memory reading %s", path);
      goto done;
    }
    for (size_t j = 0; j < P; j++, p += 4) (*m)[j] = getf(p);
    for (size_t j = 0; j < P; j++, p += 4) (*v)[j] = getf(p);
    for (size_t j = 0; j < P; j++)
      if (!isfinite((*m)[j]) || !((*v)[j] >= 0) || !isfinite((*v)[j]))
        BAD("%s: Adam moments hold invalid values (NaN, infinite or a negative second moment)", path);
    /* The trainer's counters index arrays and scale steps: each within what training makes. */
    int32_t epoch = (int32_t)get32(p), best_epoch = (int32_t)get32(p + 4);
    uint64_t adam_t = get64(p + 8);
    float best_val = getf(p + 24);
    if (epoch < 0 || epoch > WV_NET_MAX_EPOCHS)
      BAD("%s: training state 'epoch' = %d is outside 0..%d", path, (int)epoch, WV_NET_MAX_EPOCHS);
    if (best_epoch < 0 || best_epoch > epoch)
      BAD("%s: training state 'best_epoch' = %d is outside 0..%d (the epochs done)", path, (int)best_epoch,
          (int)epoch);
    if (adam_t > ((uint64_t)1 << 53))
      BAD("%s: training state 'adam_t' = %llu is outside 0..2^53", path, (unsigned long long)adam_t);
    if (best_epoch > 0 ? !(best_val >= 0 && isfinite(best_val)) : !(best_val >= 0))
      BAD("%s: training state 'best_val' = %g is not a loss", path, (double)best_val);
    ts->epoch = epoch;
    ts->best_epoch = best_epoch;
    ts->adam_t = (long)adam_t;
    ts->rng = get64(p + 16);
    ts->best_val = best_val;
  }
#undef BAD
done:
  if (st) {
    wv_fabricnet_free(n);
    if (m && *m) free(*m), *m = NULL;
    if (v && *v) free(*v), *v = NULL;
  }
  free(data);
  return st;
}

wv_status wv_fabricnet_load(const char *path, wv_fabricnet *n, wv_error *err) {
  return load(path, KIND_MODEL, n, NULL, NULL, NULL, err);
}

wv_status wv_fabricnet_checkpoint_load(const char *path, wv_fabricnet *n, float **adam_m, float **adam_v,
                                       wv_fabricnet_trainstate *ts, wv_error *err) {
  *adam_m = *adam_v = NULL;
  return load(path, KIND_CHECKPOINT, n, adam_m, adam_v, ts, err);
}
