/* woven: FabricNet (SPEC section 7, paper section 4.2): a fully connected head on the
 * texture descriptor that predicts 21 parameters as a start for the fit, its synthetic
 * training set, and the file formats of both. docs/fabricnet.md describes the formats.
 *
 *   features (descriptor Gram vector)
 *     -> preprocessing: x' = clip((slog1p(x) - mean) / std, +-10), stats stored in the model
 *     -> FC 256 -> LeakyReLU(0.01) -> FC 256 -> LeakyReLU(0.01) -> FC 21 -> sigmoid
 *     -> remap each output to its range (wv_fabricnet_output_range)
 *
 * Outputs, in order: density warp, density weft (20..250 yarns per inch), then the 19
 * continuous parameters in wv_param_id order with wv_param_range's ranges. The weave
 * pattern is not predicted (the caller gives it) and the noise level Q is left to the fit. */
#ifndef WOVEN_FABRICNET_H
#define WOVEN_FABRICNET_H

#include <stddef.h>
#include <stdint.h>

#include "woven/error.h"
#include "woven/image.h"
#include "woven/params.h"
#include "woven/scene.h"

#define WV_NET_OUT (2 + WV_P_COUNT) /* 21 */
#define WV_NET_HIDDEN 256
#define WV_NET_SLOPE 0.01f          /* LeakyReLU slope (PyTorch's default) */
#define WV_NET_PATTERNS 5
#define WV_NET_CLIP 10.0f         /* standardised features are clipped to +-10 */

/* The five built-in patterns, in dataset order: plain, twill, satin, twill90, satin90. */
const char *wv_net_pattern(int i);

/* Range of output k (0..20), in the parameter file's units. */
void wv_fabricnet_output_range(int k, double *lo, double *hi);
const char *wv_fabricnet_output_name(int k);
/* Parameters -> 21 targets normalised to [0,1] (clamped). */
void wv_fabricnet_targets(const wv_params *p, float *y);
/* Normalised outputs -> parameters with the model's ranges: pattern given, the rest from the pattern's prior mean
 * (Q, thickness, yarn width, seed), densities rounded to whole yarns per inch. */
struct wv_fabricnet_s;
wv_status wv_fabricnet_params(const struct wv_fabricnet_s *n, const float *y, const char *pattern, wv_params *p,
                              wv_error *err);

/* ---- half floats and checksums (used by both file formats) ---- */
uint16_t wv_f32_to_f16(float f); /* round to nearest even; overflow saturates to +-65504 */
uint32_t wv_crc32(uint32_t crc, const void *data, size_t n); /* zlib's CRC-32; start at 0 */

/* ---- the network ---- */
typedef struct wv_fabricnet_s {
  /* identity, checked when a model is used */
  char descriptor[32];
  int n_in;                  /* descriptor size */
  char scene[64];            /* scene name the training renders used */
  int scene_w, scene_h;
  uint32_t scene_crc;        /* CRC-32 of the scene's canonical JSON */
  double range[WV_NET_OUT][2];
  /* preprocessing statistics: n_in each */
  float *mean, *std;
  /* layers, PyTorch nn.Linear layout W (out, in) */
  float *w1, *b1, *w2, *b2, *w3, *b3;
} wv_fabricnet;

/* Fresh network, weights uniform in +-1/sqrt(fan_in) (PyTorch's Linear default),
 * deterministic in seed; mean 0, std 1. */
wv_status wv_fabricnet_init(wv_fabricnet *n, const char *descriptor, int n_in, const wv_scene *s, uint64_t seed,
                            wv_error *err);
void wv_fabricnet_free(wv_fabricnet *n);
size_t wv_fabricnet_param_count(const wv_fabricnet *n);
/* The weight and bias arrays, in file order, as one list (for the optimiser): six
 * arrays with their lengths. */
void wv_fabricnet_tensors(wv_fabricnet *n, float **t, size_t *len);

/* Signed log1p then standardisation, in place (x: batch x n_in). */
void wv_fabricnet_preprocess(const wv_fabricnet *n, float *x, int batch);
/* Activations a training step needs; sizes batch x 256, 256, 21. */
typedef struct {
  int cap;
  float *h1, *a1, *h2, *a2, *out;   /* forward */
  float *d_out, *d_a2, *d_h2, *d_a1; /* backward scratch */
} wv_fabricnet_acts;
wv_status wv_fabricnet_acts_alloc(wv_fabricnet_acts *a, int batch, wv_error *err);
void wv_fabricnet_acts_free(wv_fabricnet_acts *a);
/* x preprocessed (batch x n_in) -> a->out (batch x 21, in [0,1]). */
void wv_fabricnet_forward(const wv_fabricnet *n, const float *x, int batch, wv_fabricnet_acts *a);
/* L1 loss against targets y (batch x 21); gradients accumulate into g (same layout as
 * wv_fabricnet_tensors: gw1, gb1, ...). Returns the loss (before the backward pass). */
