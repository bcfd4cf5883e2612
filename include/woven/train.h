/* woven: FabricNet's training (docs/fabricnet.md, "woven train"): Adam epochs over a
 * dataset (woven/dataset.h), the best epoch kept as the model, and checkpoints (their
 * format is the model file's, woven/fabricnet.h) from which a run resumes. */
#ifndef WOVEN_TRAIN_H
#define WOVEN_TRAIN_H

#include <stdint.h>

#include "woven/error.h"
#include "woven/fabricnet.h"

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
  int outputs;               /* the model's outputs: WV_NET_OUT, or WV_NET_OUT_PAIR for a pair dataset */
  double val_per_output[WV_NET_OUT_MAX];
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
  int pattern_head_only; /* with init or resume: only the pattern head learns; every other weight, and
                          * so every parameter estimate, stays the starting model's */
  double head_start_weight; /* with pattern_head_only and init: the saved pattern head is (1 - w) times the
                             * trained head plus w times the starting model's (weight-space ensembling,
                             * Wortsman et al. 2022, "Robust fine-tuning of zero-shot models"); 0: the
                             * trained head. In [0, 1); not with resume. The checkpoint keeps the trained head. */
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

#endif
