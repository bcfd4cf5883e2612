/* woven: FabricNet (SPEC section 7, paper section 4.2): a fully connected head on the
 * texture descriptor that predicts 21 parameters as a start for the fit and the weave
 * pattern's probabilities over the built-in library, its synthetic training set, and the
 * file formats of both. docs/fabricnet.md describes the formats.
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
 * photo, rendering and the pattern head; the noise level Q is left to the fit. */
#ifndef WOVEN_FABRICNET_H
#define WOVEN_FABRICNET_H

#include <stddef.h>
#include <stdint.h>

#include "woven/analysis.h"
#include "woven/dist.h"
#include "woven/error.h"
#include "woven/image.h"
#include "woven/params.h"
#include "woven/scene.h"

#define WV_NET_OUT (2 + WV_P_COUNT) /* 21 */
#define WV_NET_HIDDEN 256
#define WV_NET_SLOPE 0.01f          /* LeakyReLU slope (PyTorch's default) */
#define WV_NET_PATTERNS 5
#define WV_NET_CLIP 10.0f         /* standardised features are clipped to +-10 */
#define WV_NET_CLASSES 16         /* the pattern head: one class per canonical built-in (wv_weave_builtin_count) */
#define WV_NET_TENSORS 8          /* w1 b1 w2 b2 w3 b3, then the pattern head's w4 b4 */

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
  int n_cls;                 /* pattern classes: WV_NET_CLASSES, or 0 (a version 1 model, no head) */
  /* layers, PyTorch nn.Linear layout W (out, in); w4 (n_cls x 256), b4: the pattern head */
  float *w1, *b1, *w2, *b2, *w3, *b3, *w4, *b4;
} wv_fabricnet;

/* Fresh network with the pattern head, weights uniform in +-1/sqrt(fan_in) (PyTorch's
 * Linear default), deterministic in seed; mean 0, std 1. */
wv_status wv_fabricnet_init(wv_fabricnet *n, const char *descriptor, int n_in, const wv_scene *s, uint64_t seed,
                            wv_error *err);
void wv_fabricnet_free(wv_fabricnet *n);
size_t wv_fabricnet_param_count(const wv_fabricnet *n);
/* The weight and bias arrays, in file order, as one list (for the optimiser): the
 * WV_NET_TENSORS arrays with their lengths (w4, b4 of length 0 without a pattern head).
 * They are one contiguous block starting at w1, wv_fabricnet_param_count floats long. */
void wv_fabricnet_tensors(wv_fabricnet *n, float **t, size_t *len);

/* Signed log1p then standardisation, in place (x: batch x n_in). */
void wv_fabricnet_preprocess(const wv_fabricnet *n, float *x, int batch);
/* Activations a training step needs; sizes batch x 256, 256, 21 and batch x
 * WV_NET_CLASSES for the pattern head. */
typedef struct {
  int cap;
  float *h1, *a1, *h2, *a2, *out;   /* forward */
  float *logits, *prob;             /* pattern head: logits and softmax (when the model has it) */
  float *d_out, *d_a2, *d_h2, *d_a1, *d_logits; /* backward scratch */
} wv_fabricnet_acts;
wv_status wv_fabricnet_acts_alloc(wv_fabricnet_acts *a, int batch, wv_error *err);
void wv_fabricnet_acts_free(wv_fabricnet_acts *a);
/* x preprocessed (batch x n_in) -> a->out (batch x 21, in [0,1]) and, with a pattern
 * head, a->prob (batch x n_cls). */
void wv_fabricnet_forward(const wv_fabricnet *n, const float *x, int batch, wv_fabricnet_acts *a);
/* Loss L1(out, y) + ce_weight CE(prob, labels): L1 against targets y (batch x 21), softmax
 * cross-entropy against the pattern labels (batch, indices of wv_weave_builtin_name; NULL or
 * a model without a head: no CE term). Gradients accumulate into g (same layout as
 * wv_fabricnet_tensors: gw1, gb1, ...). Returns the total loss (before the backward pass);
 * l1 and ce (may be NULL) receive its parts. */
