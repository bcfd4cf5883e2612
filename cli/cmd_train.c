/* woven train: FabricNet's fully connected head on a dataset from 'woven dataset'. */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "cli.h"
#include "util/hash.h"
#include "woven/fabricnet.h"
#include "woven/io.h"
#include "woven/nn.h"

static const char *HELP =
    "usage: woven train DIR -o MODEL [--epochs N] [--batch N] [--lr X] [--val-frac X] [--seed N]\n"
    "                   [--checkpoint-every N] [--resume | --force] [--partial] [--quiet] [--json]\n"
    "\n"
    "Trains FabricNet (SPEC section 7: features -> 256 -> LeakyReLU -> 256 -> LeakyReLU -> 21 ->\n"
    "sigmoid; L1 loss on normalised parameters; Adam) on the dataset in DIR.\n"
    "  --epochs N            total epochs (default 60)\n"
    "  --batch N             batch size (default 32)\n"
    "  --lr X                Adam learning rate (default 1e-4)\n"
    "  --val-frac X          held-out validation fraction (default 0.1, chosen by a hash of the sample)\n"
    "  --checkpoint-every N  epochs between checkpoints (default 1)\n"
    "  --resume              continue from MODEL.train/checkpoint.bin\n"
    "  --force               start again even if MODEL.train/ holds a checkpoint\n"
    "  --partial             train on the finished samples of an incomplete dataset\n"
    "MODEL receives the weights of the epoch with the lowest validation loss (f16, docs/fabricnet.md).\n"
    "MODEL.train/ holds checkpoint.bin, loss.csv, loss.svg and train.json.\n";

typedef struct {
  int epoch;
  double train, val;
} epoch_rec;

