/* woven: FabricNet (SPEC section 7, paper section 4.2): a fully connected head on the
 * texture descriptor that predicts 21 parameters as a start for the fit and the weave
 * pattern's probabilities over the built-in library, and its files (model and training
 * checkpoint). docs/fabricnet.md describes the formats.
 *
 *   features (descriptor Gram vector)
 *     -> preprocessing: x' = clip((slog1p(x) - mean) / std, +-10), stats stored in the model
 *     -> FC 256 -> LeakyReLU(0.01) -> FC 256 -> LeakyReLU(0.01) -+-> FC 21 -> sigmoid
 *                                                                 +-> FC 16 -> softmax (pattern head)
 *     -> remap each of the 21 outputs to its range (wv_fabricnet_output_range)
 *
 * Outputs, in order: density warp, density weft (20..250 yarns per inch), then the 19
 * continuous parameters in wv_param_id order with wv_param_range's ranges. The pattern
 * head gives a probability per canonical built-in (wv_weave_builtin_name's order); models
 * of format version 1 have no pattern head. The pattern is given by the caller or chosen by
 * wv_fabricnet_choose_pattern over the built-in library from the weave analysis of the
 * photo, rendering and the pattern head (woven/pattern.h); the noise level Q is left to the
 * fit. The training set is woven/dataset.h's, the training woven/train.h's and the estimate
 * of a photo woven/estimate.h's. */
#ifndef WOVEN_FABRICNET_H
#define WOVEN_FABRICNET_H

#include <stddef.h>
#include <stdint.h>

#include "woven/error.h"
#include "woven/image.h"
#include "woven/params.h"
#include "woven/scene.h"

#define WV_NET_OUT (2 + WV_P_REFLECT_COUNT) /* 21: the reflection model's parameters (the transmission
                                              * colours take their prior mean, wv_params_transmission_default) */
#define WV_NET_OUT_PAIR (2 + WV_P_KST_WARP_R) /* 27: a pair model's, the 21 and the diffuse transmission
                                              * colours k_t (k_st starts at its default and is fitted) */
#define WV_NET_OUT_MAX WV_NET_OUT_PAIR
#define WV_NET_HIDDEN 256
#define WV_NET_SLOPE 0.01f          /* LeakyReLU slope (PyTorch's default) */
#define WV_NET_CLIP 10.0f         /* standardised features are clipped to +-10 */
#define WV_NET_CLASSES 16         /* the pattern head: one class per canonical built-in (wv_weave_builtin_count) */
#define WV_NET_TENSORS 8          /* w1 b1 w2 b2 w3 b3, then the pattern head's w4 b4 */
#define WV_NET_HEAD_W 6           /* the index of the pattern head's first tensor, w4 */

/* Range of output k (0..WV_NET_OUT_MAX - 1), in the parameter file's units. */
void wv_fabricnet_output_range(int k, double *lo, double *hi);
const char *wv_fabricnet_output_name(int k);
/* Parameters -> the first n_out targets (WV_NET_OUT or WV_NET_OUT_PAIR) normalised to [0,1] (clamped). */
void wv_fabricnet_targets(const wv_params *p, int n_out, float *y);
/* Normalised outputs -> parameters with the model's ranges: pattern given, the rest from the pattern's prior mean
 * (Q, thickness, yarn width, seed), densities rounded to whole yarns per inch; the transmission colours from a pair
 * model's outputs, else the prior mean given the predicted colour. */
struct wv_fabricnet_s;
wv_status wv_fabricnet_params(const struct wv_fabricnet_s *n, const float *y, const char *pattern, wv_params *p,
                              wv_error *err);
/* Only the transmission colours of p from a pair model's outputs (n->n_out == WV_NET_OUT_PAIR). */
wv_status wv_fabricnet_transmission(const struct wv_fabricnet_s *n, const float *y, wv_params *p, wv_error *err);

/* ---- the network ---- */
typedef struct wv_fabricnet_s {
  /* identity, checked when a model is used */
  char descriptor[32];
  int n_in;                  /* descriptor size */
  char scene[64];            /* scene name the training renders used */
  int scene_w, scene_h;
  uint32_t scene_crc;        /* CRC-32 of the scene's canonical JSON */
  /* A pair model (version 3): the back-lit scene of its transmission renders; its input is
   * the descriptor of the reflection image followed by that of the transmission image
   * (n_in twice the descriptor's size) and it has WV_NET_OUT_PAIR outputs. Empty name:
   * a one-photo model of WV_NET_OUT outputs. */
  char tscene[64];
  int tscene_w, tscene_h;
  uint32_t tscene_crc;
  int n_out;                 /* WV_NET_OUT or WV_NET_OUT_PAIR */
  double range[WV_NET_OUT_MAX][2];
  /* preprocessing statistics: n_in each */
  float *mean, *std;
  int n_cls;                 /* pattern classes: WV_NET_CLASSES, or 0 (a version 1 model, no head) */
  /* layers, PyTorch nn.Linear layout W (out, in); w4 (n_cls x 256), b4: the pattern head */
  float *w1, *b1, *w2, *b2, *w3, *b3, *w4, *b4;
} wv_fabricnet;

/* Fresh network with the pattern head, weights uniform in +-1/sqrt(fan_in) (PyTorch's
 * Linear default), deterministic in seed; mean 0, std 1. ts NULL: a one-photo model;
 * else a pair model for the reflection scene s and the back-lit scene ts (n_in: both
 * images' features). */
wv_status wv_fabricnet_init(wv_fabricnet *n, const char *descriptor, int n_in, const wv_scene *s, const wv_scene *ts,
                            uint64_t seed, wv_error *err);
