/* woven train: FabricNet's fully connected head on a dataset from 'woven dataset'. */
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "woven/fabricnet.h"
#include "woven/io.h"

static const char *HELP =
    "usage: woven train DIR -o MODEL [--epochs N] [--batch N] [--lr X] [--val-frac X] [--seed N]\n"
    "                   [--ce-weight X] [--init MODEL] [--checkpoint-every N] [--resume | --force]\n"
    "                   [--partial]\n"
    "                   [--quiet] [--json]\n"
    "\n"
    "Trains FabricNet (SPEC section 7: features -> 256 -> LeakyReLU -> 256 -> LeakyReLU -> 21 ->\n"
    "sigmoid, and a pattern head -> 16 -> softmax over the built-in weaves; L1 loss on normalised\n"
    "parameters plus the pattern's cross-entropy; Adam) on the dataset in DIR.\n"
    "  --epochs N            total epochs (default 60)\n"
    "  --batch N             batch size (default 32)\n"
    "  --lr X                Adam learning rate (default 1e-4)\n"
    "  --val-frac X          held-out validation fraction (default 0.1, chosen by a hash of the sample)\n"
    "  --ce-weight X         weight of the pattern cross-entropy beside the L1 (default 0.1)\n"
    "  --init MODEL          fine-tune: start from MODEL's weights and feature statistics (a model\n"
    "                        without a pattern head gets a fresh one)\n"
    "  --checkpoint-every N  epochs between checkpoints (default 1)\n"
    "  --resume              continue from MODEL.train/checkpoint.bin\n"
    "  --force               start again even if MODEL.train/ holds a checkpoint\n"
    "  --partial             train on the finished samples of an incomplete dataset\n"
    "MODEL receives the weights of the epoch with the lowest validation loss (f16, docs/fabricnet.md).\n"
    "MODEL.train/ holds checkpoint.bin, loss.csv, loss.svg and train.json.\n";

static void on_start(const cli_ctx *c, const wv_train_result *r) {
  cli_info(c, "%d samples loaded in %.1f s (%d train, %d validation)%s\n", r->samples, r->load_seconds, r->train,
           r->validation, r->missing ? " [partial]" : "");
  if (r->resumed_epoch) cli_info(c, "resuming at epoch %d\n", r->resumed_epoch);
}

typedef struct {
  cli_ctx *c;
  cli_progress *bar;
  long epochs;
} train_ui;

static void on_progress(void *user, double f) {
  train_ui *u = user;
  cli_progress_update(u->bar, f);
}

static void on_epoch(void *user, const wv_train_epoch *e) {
  train_ui *u = user;
  if (!u->bar->enabled)
    cli_info(u->c, "epoch %d/%ld  train L1 %.5f CE %.4f  validation L1 %.5f CE %.4f pattern %.3f%s  %.0fs\n", e->epoch,
             u->epochs, e->train, e->train_ce, e->val, e->val_ce, e->val_acc, e->best ? " (best)" : "", e->seconds);
}

static void on_start_ui(void *user, const wv_train_result *r) {
  train_ui *u = user;
  on_start(u->c, r);
}

int cmd_train(int argc, char **argv) {
  cli_ctx c = {0, 0, "train"};
  cli_args a;
  cli_args_init(&a, argc, argv, c.cmd);
  const char *dir = NULL, *model = NULL, *lr_s = NULL, *vf_s = NULL, *ce_s = NULL, *init = NULL;
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
    } else if (cli_is(&a, s, "--init")) {
      if (!(init = cli_value(&a, "--init"))) return EXIT_USAGE;
    } else if (cli_is(&a, s, "--ce-weight")) {
      if (!(ce_s = cli_value(&a, "--ce-weight"))) return EXIT_USAGE;
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
  wv_train_opts o;
  wv_train_opts_default(&o);
  o.epochs = (int)epochs, o.batch = (int)batch, o.lr = lr, o.val_frac = vf, o.seed = (uint64_t)seed;
  o.checkpoint_every = (int)ck_every, o.resume = resume, o.force = force, o.partial = partial, o.init = init;
  if (init && resume) return cli_usage_error(c.cmd, "--init and --resume exclude each other");
  if (ce_s && (o.ce_weight = strtod(ce_s, &end), *end || !(o.ce_weight >= 0 && o.ce_weight <= 100)))
    return cli_usage_error(c.cmd, "--ce-weight must be a number in [0, 100]");
  { /* MODEL and MODEL.train/ must not land on the dataset's files */
    char ds[2][4096], work[4096];
    snprintf(work, sizeof work, "%s.train", model);
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
    cli_clean_temps_beside(model);
    wv_remove_stale_temps(work, NULL);
  }
  cli_progress bar;
  cli_progress_start(&bar, &c, "train");
  train_ui ui = {&c, &bar, epochs};
  o.on_start = on_start_ui, o.on_progress = on_progress, o.on_epoch = on_epoch, o.user = &ui;
  wv_train_result r;
  wv_status st = wv_train(dir, model, &o, &r, &err);
  cli_progress_end(&bar);
  if (st) return cli_fail(&c, &err);
  cli_info(&c, "%d epochs in %.1f s; %s: best epoch %d, validation L1 %.5f, pattern accuracy %.3f (CE %.4f)\n",
           r.epochs_run, r.seconds, model, r.best_epoch, r.val_f16, r.val_accuracy, r.val_ce);
  if (c.json) {
    json_t *po = json_object();
    for (int k = 0; k < WV_NET_OUT; k++)
      json_object_set_new(po, wv_fabricnet_output_name(k), cli_real(r.val_per_output[k], 5));
    cli_print_json(json_pack("{s:o,s:i,s:o,s:i,s:i,s:i,s:o,s:o,s:o,s:o,s:o}", "model", cli_str(model), "epochs",
                             r.epochs, "seconds", cli_real(r.seconds, 3), "train_samples", r.train, "val_samples",
                             r.validation, "best_epoch", r.best_epoch, "val_l1", cli_real(r.val_f16, 6), "val_ce",
                             cli_real(r.val_ce, 6), "val_pattern_accuracy", cli_real(r.val_accuracy, 4),
                             "final_train_l1", cli_real(r.final_train, 6), "val_l1_per_output", po));
  }
  return 0;
}