/* A training curve: train and validation L1 per epoch, log scale. */
static wv_status write_loss_svg(const char *path, const epoch_rec *r, int n, wv_error *err) {
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

static wv_status write_loss_csv(const char *path, const epoch_rec *r, int n, wv_error *err) {
  size_t cap = 64 + (size_t)n * 64;
  char *b = malloc(cap);
  if (!b) return wv_fail(err, WV_ERR_NOMEM, "out of memory for %s", path);
  size_t k = (size_t)snprintf(b, cap, "epoch,train_l1,val_l1\n");
  for (int i = 0; i < n; i++) k += (size_t)snprintf(b + k, cap - k, "%d,%.6f,%.6f\n", r[i].epoch, r[i].train, r[i].val);
  wv_status st = wv_write_file_atomic(path, b, k, err);
  free(b);
  return st;
}

/* Rows of loss.csv up to epoch 'upto' (a resume keeps the history the checkpoint covers). */
static int read_loss_csv(const char *path, epoch_rec *r, int upto) {
  FILE *f = fopen(path, "r");
  if (!f) return 0;
  char line[256];
  int n = 0;
  while (fgets(line, sizeof line, f) && n < upto) {
    epoch_rec e;
    if (sscanf(line, "%d,%lf,%lf", &e.epoch, &e.train, &e.val) == 3 && e.epoch == n + 1) r[n++] = e;
  }
  fclose(f);
  return n;
}

/* f16 features of a batch -> f32, preprocessed. */
static void make_batch(const wv_fabricnet *net, const uint16_t *feat, const float *targets, const int *idx, int nb,
                       float *x, float *y) {
  for (int b = 0; b < nb; b++) {
    const uint16_t *src = feat + (size_t)idx[b] * net->n_in;
    float *dst = x + (size_t)b * net->n_in;
    for (int i = 0; i < net->n_in; i++) dst[i] = wv_nn_f16_to_f32(src[i]);
    memcpy(y + (size_t)b * WV_NET_OUT, targets + (size_t)idx[b] * WV_NET_OUT, WV_NET_OUT * sizeof(float));
  }
  wv_fabricnet_preprocess(net, x, nb);
}

/* Mean L1 over a set, and per output (err_out, WV_NET_OUT values, may be NULL). */
static double evaluate(const wv_fabricnet *net, const uint16_t *feat, const float *targets, const int *idx, int n,
                       int batch, float *x, float *y, wv_fabricnet_acts *a, double *err_out) {
  double s = 0, per[WV_NET_OUT] = {0};
  for (int i = 0; i < n; i += batch) {
    int nb = n - i < batch ? n - i : batch;
    make_batch(net, feat, targets, idx + i, nb, x, y);
    wv_fabricnet_forward(net, x, nb, a);
    for (int j = 0; j < nb * WV_NET_OUT; j++) {
      double d = fabs((double)a->out[j] - y[j]);
      s += d, per[j % WV_NET_OUT] += d;
    }
  }
  if (err_out)
    for (int k = 0; k < WV_NET_OUT; k++) err_out[k] = n ? per[k] / n : 0;
  return n ? s / ((double)n * WV_NET_OUT) : 0;
}

int cmd_train(int argc, char **argv) {
  cli_ctx c = {0, 0, "train"};
  cli_args a;
  cli_args_init(&a, argc, argv, c.cmd);
  const char *dir = NULL, *model = NULL, *lr_s = NULL, *vf_s = NULL;
  long epochs = 60, batch = 32, seed = 1, ck_every = 1;
  int resume = 0, force = 0, partial = 0;
  for (const char *s; (s = cli_next(&a));) {
    if (!strcmp(s, "--help") || !strcmp(s, "-h")) {
      fputs(HELP, stdout);
      return 0;
    } else if (cli_is(&a, s, "-o") || cli_is(&a, s, "--output")) {
      if (!(model = cli_value(&a, "-o"))) return EXIT_USAGE;
    } else if (cli_is(&a, s, "--epochs")) {
      if (!cli_int(&a, "--epochs", 1, WV_NET_MAX_EPOCHS, &epochs)) return EXIT_USAGE;
    } else if (cli_is(&a, s, "--batch")) {
      if (!cli_int(&a, "--batch", 1, 4096, &batch)) return EXIT_USAGE;
    } else if (cli_is(&a, s, "--seed")) {
      if (!cli_int(&a, "--seed", 0, 2147483647L, &seed)) return EXIT_USAGE;
    } else if (cli_is(&a, s, "--checkpoint-every")) {
      if (!cli_int(&a, "--checkpoint-every", 1, 100000, &ck_every)) return EXIT_USAGE;
    } else if (cli_is(&a, s, "--lr")) {
      if (!(lr_s = cli_value(&a, "--lr"))) return EXIT_USAGE;
    } else if (cli_is(&a, s, "--val-frac")) {
      if (!(vf_s = cli_value(&a, "--val-frac"))) return EXIT_USAGE;
    } else if (!strcmp(s, "--resume")) {
      resume = 1;
    } else if (!strcmp(s, "--force")) {
      force = 1;
    } else if (!strcmp(s, "--partial")) {
      partial = 1;
    } else if (cli_common_flag(&c, s)) {
      /* --quiet, -q, --json */
    } else if (s[0] == '-' && s[1]) {
      return cli_usage_error(c.cmd, "unknown option '%s'", s);
    } else if (!dir) {
      dir = s;
    } else {
      return cli_usage_error(c.cmd, "unexpected argument '%s'", s);
    }
  }
  if (!dir) return cli_usage_error(c.cmd, "a dataset DIR is required");
  if (!model) return cli_usage_error(c.cmd, "-o MODEL is required");
  if (resume && force) return cli_usage_error(c.cmd, "--resume and --force exclude each other");
  double lr = 1e-4, vf = 0.1;
  char *end;
  if (lr_s && (lr = strtod(lr_s, &end), *end || !(lr > 0 && lr < 1)))
    return cli_usage_error(c.cmd, "--lr must be a number in (0, 1)");
  if (vf_s && (vf = strtod(vf_s, &end), *end || !(vf > 0 && vf < 0.9)))
    return cli_usage_error(c.cmd, "--val-frac must be a number in (0, 0.9)");

  wv_error err = {0};
  wv_dataset_info info;
  if (wv_dataset_info_read(dir, &info, &err)) return cli_fail(&c, &err);
  char work[4096], ckpt[4096], path[4096];
  snprintf(work, sizeof work, "%s.train", model);
  snprintf(ckpt, sizeof ckpt, "%s/checkpoint.bin", work);
  { /* MODEL and MODEL.train/ must not land on the dataset's files */
    char ds[2][4096];
    snprintf(ds[0], sizeof ds[0], "%s/dataset.json", dir);
    snprintf(ds[1], sizeof ds[1], "%s/samples", dir);
    const char *outs[2] = {model, work};
    for (int i = 0; i < 2; i++) {
      const char *in = ds[0];
      if (wv_check_not_input(outs[i], 0, &in, 1, &err) ||
          (wv_path_within(outs[i], ds[1]) &&
           wv_fail(&err, WV_ERR_INVALID, "%s lies inside the dataset's samples directory %s; write the model elsewhere",
                   outs[i], ds[1])))
        return cli_fail(&c, &err);
    }
  }
  cli_clean_temps_beside(model);
  wv_remove_stale_temps(work, NULL);
  struct stat sb;
  if (!resume && !force && stat(ckpt, &sb) == 0) {
    fprintf(stderr, "woven train: error: %s holds a checkpoint of an earlier run; use --resume to continue it or "
                    "--force to start again\n", ckpt);
    return WV_ERR_IO;
  }
  if (resume && stat(ckpt, &sb) != 0) {
    fprintf(stderr, "woven train: error: --resume: no checkpoint at %s\n", ckpt);
    return WV_ERR_IO;
  }

  /* Load every finished sample; a partial dataset needs --partial. */
  int total = WV_NET_PATTERNS * info.per_pattern, n = 0, missing = 0, first_missing = -1;
  uint16_t *feat = malloc(sizeof(uint16_t) * (size_t)total * info.n_feat);
  float *targets = malloc(sizeof(float) * (size_t)total * WV_NET_OUT);
  int *ids = malloc(sizeof(int) * (size_t)total);
  int rc = 0;
  if (!feat || !targets || !ids) {
    fprintf(stderr, "woven train: error: out of memory for %d samples\n", total);
    rc = WV_ERR_NOMEM;
  }
  double t_load = cli_now();
  for (int k = 0; k < total && !rc; k++) {
    wv_dataset_path(dir, k, "feat", path, sizeof path);
    char ppath[4096];
    wv_dataset_path(dir, k, "json", ppath, sizeof ppath);
    wv_params p;
    wv_error e;
    if (stat(path, &sb) != 0 || stat(ppath, &sb) != 0) {
      if (first_missing < 0) first_missing = k;
      missing++;
      continue;
    }
    if (wv_dataset_read_features(path, info.n_feat, feat + (size_t)n * info.n_feat, &e) ||
        wv_params_read(ppath, &p, &e)) {
      fprintf(stderr, "woven train: error: %s\n", e.msg);
      rc = e.code;
      break;
    }
    if (strcmp(p.pattern, wv_net_pattern(k % WV_NET_PATTERNS))) {
      fprintf(stderr, "woven train: error: %s: pattern '%s' where the dataset has '%s'\n", ppath, p.pattern,
              wv_net_pattern(k % WV_NET_PATTERNS));
      rc = WV_ERR_FORMAT;
      break;
    }
    wv_fabricnet_targets(&p, targets + (size_t)n * WV_NET_OUT);
    ids[n++] = k;
  }
  if (!rc && missing && !partial) {
    char name[64];
    wv_dataset_sample_name(first_missing, name, sizeof name);
    fprintf(stderr,
            "woven train: error: %s is partial: %d of %d samples missing (first: %s); finish it by running the "
            "same 'woven dataset' command again, or pass --partial\n",
            dir, missing, total, name);
    rc = WV_ERR_INVALID;
  }
  /* Split by a hash of the sample, so the split does not change when the set grows. */
  int *tr = rc ? NULL : malloc(sizeof(int) * (size_t)(n + 1)), *va = rc ? NULL : malloc(sizeof(int) * (size_t)(n + 1));
  int ntr = 0, nva = 0;
  if (!rc && (!tr || !va)) rc = WV_ERR_NOMEM;
  if (!rc) {
    for (int i = 0; i < n; i++) {
      double u = wv_u01d(wv_hash4(info.seed, (uint64_t)ids[i], 0x76616c, 0));
      if (u < vf)
        va[nva++] = i;
      else
        tr[ntr++] = i;
    }
    if (ntr < 1 || nva < 1) {
      fprintf(stderr, "woven train: error: %s: %d samples are too few for a training and a validation split\n", dir, n);
      rc = WV_ERR_INVALID;
    }
  }
  if (!rc)
    cli_info(&c, "%s: %d samples loaded in %.1f s (%d train, %d validation)%s\n", dir, n, cli_now() - t_load, ntr, nva,
             missing ? " [partial]" : "");

  wv_fabricnet net;
  memset(&net, 0, sizeof net);
  wv_fabricnet_trainstate ts = {0, 0, 0, INFINITY, 0};
  float *am = NULL, *av = NULL;
  epoch_rec *hist = rc ? NULL : calloc((size_t)epochs + 1, sizeof *hist);
  int nhist = 0;
  if (!rc && !hist) rc = WV_ERR_NOMEM;
  if (!rc && resume) {
    if (wv_fabricnet_checkpoint_load(ckpt, &net, &am, &av, &ts, &err)) {
      rc = cli_fail(&c, &err);
    } else if (wv_fabricnet_check(&net, ckpt, info.descriptor, (size_t)info.n_feat, &info.scene, &err)) {
      rc = cli_fail(&c, &err);
    } else {
      snprintf(path, sizeof path, "%s/loss.csv", work);
      int upto = ts.epoch < epochs ? ts.epoch : (int)epochs;
      nhist = read_loss_csv(path, hist, upto);
      cli_info(&c, "resuming %s at epoch %d (best validation %.5f at epoch %d)\n", ckpt, ts.epoch, ts.best_val,
               ts.best_epoch);
    }
  } else if (!rc) {
    if (wv_fabricnet_init(&net, info.descriptor, info.n_feat, &info.scene, (uint64_t)seed, &err)) {
      rc = cli_fail(&c, &err);
    } else {
      /* Feature statistics over the training split, after the signed log1p. */
      double *s1 = calloc((size_t)info.n_feat, sizeof(double)), *s2 = calloc((size_t)info.n_feat, sizeof(double));
      if (!s1 || !s2) rc = WV_ERR_NOMEM;
      for (int t = 0; t < ntr && !rc; t++) {
        const uint16_t *f = feat + (size_t)tr[t] * info.n_feat;
        for (int i = 0; i < info.n_feat; i++) {
          double v = wv_nn_f16_to_f32(f[i]), l = v < 0 ? -log1p(-v) : log1p(v);
          s1[i] += l, s2[i] += l * l;
        }
      }
      double mean_sd = 0;
      for (int i = 0; i < info.n_feat && !rc; i++) {
        double m = s1[i] / ntr, var = s2[i] / ntr - m * m;
        net.mean[i] = (float)m;
        s2[i] = sqrt(fmax(var, 0));
        mean_sd += s2[i] / info.n_feat;
      }
      /* a floor (a tenth of the average spread) keeps near-constant features from
       * turning rounding and render noise into large inputs */
      for (int i = 0; i < info.n_feat && !rc; i++) net.std[i] = (float)fmax(s2[i], fmax(0.1 * mean_sd, 1e-6));
      free(s1), free(s2);
      size_t P = wv_fabricnet_param_count(&net);
      am = calloc(P, sizeof(float)), av = calloc(P, sizeof(float));
      if (!am || !av) rc = WV_ERR_NOMEM;
    }
  }
  if (!rc && mkdir(work, 0777) != 0 && errno != EEXIST) {
    fprintf(stderr, "woven train: error: %s: cannot create directory: %s\n", work, strerror(errno));
    rc = WV_ERR_IO;
  }
  if (!rc) {
    snprintf(path, sizeof path, "%s/train.json", work);
    json_t *tj = json_pack("{s:s,s:o,s:i,s:i,s:i,s:f,s:I,s:f,s:I,s:I}", "kind", "woven-train", "dataset", cli_str(dir),
                           "samples", n, "train", ntr, "validation", nva, "val_frac", vf, "batch", (json_int_t)batch,
                           "lr", lr, "seed", (json_int_t)seed, "epochs", (json_int_t)epochs);
    char *text = tj ? json_dumps(tj, JSON_PRESERVE_ORDER | JSON_REAL_PRECISION(15)) : NULL;
    json_decref(tj);
    size_t len = text ? strlen(text) : 0;
    char *tl = text ? realloc(text, len + 2) : NULL;
    if (!tl) {
      free(text);
      rc = cli_fail(&c, &(wv_error){WV_ERR_NOMEM, "out of memory for train.json"});
    } else {
      tl[len] = '\n', tl[len + 1] = '\0';
      if (wv_write_file_atomic(path, tl, len + 1, &err)) rc = cli_fail(&c, &err);
      free(tl);
    }
  }

  size_t P = rc ? 0 : wv_fabricnet_param_count(&net);
  float *grad = rc ? NULL : calloc(P, sizeof(float));
  float *x = rc ? NULL : malloc(sizeof(float) * (size_t)batch * info.n_feat);
  float *y = rc ? NULL : malloc(sizeof(float) * (size_t)batch * WV_NET_OUT);
  int *order = rc ? NULL : malloc(sizeof(int) * (size_t)ntr);
  wv_fabricnet_acts acts = {0};
  if (!rc && (!grad || !x || !y || !order)) rc = WV_ERR_NOMEM;
  if (!rc && wv_fabricnet_acts_alloc(&acts, (int)batch, &err)) rc = cli_fail(&c, &err);
  if (rc == WV_ERR_NOMEM) fprintf(stderr, "woven train: error: out of memory\n");
  wv_nn_adam adam = {0};
  if (!rc && wv_nn_adam_init(&adam, P, (float)lr, &err)) rc = cli_fail(&c, &err);
  if (!rc) { /* the checkpoint's moments */
    memcpy(adam.m, am, P * sizeof(float));
    memcpy(adam.v, av, P * sizeof(float));
    adam.t = ts.adam_t;
  }
  /* The weight arrays are one contiguous block starting at w1 (see alloc_net). */
  float *gt[6];
  if (!rc) {
    size_t off = 0;
    float *t[6];
    size_t len[6];
    wv_fabricnet_tensors(&net, t, len);
    for (int i = 0; i < 6; i++) gt[i] = grad + off, off += len[i];
  }
  double t0 = cli_now();
  cli_progress bar;
  cli_progress_start(&bar, &c, "train");
  int start_epoch = ts.epoch;
  for (int ep = ts.epoch; ep < epochs && !rc; ep++) {
    /* Shuffle with a stream that depends on (seed, epoch) only: resuming repeats it. */
    wv_rng r;
    wv_rng_seed(&r, wv_hash4((uint64_t)seed, (uint64_t)ep, 0x73687566, 0));
    for (int i = 0; i < ntr; i++) order[i] = tr[i];
    for (int i = ntr - 1; i > 0; i--) {
      int j = (int)(wv_rng_u64(&r) % (uint64_t)(i + 1)), tmp = order[i];
      order[i] = order[j], order[j] = tmp;
    }
    double sum = 0;
    int nb_total = 0;
    for (int i = 0; i < ntr; i += (int)batch) {
      int nb = ntr - i < batch ? ntr - i : (int)batch;
      int idx[4096];
      for (int b = 0; b < nb; b++) idx[b] = order[i + b];
      make_batch(&net, feat, targets, idx, nb, x, y);
      memset(grad, 0, P * sizeof(float));
      sum += wv_fabricnet_backward(&net, x, y, nb, &acts, gt) * nb;
      nb_total += nb;
      wv_nn_adam_step(&adam, net.w1, grad);
      cli_progress_update(&bar, (ep - start_epoch + (double)(i + nb) / ntr) / (epochs - start_epoch));
    }
    double train_l1 = sum / nb_total;
    double val_l1 = evaluate(&net, feat, targets, va, nva, (int)batch, x, y, &acts, NULL);
    hist[nhist++] = (epoch_rec){ep + 1, train_l1, val_l1};
    ts.epoch = ep + 1, ts.adam_t = adam.t;
    if (val_l1 < ts.best_val) { /* MODEL always holds the best epoch so far */
      ts.best_val = (float)val_l1, ts.best_epoch = ep + 1;
      if (wv_fabricnet_save(model, &net, &err)) rc = cli_fail(&c, &err);
    }
    if (!bar.enabled)
      cli_info(&c, "epoch %d/%ld  train L1 %.5f  validation L1 %.5f%s  %.0fs\n", ep + 1, epochs, train_l1, val_l1,
               ts.best_epoch == ep + 1 ? " (best)" : "", cli_now() - t0);
    snprintf(path, sizeof path, "%s/loss.csv", work);
    if (!rc && write_loss_csv(path, hist, nhist, &err)) rc = cli_fail(&c, &err);
    snprintf(path, sizeof path, "%s/loss.svg", work);
    if (!rc && write_loss_svg(path, hist, nhist, &err)) rc = cli_fail(&c, &err);
    if (!rc && ((ep + 1) % ck_every == 0 || ep + 1 == epochs) &&
        wv_fabricnet_checkpoint_save(ckpt, &net, adam.m, adam.v, &ts, &err))
      rc = cli_fail(&c, &err);
  }
  cli_progress_end(&bar);
  double el = cli_now() - t0;
  if (!rc) {
    /* Report the saved model (the best epoch) on the validation split. */
    wv_fabricnet best;
    double per[WV_NET_OUT], val = 0;
    if (wv_fabricnet_load(model, &best, &err)) {
      rc = cli_fail(&c, &err);
    } else {
      val = evaluate(&best, feat, targets, va, nva, (int)batch, x, y, &acts, per);
      wv_fabricnet_free(&best);
      cli_info(&c, "%d epochs in %.1f s; %s: best epoch %d, validation L1 %.5f (f16 weights %.5f)\n",
               ts.epoch - start_epoch, el, model, ts.best_epoch, ts.best_val, val);
      if (c.json) {
        json_t *po = json_object();
        for (int k = 0; k < WV_NET_OUT; k++) json_object_set_new(po, wv_fabricnet_output_name(k), cli_real(per[k], 5));
        cli_print_json(json_pack("{s:o,s:i,s:o,s:i,s:i,s:i,s:o,s:o,s:o}", "model", cli_str(model), "epochs", ts.epoch,
                                 "seconds", cli_real(el, 3), "train_samples", ntr, "val_samples", nva, "best_epoch",
                                 ts.best_epoch, "val_l1", cli_real(val, 6), "final_train_l1",
                                 cli_real(nhist ? hist[nhist - 1].train : 0.0, 6), "val_l1_per_output", po));
      }
    }
  }
  wv_nn_adam_free(&adam);
  wv_fabricnet_acts_free(&acts);
  wv_fabricnet_free(&net);
  free(am), free(av), free(grad), free(x), free(y), free(order), free(hist), free(tr), free(va);
  free(feat), free(targets), free(ids);
  return rc;
}
