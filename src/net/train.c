/* woven: FabricNet training (wv_train): loads a dataset made by wv_dataset_make_sample,
 * splits it, runs Adam epochs on the L1 of the 21 outputs plus the pattern head's
 * cross-entropy, keeps the best epoch as the model and checkpoints so that a resumed run
 * equals an uninterrupted one. The loss curve (loss.csv, loss.svg) and train.json go to
 * MODEL.train/. */
#include <errno.h>
#include <jansson.h>
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "util/hash.h"
#include "woven/dataset.h"
#include "woven/io.h"
#include "woven/nn.h"
#include "woven/train.h"
#include "woven/weave.h"

void wv_train_opts_default(wv_train_opts *o) {
  memset(o, 0, sizeof *o);
  o->epochs = 60;
  o->batch = 32;
  o->lr = 1e-4;
  o->val_frac = 0.1;
  o->seed = 1;
  o->checkpoint_every = 1;
  o->ce_weight = WV_NET_CE_WEIGHT;
}

/* A training curve: train and validation L1 per epoch, log scale. */
static wv_status write_loss_svg(const char *path, const wv_train_epoch *r, int n, wv_error *err) {
  size_t cap = 4096 + (size_t)n * 64;
  char *b = malloc(cap);
  if (!b) return wv_fail(err, WV_ERR_NOMEM, "out of memory for %s", path);
  const int W = 640, H = 300, L = 60, R = 120, T = 20, B = 40;
  double lo = INFINITY, hi = -INFINITY;
  for (int i = 0; i < n; i++) {
    lo = fmin(lo, fmin(r[i].train, r[i].val)), hi = fmax(hi, fmax(r[i].train, r[i].val));
  }
  if (n == 0 || !(lo > 0) || !(lo < hi)) lo = 0.01, hi = 1;
  double llo = floor(log10(lo) * 4) / 4, lhi = ceil(log10(hi) * 4) / 4;
  if (lhi <= llo) lhi = llo + 0.25;
  double pw = W - L - R, ph = H - T - B;
  size_t k = 0;
  k += (size_t)snprintf(b + k, cap - k,
                        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" font-family=\"sans-serif\" "
                        "font-size=\"12\">\n<rect width=\"100%%\" height=\"100%%\" fill=\"white\"/>\n"
                        "<rect x=\"%d\" y=\"%d\" width=\"%g\" height=\"%g\" fill=\"none\" stroke=\"#888\"/>\n",
                        W, H, L, T, pw, ph);
  for (double e = llo; e <= lhi + 1e-9; e += 0.25) {
    double y = T + ph * (1 - (e - llo) / (lhi - llo));
    k += (size_t)snprintf(b + k, cap - k, "<text x=\"%d\" y=\"%.1f\" text-anchor=\"end\">%.3g</text>\n", L - 5,
                          y + 4, pow(10, e));
  }
  k += (size_t)snprintf(b + k, cap - k,
                        "<text x=\"%g\" y=\"%d\" text-anchor=\"middle\">epoch (1..%d), L1 on normalised parameters</text>\n",
                        L + pw / 2, H - 10, n);
  static const char *names[2] = {"train", "validation"}, *colours[2] = {"#1f77b4", "#d62728"};
  for (int s = 0; s < 2; s++) {
    k += (size_t)snprintf(b + k, cap - k, "<polyline fill=\"none\" stroke=\"%s\" stroke-width=\"1.5\" points=\"",
                          colours[s]);
    for (int i = 0; i < n; i++) {
      double v = s ? r[i].val : r[i].train;
      double x = L + pw * (n > 1 ? (double)i / (n - 1) : 0.5), y = T + ph * (1 - (log10(v) - llo) / (lhi - llo));
      k += (size_t)snprintf(b + k, cap - k, "%.1f,%.1f ", x, y);
    }
    k += (size_t)snprintf(b + k, cap - k,
                          "\"/>\n<line x1=\"%g\" x2=\"%g\" y1=\"%d\" y2=\"%d\" stroke=\"%s\" stroke-width=\"2\"/>"
                          "<text x=\"%g\" y=\"%d\">%s</text>\n",
                          L + pw + 10, L + pw + 30, T + 15 + 18 * s, T + 15 + 18 * s, colours[s], L + pw + 35,
                          T + 19 + 18 * s, names[s]);
  }
  k += (size_t)snprintf(b + k, cap - k, "</svg>\n");
  wv_status st = wv_write_file_atomic(path, b, k, err);
  free(b);
  return st;
}