float wv_fabricnet_backward(const wv_fabricnet *n, const float *x, const float *y, const int *labels,
                            float ce_weight, int batch, wv_fabricnet_acts *a, float *const *g, float *l1, float *ce);

/* One image -> 21 normalised outputs (runs the descriptor; the image is the scene's
 * capture image). feat: n_in floats of scratch. probs (optional, may be NULL):
 * wv_weave_builtin_count() floats, the probability of each canonical built-in pattern,
 * indexed like wv_weave_builtin_name; they sum to 1. A model without a pattern head
 * (format version 1) gives every pattern 1 / count. */
struct wv_descriptor;
wv_status wv_fabricnet_predict(const wv_fabricnet *n, struct wv_descriptor *d, const wv_image *img, float *feat,
                               float *y, float *probs, wv_error *err);
/* The same from the photo's raw descriptor features (n_in floats, preprocessed in place). */
wv_status wv_fabricnet_predict_features(const wv_fabricnet *n, float *feat, float *y, float *probs, wv_error *err);

/* ---- the weave pattern: chosen over the whole built-in library ----
 * The 21 outputs do not depend on the pattern; only the parameters built from them
 * (wv_fabricnet_params) do. The choice (docs/analysis.md):
 *   1. The weave analysis of the photo (analysis.h): the lattice of its spectral peaks,
 *      explained for every built-in by densities and an orientation.
 *   2. If there is a lattice: the family (plain, basket, twill, satin) whose best built-in
 *      has the best mean of lattice score and ranking score (below) wins; families within
 *      o->family_tie of it are contenders,
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
#define WV_PATTERN_FAMILY_TIE 0.0 /* families this close to the best go to the loss criterion too; 0: the
                                  * lattice and render match alone decide the family (fewer wrong
                                  * families on synthetic targets, docs/analysis.md) */
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
  double psf_sigma; /* camera blur of the candidates' renders: -1 (default) the scene's, else measured
                     * from the photo on the network's estimate (wv_psf_estimate); >= 0 this sigma */
  int orient;     /* 1 (default): on a plane scene, each candidate is rendered, and the chosen one
                   * fitted, with its lattice's rotation and skew (wv_pattern_choice_scene) */
  int refine;     /* 1 (default): the chosen pattern's lattice is refined over the whole image
                   * (wv_lattice_refine) */
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
  int has_prob;                     /* the network's pattern head gave probabilities: */
  double prob[WV_WEAVE_BUILTINS];   /* ... each built-in's */
  wv_params params[WV_WEAVE_BUILTINS]; /* each candidate: the network's estimate with the pattern
                                        * (and, with a lattice, its lattice densities) */
  int spp;                  /* what the loss criterion's renders used */
  double w_pixel;           /* what the criterion used */
  double seconds;           /* analysis, renders and descriptor passes */
  double psf_sigma;         /* the camera blur the candidates were rendered with */
  int orient;               /* the candidates carry their lattice's orientation (wv_pattern_opts) */
} wv_pattern_choice;
/* The scene in which candidate i of c is rendered and fitted: s, with the rotation and
 * skew of its lattice added when c->orient and the lattice was found (a plane scene). out
 * may be s. */
void wv_pattern_choice_scene(const wv_pattern_choice *c, const wv_scene *s, int i, wv_scene *out);
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

/* ---- model file: a header naming descriptor, scene, layer sizes, ranges and pattern
 * classes, the preprocessing statistics (f32) and the weights (f16), CRC-32 over header and
 * payload. Version 2 adds the pattern head; version 1 files (no head) still load. ---- */
#define WV_NET_MAGIC "WVFNET\r\n"
#define WV_NET_VERSION 2
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

