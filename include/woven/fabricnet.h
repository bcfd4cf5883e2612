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
 * pattern is not predicted: the caller gives it or wv_fabricnet_choose_pattern picks it over
 * the built-in library by the weave analysis of the photo and rendering; the noise level Q
 * is left to the fit. */
#ifndef WOVEN_FABRICNET_H
#define WOVEN_FABRICNET_H

#include <stddef.h>
#include <stdint.h>

#include "woven/analysis.h"
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
/* The same from the photo's raw descriptor features (n_in floats, preprocessed in place). */
wv_status wv_fabricnet_predict_features(const wv_fabricnet *n, float *feat, float *y, wv_error *err);

/* ---- the weave pattern: chosen over the whole built-in library ----
 * The 21 outputs do not depend on the pattern; only the parameters built from them
 * (wv_fabricnet_params) do. The choice (docs/analysis.md):
 *   1. The weave analysis of the photo (analysis.h): the lattice of its spectral peaks,
 *      explained for every built-in by densities and an orientation.
 *   2. If there is a lattice: the family (plain, basket, twill, satin) whose best lattice
 *      explains the peaks best wins; families within o->family_tie of it are contenders,
 *      decided by the loss criterion below (each with its best-ranked pattern). Within the
 *      family every built-in is rendered with the network's estimate and its own lattice
 *      densities in the centre window at a low spp and scored by how well its spectral peaks
 *      match the photo's (wv_lattice_rank; with o->prob, mixed with the network's class
 *      probabilities); patterns within o->tie of the best score are decided by the loss
 *      criterion. The chosen pattern starts with its lattice densities.
 *   3. Without a lattice (a flat card, sand, noise), the network's choice: the most
 *      probable class when o->prob is given, else the loss criterion over every built-in.
 * The loss criterion renders a candidate's parameters over the whole scene image at a low
 * spp and compares it with the photo by the fit's loss terms: the Gram loss L_g = mean
 * |Gram(photo) - Gram(render)| plus w_pixel times the pixel loss L_c = mean |down(photo) -
 * down(render)| (16 x 8 area averages); the smallest wins. Gram matrices are not rotation
 * invariant, so a pattern and its 90-degree variant give different losses. */
#define WV_PATTERN_SPP 4       /* as the fit iterates; 16 helps twill vs satin at 2-3x the cost (docs/fabricnet.md) */
#define WV_PATTERN_W_PIXEL 0.2 /* the fit's w2 */
#define WV_PATTERN_TIE 0.05    /* ranking scores this close to the best go to the loss criterion */
#define WV_PATTERN_FAMILY_TIE 0.05/* families whose lattices explain the photo this close to the best: too */
typedef struct {
  int spp;        /* samples per pixel of each candidate's render; 0: WV_PATTERN_SPP */
  int threads;    /* render threads; 0: OpenMP default */
  double w_pixel; /* weight of L_c in the criterion (the fit's w2 is 0.2) */
  int lattice;    /* 1: use the weave analysis (default); 0: the loss criterion over every built-in */
  double tie;     /* WV_PATTERN_TIE; 0: the best ranking score alone decides */
  double family_tie; /* WV_PATTERN_FAMILY_TIE; 0: the best lattice's family */
  /* Optional: the network's probability of each canonical built-in (WV_WEAVE_BUILTINS
   * values, wv_weave_builtin_name order; FabricNet's pattern head), NULL when the model has
   * none. Used as wv_rank_opts.prob (weight w_prob) and, without a lattice, as the choice. */
  const float *prob;
  double w_prob;  /* 0.25 */
} wv_pattern_opts;
void wv_pattern_opts_default(wv_pattern_opts *o);
typedef struct {
  int best;                 /* the chosen pattern, an index for wv_weave_builtin_name */
  const char *method;       /* "lattice" (the lattice and the ranking alone), "lattice+loss" (a tie of
                             * families or patterns broken by the loss criterion), "loss" (no lattice:
                             * the loss criterion), "network" (no lattice: the network's most probable
                             * class) */
  int family_contenders;    /* with a lattice: how many families the loss criterion chose among (1: none) */
  wv_lattice lattice;       /* the weave analysis (lattice.found: the photo showed one) */
  wv_lattice_ranking ranking; /* with a lattice: each built-in's render against the photo */
  int evaluated[WV_WEAVE_BUILTINS]; /* the loss criterion ran for this candidate */
  double loss[WV_WEAVE_BUILTINS];   /* its criterion, gram + w_pixel pixel */
  double gram[WV_WEAVE_BUILTINS];   /* its L_g */
  double pixel[WV_WEAVE_BUILTINS];  /* its L_c */
  wv_params params[WV_WEAVE_BUILTINS]; /* each candidate: the network's estimate with the pattern
                                        * (and, with a lattice, its lattice densities) */
  int spp;                  /* what the loss criterion's renders used */
  double w_pixel;           /* what the criterion used */
  double seconds;           /* analysis, renders and descriptor passes */
} wv_pattern_choice;
/* The loss criterion of candidate i of a choice made for this photo (a no-op when known). */
wv_status wv_pattern_loss(struct wv_descriptor *d, const wv_scene *s, const wv_image *photo, const float *gram_photo,
                          const wv_pattern_opts *o, int i, wv_pattern_choice *c, wv_error *err);