static wv_status write_loss_csv(const char *path, const wv_train_epoch *r, int n, wv_error *err) {
  size_t cap = 128 + (size_t)n * 96;
  char *b = malloc(cap);
  if (!b) return wv_fail(err, WV_ERR_NOMEM, "out of memory for %s", path);
  size_t k = (size_t)snprintf(b, cap, "epoch,train_l1,val_l1,train_ce,val_ce,val_pattern_accuracy\n");
  for (int i = 0; i < n; i++)
    k += (size_t)snprintf(b + k, cap - k, "%d,%.6f,%.6f,%.6f,%.6f,%.4f\n", r[i].epoch, r[i].train, r[i].val,
                          r[i].train_ce, r[i].val_ce, r[i].val_acc);
  wv_status st = wv_write_file_atomic(path, b, k, err);
  free(b);
  return st;
}

/* Rows of loss.csv up to epoch 'upto' (a resume keeps the history the checkpoint covers).
 * Files of earlier versions hold only the first three columns. */
static int read_loss_csv(const char *path, wv_train_epoch *r, int upto) {
  FILE *f;
  wv_error ignored;
  if (wv_fopen_regular(path, &f, &ignored)) return 0;
  char line[256];
  int n = 0;
  while (fgets(line, sizeof line, f) && n < upto) {
    wv_train_epoch e;
    memset(&e, 0, sizeof e);
    if (sscanf(line, "%d,%lf,%lf,%lf,%lf,%lf", &e.epoch, &e.train, &e.val, &e.train_ce, &e.val_ce, &e.val_acc) >= 3 &&
        e.epoch == n + 1)
      r[n++] = e;
  }
  fclose(f);
  return n;
}

/* Everything a run holds: the loaded set and the network's training state. */
typedef struct {
  int n_feat;
  uint16_t *feat;  /* n samples x n_feat, f16 */
  int n_out;       /* targets per sample: WV_NET_OUT, or WV_NET_OUT_PAIR for a pair set */
  float *targets;  /* n x n_out */
  int *labels;     /* n: index of the sample's pattern among the built-ins */
  float *x, *y;    /* one batch */
  int *lab;        /* one batch's labels */
  wv_fabricnet_acts acts;
} trainset;

static void make_batch(const wv_fabricnet *net, const trainset *t, const int *idx, int nb) {
  for (int b = 0; b < nb; b++) {
    const uint16_t *src = t->feat + (size_t)idx[b] * net->n_in;
    float *dst = t->x + (size_t)b * net->n_in;
    for (int i = 0; i < net->n_in; i++) dst[i] = wv_nn_f16_to_f32(src[i]);
    memcpy(t->y + (size_t)b * t->n_out, t->targets + (size_t)idx[b] * t->n_out, (size_t)t->n_out * sizeof(float));
    t->lab[b] = t->labels[idx[b]];
  }
  wv_fabricnet_preprocess(net, t->x, nb);
}

/* Mean L1 over a set, per output (err_out, may be NULL), the pattern head's mean
 * cross-entropy and its accuracy (the most probable pattern is the sample's). */
static double evaluate(const wv_fabricnet *net, trainset *t, const int *idx, int n, int batch, double *err_out,
                       double *ce_out, double *acc_out) {
  double s = 0, per[WV_NET_OUT_MAX] = {0}, ce = 0;
  const int no = t->n_out;
  int right = 0;
  wv_fabricnet_acts *a = &t->acts;
  for (int i = 0; i < n; i += batch) {
    int nb = n - i < batch ? n - i : batch;
    make_batch(net, t, idx + i, nb);
    wv_fabricnet_forward(net, t->x, nb, a);
    for (int j = 0; j < nb * no; j++) {
      double d = fabs((double)a->out[j] - t->y[j]);
      s += d, per[j % no] += d;
    }
    if (net->n_cls > 0) {
      ce += (double)wv_nn_softmax_xent_forward(NULL, a->logits, t->lab, nb, net->n_cls) * nb;
      for (int b = 0; b < nb; b++) {
        const float *p = a->prob + (size_t)b * net->n_cls;
        int best = 0;
        for (int k = 1; k < net->n_cls; k++) best = p[k] > p[best] ? k : best;
        right += best == t->lab[b];
      }
    }
  }
  if (err_out)
    for (int k = 0; k < no; k++) err_out[k] = n ? per[k] / n : 0;
  if (ce_out) *ce_out = n ? ce / n : 0;
  if (acc_out) *acc_out = n ? (double)right / n : 0;
  return n ? s / ((double)n * no) : 0;
}

