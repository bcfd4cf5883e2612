/* woven train: FabricNet's fully connected head on a dataset from 'woven dataset'. */
#include <limits.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "woven/train.h"

typedef struct {
  const char *dir, *model, *init;
  int epochs, batch, seed, ck_every, resume, force, partial, head_only;
  double lr, vf, ce, head_start;
} train_args;

static const cli_opt OPTS[] = {
    CLI_O_STR("--output", "-o", train_args, model, "MODEL", "the model file"),
    CLI_O_INT("--epochs", NULL, train_args, epochs, 1, WV_NET_MAX_EPOCHS, "N", "total epochs (default 60)"),
    CLI_O_INT("--batch", NULL, train_args, batch, 1, 4096, "N", "batch size (default 32)"),
    CLI_O_REAL("--lr", train_args, lr, 0, 1, CLI_OPEN_LO | CLI_OPEN_HI, "X", "Adam learning rate (default 1e-4)"),
    CLI_O_REAL("--val-frac", train_args, vf, 0, 0.9, CLI_OPEN_LO | CLI_OPEN_HI, "X",
               "held-out validation fraction (default 0.1, chosen by a hash of the\nsample)"),
    CLI_O_INT("--seed", NULL, train_args, seed, 0, INT_MAX, "N", "the seed of the initial weights and batches (default 1)"),
    CLI_O_REAL("--ce-weight", train_args, ce, 0, 100, 0, "X",
               "weight of the pattern cross-entropy beside the L1 (default 0.1)"),
    CLI_O_STR("--init", NULL, train_args, init, "MODEL",
              "fine-tune: start from MODEL's weights and feature statistics (a\nmodel without a pattern head gets a fresh one)"),
    CLI_O_INT("--checkpoint-every", NULL, train_args, ck_every, 1, 100000, "N", "epochs between checkpoints (default 1)"),
    CLI_O_FLAG("--resume", train_args, resume, "continue from MODEL.train/checkpoint.bin"),
    CLI_O_FLAG("--force", train_args, force, "start again even if MODEL.train/ holds a checkpoint"),
    CLI_O_FLAG("--partial", train_args, partial, "train on the finished samples of an incomplete dataset"),
    CLI_O_FLAG("--pattern-head-only", train_args, head_only,
               "with --init or --resume: train the pattern head alone; every other\n"
               "weight, and so every parameter estimate, stays the starting model's"),
    CLI_O_REAL("--head-start-weight", train_args, head_start, 0, 1, CLI_OPEN_HI, "W",
               "with --init and --pattern-head-only: save the pattern head as (1 - W)\n"
               "times the trained head plus W times the starting model's (default 0)"),
    CLI_O_END};

static const cli_cmd CMD = {
    "train",
    "usage: woven train DIR -o MODEL [--epochs N] [--batch N] [--lr X] [--val-frac X] [--seed N]\n"
    "                   [--ce-weight X] [--init MODEL] [--checkpoint-every N] [--resume | --force]\n"
    "                   [--partial] [--pattern-head-only [--head-start-weight W]]\n"
    "                   [--quiet] [--json]\n"
    "\n"
    "Trains FabricNet (SPEC section 7: features -> 256 -> LeakyReLU -> 256 -> LeakyReLU -> 21 ->\n"
    "sigmoid, and a pattern head -> 16 -> softmax over the built-in weaves; L1 loss on normalised\n"
    "parameters plus the pattern's cross-entropy; Adam) on the dataset in DIR.\n",
    "MODEL receives the weights of the epoch with the lowest validation loss (f16, docs/fabricnet.md).\n"
    "MODEL.train/ holds checkpoint.bin, loss.csv, loss.svg and train.json.\n",
    {{OPTS, 0}}, 1, {offsetof(train_args, dir)}};

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
  train_args ta;
  memset(&ta, 0, sizeof ta);
  ta.epochs = 60, ta.batch = 32, ta.seed = 1, ta.ck_every = 1, ta.lr = 1e-4, ta.vf = 0.1, ta.ce = -1;
  CLI_PARSE(&CMD, argc, argv, &ta, &c);
  const char *dir = ta.dir, *model = ta.model, *init = ta.init;
  long epochs = ta.epochs;
  int resume = ta.resume, force = ta.force;
  if (!dir) return cli_usage_error(c.cmd, "a dataset DIR is required");
  if (!model) return cli_usage_error(c.cmd, "-o MODEL is required");
  if (resume && force) return cli_usage_error(c.cmd, "--resume and --force exclude each other");
  wv_error err = {0};
  wv_train_opts o;
  wv_train_opts_default(&o);
  o.epochs = ta.epochs, o.batch = ta.batch, o.lr = ta.lr, o.val_frac = ta.vf, o.seed = (uint64_t)ta.seed;
  o.checkpoint_every = ta.ck_every, o.resume = resume, o.force = force, o.partial = ta.partial, o.init = init;
  o.pattern_head_only = ta.head_only, o.head_start_weight = ta.head_start;
  if (init && resume) return cli_usage_error(c.cmd, "--init and --resume exclude each other");
  if (ta.ce >= 0) o.ce_weight = ta.ce;
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
    for (int k = 0; k < r.outputs; k++)
      json_object_set_new(po, wv_fabricnet_output_name(k), cli_real(r.val_per_output[k], 5));
    cli_print_json(json_pack("{s:o,s:i,s:o,s:i,s:i,s:i,s:o,s:o,s:o,s:o,s:o}", "model", cli_str(model), "epochs",
                             r.epochs, "seconds", cli_real(r.seconds, 3), "train_samples", r.train, "val_samples",
                             r.validation, "best_epoch", r.best_epoch, "val_l1", cli_real(r.val_f16, 6), "val_ce",
                             cli_real(r.val_ce, 6), "val_pattern_accuracy", cli_real(r.val_accuracy, 4),
                             "final_train_l1", cli_real(r.final_train, 6), "val_l1_per_output", po));
  }
  return 0;
}