/* ---- training (docs/fabricnet.md, "woven train") ---- */
#define WV_NET_CE_WEIGHT 0.1 /* weight of the pattern head's cross-entropy beside the L1 */
typedef struct {
  int epoch;                 /* 1-based */
  double train, val;         /* mean L1 on normalised parameters */
  double train_ce, val_ce;   /* pattern head cross-entropy (0 without a head) */
  double val_acc;            /* fraction of validation samples whose most probable pattern is theirs */
  int best;                  /* this epoch became MODEL */
  double seconds;            /* since the run (or the resume) started */
} wv_train_epoch;
typedef struct {
  int samples, train, validation, missing; /* the loaded set and its split */
  int resumed_epoch;         /* epochs the checkpoint had done (0: a fresh start) */
  int epochs, epochs_run;    /* epochs done in all, and in this run */
  int best_epoch;
  double best_val;           /* its validation L1 + ce_weight CE (the criterion) */
  double val_f16;            /* the saved model's validation L1 (f16 weights) */
  double val_ce, val_accuracy; /* ... its pattern head's CE and accuracy */
  double val_per_output[WV_NET_OUT];
  double final_train;        /* the last epoch's training L1 */
  double seconds, load_seconds;
} wv_train_result;
typedef struct {
  int epochs;            /* total epochs (60); a resume continues up to this */
  int batch;             /* 32 */
  double lr;             /* Adam learning rate, 1e-4 */
  double val_frac;       /* held-out fraction, chosen by a hash of the sample (0.1) */
  uint64_t seed;         /* initial weights and each epoch's shuffle (1) */
  int checkpoint_every;  /* epochs between checkpoints (1) */
  int resume;            /* continue from MODEL.train/checkpoint.bin */
  int force;             /* start again even when MODEL.train/ holds a checkpoint */
  int partial;           /* train on the finished samples of an incomplete dataset */
  double ce_weight;      /* WV_NET_CE_WEIGHT */
  const char *init;      /* optional: start from this model's weights and feature statistics
                          * (fine-tuning; a version 1 model's missing pattern head starts fresh) */
  /* Optional callbacks: after loading (before the first epoch), during and after each epoch. */
  void (*on_start)(void *user, const wv_train_result *r);
  void (*on_progress)(void *user, double fraction);
  void (*on_epoch)(void *user, const wv_train_epoch *e);
  void *user;
} wv_train_opts;
void wv_train_opts_default(wv_train_opts *o);
/* Trains FabricNet on the dataset in dir. model receives the weights of the epoch with
 * the lowest validation loss (written atomically whenever it improves); model.train/
 * holds checkpoint.bin, loss.csv, loss.svg and train.json. A resumed run gives the same
 * weights as an uninterrupted one: each epoch's shuffle is a function of (seed, epoch)
 * and the checkpoint holds the weights, Adam's moments and step and the best so far.
 * model and model.train/ may not be the dataset's files nor lie among its samples. */