/* The model file: net, its pattern head mixed with the starting one (start: w4 then b4) when
 * w > 0. The trained head is put back after: training and the checkpoint go on from it. The
 * head's two tensors are contiguous, as every tensor is (one block, wv_fabricnet_tensors order). */
static wv_status save_model(const char *path, wv_fabricnet *net, const float *start, double w, wv_error *err) {
  if (!(w > 0)) return wv_fabricnet_save(path, net, err);
  float *t[WV_NET_TENSORS];
  size_t len[WV_NET_TENSORS];
  wv_fabricnet_tensors(net, t, len);
  float *head = t[WV_NET_HEAD_W];
  size_t nh = len[WV_NET_HEAD_W] + len[WV_NET_HEAD_W + 1];
  float *kept = malloc(sizeof(float) * nh);
  if (!kept) return wv_fail(err, WV_ERR_NOMEM, "out of memory for the pattern head");
  memcpy(kept, head, sizeof(float) * nh);
  for (size_t j = 0; j < nh; j++) head[j] = (float)((1 - w) * kept[j] + w * start[j]);
  wv_status st = wv_fabricnet_save(path, net, err);
  memcpy(head, kept, sizeof(float) * nh);
  free(kept);
  return st;
}

/* The built-in index of a pattern name (earlier names map to their canonical one). */
static int pattern_label(const char *name) {
  const char *c = wv_weave_canonical(name);
  for (int i = 0; c && i < wv_weave_builtin_count(); i++)
    if (!strcmp(c, wv_weave_builtin_name(i))) return i;
  return -1;
}