float wv_fabricnet_backward(const wv_fabricnet *n, const float *x, const float *y, int batch,
                            wv_fabricnet_acts *a, float *const *g);

/* One image -> 21 normalised outputs (runs the descriptor; the image is the scene's
 * capture image). feat: n_in floats of scratch. */
struct wv_descriptor;
wv_status wv_fabricnet_predict(const wv_fabricnet *n, struct wv_descriptor *d, const wv_image *img, float *feat,
                               float *y, wv_error *err);

/* ---- model file: a header naming descriptor, scene, layer sizes and ranges, the
 * preprocessing statistics (f32) and the weights (f16), CRC-32 over header and payload. ---- */
#define WV_NET_MAGIC "WVFNET\r\n"
#define WV_NET_VERSION 1
wv_status wv_fabricnet_save(const char *path, const wv_fabricnet *n, wv_error *err);
wv_status wv_fabricnet_load(const char *path, wv_fabricnet *n, wv_error *err);
/* Refuses a model made for another descriptor (name or size) or scene (name or size);
 * the message names the file. */
wv_status wv_fabricnet_check(const wv_fabricnet *n, const char *path, const char *descriptor, size_t n_in,
                             const wv_scene *s, wv_error *err);

/* ---- training checkpoint: the same header, f32 weights, Adam moments and the
 * trainer's counters. ---- */
typedef struct {
  int epoch;             /* epochs done */
  long adam_t;
  uint64_t rng;
  float best_val;        /* best validation loss so far */
  int best_epoch;
} wv_fabricnet_trainstate;
wv_status wv_fabricnet_checkpoint_save(const char *path, const wv_fabricnet *n, const float *adam_m,
                                       const float *adam_v, const wv_fabricnet_trainstate *ts, wv_error *err);
/* n, *adam_m and *adam_v (param_count floats, malloc'ed; caller frees) are allocated here. */
wv_status wv_fabricnet_checkpoint_load(const char *path, wv_fabricnet *n, float **adam_m, float **adam_v,
                                       wv_fabricnet_trainstate *ts, wv_error *err);

/* ---- synthetic dataset (docs/fabricnet.md) ----
 * DIR/dataset.json: kind "woven-dataset", version, seed, per_pattern, patterns, spp,
 * scene (the full scene JSON), descriptor name and size, image size.
 * DIR/samples/<pattern>_<i>.json   parameters (the parameter file format)
 * DIR/samples/<pattern>_<i>.png    capture image, 8-bit
 * DIR/samples/<pattern>_<i>.feat   descriptor features: 16-byte header + f16 values
 * The feature file is written last (each file atomically): a sample is done when its
 * three files exist and the feature file is complete and its CRC matches. */
#define WV_DATASET_VERSION 1
typedef struct {
  int version;
  uint64_t seed;
  int per_pattern;
  int spp;
  wv_scene scene;
  char scene_json[8192];
  char descriptor[32];
  int n_feat;
} wv_dataset_info;

wv_status wv_dataset_info_read(const char *dir, wv_dataset_info *info, wv_error *err);
wv_status wv_dataset_info_write(const char *dir, const wv_dataset_info *info, wv_error *err);
/* Sample k (0 .. 5 per_pattern - 1) interleaves the patterns: pattern k % 5, index k / 5. */
void wv_dataset_sample_name(int k, char *buf, size_t cap);
/* The prior draw of sample k (deterministic in the dataset seed). */
wv_status wv_dataset_sample_params(const wv_dataset_info *info, int k, wv_params *p, wv_error *err);
/* Path of one of a sample's files: ext "json", "png" or "feat". */
void wv_dataset_path(const char *dir, int k, const char *ext, char *buf, size_t cap);
/* 1 when the sample's three files are complete. */
int wv_dataset_sample_done(const char *dir, const wv_dataset_info *info, int k);
/* Features as f16 (n_feat values) with a header (magic, count, CRC). */
wv_status wv_dataset_write_features(const char *path, const float *x, int n, wv_error *err);
wv_status wv_dataset_read_features(const char *path, int n, uint16_t *out, wv_error *err);

#endif