void wv_fabricnet_free(wv_fabricnet *n);
size_t wv_fabricnet_param_count(const wv_fabricnet *n);
/* The weight and bias arrays, in file order, as one list (for the optimiser): the
 * WV_NET_TENSORS arrays with their lengths (w4, b4 of length 0 without a pattern head).
 * They are one contiguous block starting at w1, wv_fabricnet_param_count floats long. */
void wv_fabricnet_tensors(wv_fabricnet *n, float **t, size_t *len);

/* Signed log1p then standardisation, in place (x: batch x n_in). */
void wv_fabricnet_preprocess(const wv_fabricnet *n, float *x, int batch);
/* Activations a training step needs; sizes batch x 256, 256, n_out (room for
 * WV_NET_OUT_MAX) and batch x WV_NET_CLASSES for the pattern head. */
typedef struct {
  int cap;
  float *h1, *a1, *h2, *a2, *out;   /* forward */
  float *logits, *prob;             /* pattern head: logits and softmax (when the model has it) */
  float *d_out, *d_a2, *d_h2, *d_a1, *d_logits; /* backward scratch */
} wv_fabricnet_acts;
wv_status wv_fabricnet_acts_alloc(wv_fabricnet_acts *a, int batch, wv_error *err);
void wv_fabricnet_acts_free(wv_fabricnet_acts *a);
/* x preprocessed (batch x n_in) -> a->out (batch x n_out, in [0,1]) and, with a pattern
 * head, a->prob (batch x n_cls). */
void wv_fabricnet_forward(const wv_fabricnet *n, const float *x, int batch, wv_fabricnet_acts *a);
/* Loss L1(out, y) + ce_weight CE(prob, labels): L1 against targets y (batch x n_out), softmax
 * cross-entropy against the pattern labels (batch, indices of wv_weave_builtin_name; NULL or
 * a model without a head: no CE term). Gradients accumulate into g (same layout as
 * wv_fabricnet_tensors: gw1, gb1, ...). Returns the total loss (before the backward pass);
 * l1 and ce (may be NULL) receive its parts. */
float wv_fabricnet_backward(const wv_fabricnet *n, const float *x, const float *y, const int *labels,
                            float ce_weight, int batch, wv_fabricnet_acts *a, float *const *g, float *l1, float *ce);

/* One image -> n_out normalised outputs (runs the descriptor; the image is the scene's
 * capture image; a one-photo model). feat: n_in floats of scratch. probs (optional, may be NULL):
 * wv_weave_builtin_count() floats, the probability of each canonical built-in pattern,
 * indexed like wv_weave_builtin_name; they sum to 1. A model without a pattern head
 * (format version 1) gives every pattern 1 / count. */
struct wv_descriptor;
wv_status wv_fabricnet_predict(const wv_fabricnet *n, struct wv_descriptor *d, const wv_image *img, float *feat,
                               float *y, float *probs, wv_error *err);
/* The same from raw descriptor features (n_in floats, preprocessed in place): a pair model's
 * are the reflection photo's followed by the transmission photo's. */
wv_status wv_fabricnet_predict_features(const wv_fabricnet *n, float *feat, float *y, float *probs, wv_error *err);

/* ---- model file: a header naming descriptor, scene, layer sizes, ranges and pattern
 * classes, the preprocessing statistics (f32) and the weights (f16), CRC-32 over header and
 * payload. Version 2 adds the pattern head, version 3 the pair model's back-lit scene and
 * its outputs; versions 1 (no head) and 2 still load. ---- */
#define WV_NET_MAGIC "WVFNET\r\n"
#define WV_NET_VERSION 3 /* the newest read; one-photo models are written in version 2 */
wv_status wv_fabricnet_save(const char *path, const wv_fabricnet *n, wv_error *err);
wv_status wv_fabricnet_load(const char *path, wv_fabricnet *n, wv_error *err);
/* Refuses a model made for another descriptor (name or size; n_in: the features the model
 * takes) or scene (name or size); the message names the file. */
wv_status wv_fabricnet_check(const wv_fabricnet *n, const char *path, const char *descriptor, size_t n_in,
                             const wv_scene *s, wv_error *err);
/* Refuses a pair model where a one-photo model is wanted (ts NULL), and a one-photo model
 * or a pair model made for another back-lit scene where a pair model for ts is wanted. */
wv_status wv_fabricnet_check_pair(const wv_fabricnet *n, const char *path, const wv_scene *ts, wv_error *err);

/* ---- training checkpoint: the same header, f32 weights, Adam moments and the
 * trainer's counters. ---- */
#define WV_NET_MAX_EPOCHS 100000   /* most epochs a training may run */
typedef struct {
  int epoch;             /* epochs done */
  long adam_t;
  uint64_t rng;
  float best_val;        /* best validation loss so far */
  int best_epoch;
} wv_fabricnet_trainstate;
wv_status wv_fabricnet_checkpoint_save(const char *path, const wv_fabricnet *n, const float *adam_m,
                                       const float *adam_v, const wv_fabricnet_trainstate *ts, wv_error *err);
/* n, *adam_m and *adam_v (param_count floats, malloc'ed; caller frees) are allocated here.
 * Every value is checked (epochs 0..WV_NET_MAX_EPOCHS, best epoch within them, step
 * count, finite weights and moments); messages name the file. */
wv_status wv_fabricnet_checkpoint_load(const char *path, wv_fabricnet *n, float **adam_m, float **adam_v,
                                       wv_fabricnet_trainstate *ts, wv_error *err);

#endif