wv_status wv_train(const char *dir, const char *model, const wv_train_opts *o, wv_train_result *res, wv_error *err) {
  memset(res, 0, sizeof *res);
  if (o->epochs < 1 || o->batch < 1 || o->batch > 4096 || !(o->lr > 0 && o->lr < 1) ||
      !(o->val_frac > 0 && o->val_frac < 0.9) || o->checkpoint_every < 1 || !(o->ce_weight >= 0))
    return wv_fail(err, WV_ERR_INVALID, "training options out of range (epochs >= 1, batch 1..4096, lr in (0, 1), "
                                        "validation fraction in (0, 0.9), checkpoint interval >= 1, CE weight >= 0)");
  if (o->resume && o->force) return wv_fail(err, WV_ERR_INVALID, "resume and force exclude each other");
  if (o->pattern_head_only && !o->init && !o->resume)
    return wv_fail(err, WV_ERR_INVALID, "training the pattern head alone needs a model to start from (init or resume)");
  if (!(o->head_start_weight >= 0 && o->head_start_weight < 1))
    return wv_fail(err, WV_ERR_INVALID, "the starting head's weight %g is outside [0, 1)", o->head_start_weight);
  if (o->head_start_weight > 0 && (!o->pattern_head_only || !o->init || o->resume))
    return wv_fail(err, WV_ERR_INVALID, "mixing the starting pattern head into the trained one needs the pattern head "
                                        "trained alone from a model given to start from (init, not resume)");
  char work[4096], ckpt[4096], path[4096];
  snprintf(work, sizeof work, "%s.train", model);
  { /* model and model.train/ must not land on the dataset's files */
    char ds[2][4096];
    snprintf(ds[0], sizeof ds[0], "%s/dataset.json", dir);
    snprintf(ds[1], sizeof ds[1], "%s/samples", dir);
    const char *outs[2] = {model, work}, *in = ds[0];
    for (int i = 0; i < 2; i++) {
      wv_status cs = wv_check_not_input(outs[i], 0, &in, 1, err);
      if (cs) return cs;
      if (wv_path_within(outs[i], ds[1]))
        return wv_fail(err, WV_ERR_INVALID, "%s lies inside the dataset's samples directory %s; write the model elsewhere",
                       outs[i], ds[1]);
    }
    wv_remove_stale_temps_beside(model);
    wv_remove_stale_temps(work, NULL);
  }
  wv_dataset_info info;
  wv_status st = wv_dataset_info_read(dir, &info, err);
  if (st) return st;
  snprintf(ckpt, sizeof ckpt, "%s/checkpoint.bin", work);
  struct stat sb;
  if (!o->resume && !o->force && stat(ckpt, &sb) == 0)
    return wv_fail(err, WV_ERR_IO, "%s holds a checkpoint of an earlier run; continue it (--resume) or start again (--force)", ckpt);
  if (o->resume && stat(ckpt, &sb) != 0) return wv_fail(err, WV_ERR_IO, "--resume: no checkpoint at %s", ckpt);

  /* Load every finished sample; a partial dataset needs o->partial. */
  int np = wv_dataset_pattern_count(&info), total = np * info.per_pattern, n = 0, missing = 0, first_missing = -1;
  trainset t;
  memset(&t, 0, sizeof t);
  t.n_feat = info.n_feat;
  t.n_out = info.pair ? WV_NET_OUT_PAIR : WV_NET_OUT;
  res->outputs = t.n_out;
  t.feat = malloc(sizeof(uint16_t) * (size_t)total * info.n_feat);
  t.targets = malloc(sizeof(float) * (size_t)total * t.n_out);
  t.labels = malloc(sizeof(int) * (size_t)total);
  int *ids = malloc(sizeof(int) * (size_t)total);
  if (!t.feat || !t.targets || !t.labels || !ids) st = wv_fail(err, WV_ERR_NOMEM, "out of memory for %d samples", total);
  double t_load = omp_get_wtime();
  for (int k = 0; k < total && !st; k++) {
    char ppath[4096];
    wv_dataset_path(dir, &info, k, "feat", path, sizeof path);
    wv_dataset_path(dir, &info, k, "json", ppath, sizeof ppath);
    wv_params p;
    if (stat(path, &sb) != 0 || stat(ppath, &sb) != 0) {
      if (first_missing < 0) first_missing = k;
      missing++;
      continue;
    }
    if ((st = wv_dataset_read_features(path, info.n_feat, t.feat + (size_t)n * info.n_feat, err)) ||
        (st = wv_params_read(ppath, &p, err)))
      break;
    if (strcmp(p.pattern, wv_dataset_pattern(&info, k % np))) {
      st = wv_fail(err, WV_ERR_FORMAT, "%s: pattern '%s' where the dataset has '%s'", ppath, p.pattern,
                   wv_dataset_pattern(&info, k % np));
      break;
    }
    if ((t.labels[n] = pattern_label(p.pattern)) < 0) {
      st = wv_fail(err, WV_ERR_FORMAT, "%s: pattern '%s' is not a built-in", ppath, p.pattern);
      break;
    }
    wv_fabricnet_targets(&p, t.n_out, t.targets + (size_t)n * t.n_out);
    ids[n++] = k;
  }
  if (!st && missing && !o->partial) {
    char name[64];
    wv_dataset_sample_name(&info, first_missing, name, sizeof name);
    st = wv_fail(err, WV_ERR_INVALID,
                 "%s is partial: %d of %d samples missing (first: %s); finish it by running the same "
                 "'woven dataset' command again, or train on the finished ones (--partial)",
                 dir, missing, total, name);
  }
  /* Split by a hash of the sample, so the split does not change when the set grows. */
  int *tr = st ? NULL : malloc(sizeof(int) * (size_t)(n + 1)), *va = st ? NULL : malloc(sizeof(int) * (size_t)(n + 1));
  int ntr = 0, nva = 0;
  if (!st && (!tr || !va)) st = wv_fail(err, WV_ERR_NOMEM, "out of memory for the split");
  if (!st) {
    for (int i = 0; i < n; i++) {
      double u = wv_u01d(wv_hash4(info.seed, (uint64_t)ids[i], 0x76616c, 0));
      if (u < o->val_frac)
        va[nva++] = i;
      else
        tr[ntr++] = i;
    }
    if (ntr < 1 || nva < 1)
      st = wv_fail(err, WV_ERR_INVALID, "%s: %d samples are too few for a training and a validation split", dir, n);
  }
  res->samples = n, res->train = ntr, res->validation = nva, res->missing = missing;
  res->load_seconds = omp_get_wtime() - t_load;

  wv_fabricnet net;
  memset(&net, 0, sizeof net);
  wv_fabricnet_trainstate ts = {0, 0, 0, INFINITY, 0};
  float *am = NULL, *av = NULL;
  float *start_head = NULL; /* the starting model's w4 then b4, to mix into the trained head */
  wv_train_epoch *hist = st ? NULL : calloc((size_t)o->epochs + 1, sizeof *hist);
  int nhist = 0;
  if (!st && !hist) st = wv_fail(err, WV_ERR_NOMEM, "out of memory for the loss history");
  if (!st && o->resume) {
    if (!(st = wv_fabricnet_checkpoint_load(ckpt, &net, &am, &av, &ts, err)) &&
        !(st = wv_fabricnet_check(&net, ckpt, info.descriptor, (size_t)info.n_feat, &info.scene, err)) &&
        !(st = wv_fabricnet_check_pair(&net, ckpt, info.pair ? &info.tscene : NULL, err))) {
      snprintf(path, sizeof path, "%s/loss.csv", work);
      int upto = ts.epoch < o->epochs ? ts.epoch : o->epochs;
      nhist = read_loss_csv(path, hist, upto);
      res->resumed_epoch = ts.epoch;
    }
  } else if (!st && o->init &&
             !(st = wv_fabricnet_init(&net, info.descriptor, info.n_feat, &info.scene, info.pair ? &info.tscene : NULL,
                                      o->seed, err))) {
    /* Fine-tuning: the given model's layers and feature statistics; a pattern head it
     * lacks (a version 1 model) keeps its fresh initialisation. */
    wv_fabricnet from;
    if (!(st = wv_fabricnet_load(o->init, &from, err)) &&
        !(st = wv_fabricnet_check(&from, o->init, info.descriptor, (size_t)info.n_feat, &info.scene, err)) &&
        !(st = wv_fabricnet_check_pair(&from, o->init, info.pair ? &info.tscene : NULL, err))) {
      float *tf[WV_NET_TENSORS], *tn[WV_NET_TENSORS];
      size_t lf[WV_NET_TENSORS], ln[WV_NET_TENSORS];
      wv_fabricnet_tensors(&from, tf, lf);
      wv_fabricnet_tensors(&net, tn, ln);
      for (int i = 0; i < WV_NET_TENSORS; i++)
        if (lf[i] == ln[i] && lf[i]) memcpy(tn[i], tf[i], sizeof(float) * ln[i]);
      memcpy(net.mean, from.mean, sizeof(float) * (size_t)info.n_feat);
      memcpy(net.std, from.std, sizeof(float) * (size_t)info.n_feat);
      memcpy(net.range, from.range, sizeof net.range);
      if (o->head_start_weight > 0 && lf[WV_NET_HEAD_W] == ln[WV_NET_HEAD_W] && ln[WV_NET_HEAD_W]) {
        size_t nh = ln[WV_NET_HEAD_W] + ln[WV_NET_HEAD_W + 1];
        if (!(start_head = malloc(sizeof(float) * nh))) st = wv_fail(err, WV_ERR_NOMEM, "out of memory for the head");
        else memcpy(start_head, tf[WV_NET_HEAD_W], sizeof(float) * nh); /* w4 then b4, contiguous */
      }
      wv_fabricnet_free(&from);
    }
  } else if (!st && !o->init &&
             !(st = wv_fabricnet_init(&net, info.descriptor, info.n_feat, &info.scene, info.pair ? &info.tscene : NULL,
                                      o->seed, err))) {
    /* Feature statistics over the training split, after the signed log1p. */
    double *s1 = calloc((size_t)info.n_feat, sizeof(double)), *s2 = calloc((size_t)info.n_feat, sizeof(double));
    if (!s1 || !s2) st = wv_fail(err, WV_ERR_NOMEM, "out of memory for feature statistics");
    for (int i = 0; i < ntr && !st; i++) {
      const uint16_t *f = t.feat + (size_t)tr[i] * info.n_feat;
      for (int j = 0; j < info.n_feat; j++) {
        double v = wv_nn_f16_to_f32(f[j]), l = v < 0 ? -log1p(-v) : log1p(v);
        s1[j] += l, s2[j] += l * l;
      }
    }
    double mean_sd = 0;
    for (int j = 0; j < info.n_feat && !st; j++) {
      double m = s1[j] / ntr, var = s2[j] / ntr - m * m;
      net.mean[j] = (float)m;
      s2[j] = sqrt(fmax(var, 0));
      mean_sd += s2[j] / info.n_feat;
    }
    /* a floor (a tenth of the average spread) keeps near-constant features from
     * turning rounding and render noise into large inputs */
    for (int j = 0; j < info.n_feat && !st; j++) net.std[j] = (float)fmax(s2[j], fmax(0.1 * mean_sd, 1e-6));
    free(s1), free(s2);
  }
  if (!st && o->pattern_head_only && net.n_cls < 1)
    st = wv_fail(err, WV_ERR_INVALID, "%s has no pattern head to train", o->init ? o->init : ckpt);
  if (!st && o->head_start_weight > 0 && !start_head)
    st = wv_fail(err, WV_ERR_INVALID, "%s has no pattern head to mix into the trained one", o->init);
  if (!st && mkdir(work, 0777) != 0 && errno != EEXIST)
    st = wv_fail(err, WV_ERR_IO, "%s: cannot create directory: %s", work, strerror(errno));
  if (!st) {
    snprintf(path, sizeof path, "%s/train.json", work);
    json_t *tj = json_pack("{s:s,s:s,s:i,s:i,s:i,s:f,s:i,s:f,s:f,s:I,s:i,s:b,s:f}", "kind", "woven-train", "dataset", dir,
                           "samples", n, "train", ntr, "validation", nva, "val_frac", o->val_frac, "batch", o->batch,
                           "lr", o->lr, "ce_weight", o->ce_weight, "seed", (json_int_t)o->seed, "epochs", o->epochs,
                           "pattern_head_only", o->pattern_head_only, "head_start_weight", o->head_start_weight);
    char *text = tj ? json_dumps(tj, JSON_PRESERVE_ORDER | JSON_REAL_PRECISION(15)) : NULL;
    json_decref(tj);
    size_t len = text ? strlen(text) : 0;
    char *tl = text ? realloc(text, len + 2) : NULL;
    if (!tl) {
      free(text);
      st = wv_fail(err, WV_ERR_NOMEM, "out of memory for train.json");
    } else {
      tl[len] = '\n', tl[len + 1] = '\0';
      st = wv_write_file_atomic(path, tl, len + 1, err);
      free(tl);
    }
  }
  size_t P = st ? 0 : wv_fabricnet_param_count(&net);
  float *grad = st ? NULL : calloc(P, sizeof(float));
  t.x = st ? NULL : malloc(sizeof(float) * (size_t)o->batch * info.n_feat);
  t.y = st ? NULL : malloc(sizeof(float) * (size_t)o->batch * t.n_out);
  t.lab = st ? NULL : malloc(sizeof(int) * (size_t)o->batch);
  int *order = st ? NULL : malloc(sizeof(int) * (size_t)ntr);
  if (!st && (!grad || !t.x || !t.y || !t.lab || !order)) st = wv_fail(err, WV_ERR_NOMEM, "out of memory for training");
  if (!st) st = wv_fabricnet_acts_alloc(&t.acts, o->batch, err);
  wv_nn_adam adam = {0};
  if (!st) st = wv_nn_adam_init(&adam, P, (float)o->lr, err);
  if (!st && am) { /* the checkpoint's moments */
    memcpy(adam.m, am, P * sizeof(float));
    memcpy(adam.v, av, P * sizeof(float));
    adam.t = ts.adam_t;
  }
  /* The weight arrays are one contiguous block starting at w1 (wv_fabricnet_tensors). */
  float *gt[WV_NET_TENSORS];
  if (!st) {
    size_t off = 0;
    float *tt[WV_NET_TENSORS];
    size_t len[WV_NET_TENSORS];
    wv_fabricnet_tensors(&net, tt, len);
    for (int i = 0; i < WV_NET_TENSORS; i++) gt[i] = grad + off, off += len[i];
  }
  if (!st && o->on_start) o->on_start(o->user, res);
  double t0 = omp_get_wtime();
  int start_epoch = ts.epoch;
  for (int ep = ts.epoch; ep < o->epochs && !st; ep++) {
    /* Shuffle with a stream that depends on (seed, epoch) only: resuming repeats it. */
    wv_rng r;
    wv_rng_seed(&r, wv_hash4(o->seed, (uint64_t)ep, 0x73687566, 0));
    for (int i = 0; i < ntr; i++) order[i] = tr[i];
    for (int i = ntr - 1; i > 0; i--) {
      int j = (int)(wv_rng_u64(&r) % (uint64_t)(i + 1)), tmp = order[i];
      order[i] = order[j], order[j] = tmp;
    }
    double sum = 0, sum_ce = 0;
    int nb_total = 0;
    for (int i = 0; i < ntr; i += o->batch) {
      int nb = ntr - i < o->batch ? ntr - i : o->batch;
      make_batch(&net, &t, order + i, nb);
      memset(grad, 0, P * sizeof(float));
      float l1, ce;
      wv_fabricnet_backward(&net, t.x, t.y, t.lab, (float)o->ce_weight, nb, &t.acts, gt, &l1, &ce);
      /* Adam moves no weight whose gradient has always been 0 (its moments stay 0) */
      if (o->pattern_head_only) memset(grad, 0, (size_t)(gt[WV_NET_HEAD_W] - grad) * sizeof(float));
      sum += (double)l1 * nb, sum_ce += (double)ce * nb;
      nb_total += nb;
      wv_nn_adam_step(&adam, net.w1, grad);
      if (o->on_progress) o->on_progress(o->user, (ep - start_epoch + (double)(i + nb) / ntr) / (o->epochs - start_epoch));
    }
    wv_train_epoch e = {ep + 1, sum / nb_total, 0, sum_ce / nb_total, 0, 0, 0, 0};
    e.val = evaluate(&net, &t, va, nva, o->batch, NULL, &e.val_ce, &e.val_acc);
    ts.epoch = ep + 1, ts.adam_t = adam.t;
    /* MODEL always holds the best epoch so far, by the validation loss that training minimises */
    double crit = e.val + (net.n_cls > 0 ? o->ce_weight * e.val_ce : 0);
    if (crit < ts.best_val) {
      ts.best_val = (float)crit, ts.best_epoch = ep + 1, e.best = 1;
      st = save_model(model, &net, start_head, o->head_start_weight, err);
    }
    e.seconds = omp_get_wtime() - t0;
    hist[nhist++] = e;
    snprintf(path, sizeof path, "%s/loss.csv", work);
    if (!st) st = write_loss_csv(path, hist, nhist, err);
    snprintf(path, sizeof path, "%s/loss.svg", work);
    if (!st) st = write_loss_svg(path, hist, nhist, err);
    if (!st && ((ep + 1) % o->checkpoint_every == 0 || ep + 1 == o->epochs))
      st = wv_fabricnet_checkpoint_save(ckpt, &net, adam.m, adam.v, &ts, err);
    if (!st && o->on_epoch) o->on_epoch(o->user, &e);
  }
  res->seconds = omp_get_wtime() - t0;
  res->epochs_run = ts.epoch - start_epoch;
  res->epochs = ts.epoch;
  res->best_epoch = ts.best_epoch;
  res->best_val = ts.best_val;
  res->final_train = nhist ? hist[nhist - 1].train : 0;
  if (!st) {
    /* The saved model (the best epoch, f16 weights) on the validation split. */
    wv_fabricnet best;
    if (!(st = wv_fabricnet_load(model, &best, err))) {
      res->val_f16 = evaluate(&best, &t, va, nva, o->batch, res->val_per_output, &res->val_ce, &res->val_accuracy);
      wv_fabricnet_free(&best);
    }
  }
  wv_nn_adam_free(&adam);
  wv_fabricnet_acts_free(&t.acts);
  wv_fabricnet_free(&net);
  free(am), free(av), free(start_head), free(grad), free(order), free(hist), free(tr), free(va);
  free(t.x), free(t.y), free(t.lab), free(t.feat), free(t.targets), free(t.labels), free(ids);
  return st;
}