wv_status wv_train(const char *dir, const char *model, const wv_train_opts *o, wv_train_result *res, wv_error *err);

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
#define WV_DATASET_VERSION 2 /* 1: the five earlier patterns; 2: every built-in, "augment" */
typedef struct {
  int version;  /* 1 or 2: which patterns the samples cycle through (wv_dataset_pattern) */
  int renderer; /* WV_RENDER_VERSION of the renderer that made the samples */
  int augment;  /* 1: images pass through wv_camera_augment (version 2 only) */
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
/* The patterns a dataset cycles through: version 1 the five of wv_net_pattern, version 2
 * every canonical built-in (wv_weave_builtin_name). */
int wv_dataset_pattern_count(const wv_dataset_info *info);
const char *wv_dataset_pattern(const wv_dataset_info *info, int i);
/* Sample k (0 .. n per_pattern - 1, n patterns) interleaves the patterns: pattern k % n,
 * index k / n. */
void wv_dataset_sample_name(const wv_dataset_info *info, int k, char *buf, size_t cap);
/* The prior draw of sample k (deterministic in the dataset seed). */
wv_status wv_dataset_sample_params(const wv_dataset_info *info, int k, wv_params *p, wv_error *err);
/* Path of one of a sample's files: ext "json", "png" or "feat". */
void wv_dataset_path(const char *dir, const wv_dataset_info *info, int k, const char *ext, char *buf, size_t cap);
/* 1 when the sample's three files are complete. */
int wv_dataset_sample_done(const char *dir, const wv_dataset_info *info, int k);
/* Makes sample k in dir (whose samples/ exists): the prior draw rendered at info's
 * spp with render_threads (0 = all) and the footprints fp (made for info's scene,
 * or NULL), passed through the camera augmentation when info->augment (else only
 * quantised to 8 bits as a photo arrives), then its parameter file, PNG and, last,
 * its features computed by d into feat (n_feat floats of scratch). */
struct wv_descriptor;
struct wv_footprints;
wv_status wv_dataset_make_sample(const char *dir, const wv_dataset_info *info, int k, int render_threads,
                                 const struct wv_footprints *fp, struct wv_descriptor *d, float *feat,
                                 wv_error *err);
/* What a real camera adds to a render, drawn from seed (docs/fabricnet.md, "Camera
 * augmentation"): on the linear radiance, glint speckle, defocus blur, exposure and
 * white-balance gains and signal-dependent sensor noise; then the scene's response,
 * 8-bit quantisation and, most of the time, a JPEG round trip. capture is allocated here
 * (the scene's image, 8-bit values). The same seed gives the same image. */
wv_status wv_camera_augment(const wv_scene *s, const wv_image *radiance, uint64_t seed, wv_image *capture,
                            wv_error *err);

/* Building a dataset (woven dataset): resumable, shared over the ranks of dist. */
typedef struct {
  const char *scene;       /* a scene file or preset name */
  const char *dir;         /* DIR: dataset.json and samples/ */
  int per_pattern;         /* samples per pattern (1..WV_DATASET_MAX_PER_PATTERN) */
  uint64_t seed;           /* 1 */
  int spp;                 /* 0: the scene's */
  int augment;             /* 1: the camera augmentation */
  int jobs;                /* samples rendered at once, one thread each (0: all cores) */
  const char *descriptor;  /* "default" */
  const char *weights;     /* the descriptor's weights file, or NULL */
  /* Optional, called on rank 0 only: a line for the user (no newline), and progress
   * after each sample (samples done of todo, seconds since rendering began); a non-zero
   * return stops the build once the samples in flight are done (res->stopped). */
  void (*on_note)(void *user, const char *text);
  int (*on_progress)(void *user, int done, int todo, double seconds);
  void *user;
} wv_dataset_build_opts;
void wv_dataset_build_opts_default(wv_dataset_build_opts *o);
typedef struct {
  int samples, done_before, rendered; /* rendered: by every rank */
  int spp, width, height, jobs;
  int per_pattern; /* as recorded: a larger earlier size is kept */
  int stopped;     /* on_progress stopped the build: run it again to finish */
  double seconds;
} wv_dataset_build_result;
/* Renders the samples of dir that are not done (the dataset grows in place: inputs may
 * not be its files). Rank 0 holds the directory's lock and writes dataset.json before
 * any sample; a directory made with other settings is refused. Every rank calls it;
 * a rank whose own step succeeded returns the failure of another with an empty message. */
wv_status wv_dataset_build(const wv_dist *dist, const wv_dataset_build_opts *o, wv_dataset_build_result *res,
                           wv_error *err);

/* Features as f16 (n_feat values) with a header (magic, count, CRC). */
wv_status wv_dataset_write_features(const char *path, const float *x, int n, wv_error *err);
wv_status wv_dataset_read_features(const char *path, int n, uint16_t *out, wv_error *err);

#endif