/* The decision of step 2 from a choice whose lattice was found and ranked: the chosen
 * pattern, or -1 - i when it needs the loss criterion of candidate i, not yet evaluated.
 * contenders (may be NULL): how many families were within family_tie. */
int wv_pattern_decide(const wv_pattern_choice *c, double family_tie, double tie, int *contenders);
/* y: the network's normalised outputs; photo: the scene's capture image; gram_photo: its raw
 * descriptor features (before preprocessing). o may be NULL (defaults). */
wv_status wv_fabricnet_choose_pattern(const wv_fabricnet *n, struct wv_descriptor *d, const wv_scene *s,
                                      const wv_image *photo, const float *gram_photo, const float *y,
                                      const wv_pattern_opts *o, wv_pattern_choice *out, wv_error *err);
/* The whole estimate without a pattern: one descriptor pass over the photo serves both the
 * network (y, 21 normalised outputs) and the choice. The result is out->params[out->best]. */
wv_status wv_fabricnet_predict_pattern(const wv_fabricnet *n, struct wv_descriptor *d, const wv_scene *s,
                                       const wv_image *photo, const wv_pattern_opts *o, float *y,
                                       wv_pattern_choice *out, wv_error *err);
/* {"chosen", "family", "method", "criterion", "spp", "w_pixel", "seconds", "lattice": {...},
 * "ranking": {...}, "loss", "gram_loss", "pixel_loss"}, the last three {pattern: value} over
 * the candidates the loss criterion evaluated; one line (malloc'ed, caller frees; NULL when
 * out of memory). docs/analysis.md lists the fields. */
char *wv_pattern_choice_to_json(const wv_pattern_choice *c);

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
#define WV_NET_MAX_EPOCHS 100000   /* most epochs a training may run */
#define WV_DATASET_MAX_PER_PATTERN 1000000 /* most samples per pattern in a dataset */
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

/* ---- synthetic dataset (docs/fabricnet.md) ----
 * DIR/dataset.json: kind "woven-dataset", version, seed, per_pattern, patterns, spp,
 * renderer (WV_RENDER_VERSION that made the images; absent = 1),
 * scene (the full scene JSON), descriptor name and size, image size.
 * DIR/samples/<pattern>_<i>.json   parameters (the parameter file format)
 * DIR/samples/<pattern>_<i>.png    capture image, 8-bit
 * DIR/samples/<pattern>_<i>.feat   descriptor features: 16-byte header + f16 values
 * The feature file is written last (each file atomically): a sample is done when its
 * parameter file reads back with the sample's pattern, its PNG is whole (every chunk's
 * CRC, wv_png_check) and the feature file is complete and its CRC matches. */
#define WV_DATASET_VERSION 1
typedef struct {
  int version;
  int renderer; /* WV_RENDER_VERSION of the renderer that made the samples */
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
/* Makes sample k in dir (whose samples/ exists): the prior draw rendered at info's
 * spp with render_threads (0 = all) and the footprints fp (made for info's scene,
 * or NULL), quantised to 8 bits as a photo arrives, then its parameter file, PNG
 * and, last, its features computed by d into feat (n_feat floats of scratch). */
struct wv_descriptor;
struct wv_footprints;
wv_status wv_dataset_make_sample(const char *dir, const wv_dataset_info *info, int k, int render_threads,
                                 const struct wv_footprints *fp, struct wv_descriptor *d, float *feat,
                                 wv_error *err);
/* Features as f16 (n_feat values) with a header (magic, count, CRC). */
wv_status wv_dataset_write_features(const char *path, const float *x, int n, wv_error *err);
wv_status wv_dataset_read_features(const char *path, int n, uint16_t *out, wv_error *err);

#endif
