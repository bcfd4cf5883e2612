/* Helpers shared by the woven subcommands: argument parsing, messages,
 * progress bars, exit codes. */
#ifndef WOVEN_CLI_H
#define WOVEN_CLI_H

#include <stdio.h>
#include "woven/error.h"

/* Exit codes: 0 success, 1 usage error, otherwise the wv_status of the failure
 * (2 invalid input value, 3 I/O, 4 malformed file, 5 too large/out of memory). */
#define EXIT_USAGE 1

typedef struct {
  int quiet, json;
  const char *cmd; /* subcommand name for messages */
} cli_ctx;

/* Argument cursor: "--key value" and "--key=value" both work. */
typedef struct {
  int argc, i;
  char **argv;
  const char *cmd;
  const char *inline_value;
} cli_args;

void cli_args_init(cli_args *a, int argc, char **argv, const char *cmd);
/* Next argument, or NULL at the end. */
const char *cli_next(cli_args *a);
/* Is the current argument the option 'name' (e.g. "--spp")? */
int cli_is(cli_args *a, const char *arg, const char *name);
/* Value of the current option; prints an error and returns NULL when missing. */
const char *cli_value(cli_args *a, const char *name);
int cli_int(cli_args *a, const char *name, long lo, long hi, long *out);

/* The flags every command takes: --quiet (-q) and --json. Returns 1 if s was one. */
int cli_common_flag(cli_ctx *c, const char *s);
int cli_fail(const cli_ctx *c, const wv_error *err);       /* prints "woven CMD: msg", returns exit code */
int cli_usage_error(const char *cmd, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
void cli_info(const cli_ctx *c, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/* --json summaries are built with jansson (paths and names escaped), one line on
 * stdout. cli_real rounds to the given decimals (NaN and infinities become null). */
#include <jansson.h>
void cli_print_json(json_t *o); /* prints and releases o */
json_t *cli_real(double v, int decimals);
/* A path or name as a JSON string (bytes that are not UTF-8 become U+FFFD). */
json_t *cli_str(const char *s);
/* A JSON text (e.g. wv_params_to_json) as a value; null when text is NULL. Frees text. */
json_t *cli_json_text(char *text);

/* Refuses (prints the message, returns the exit code) an output that would replace
 * one of the inputs (wv_check_not_input); 0 when none would be. */
int cli_check_not_input(const cli_ctx *c, const char *out, int out_is_dir, const char *const *inputs, int n);
/* Removes stale temporary files an interrupted run left beside the output file path. */
void cli_clean_temps_beside(const char *path);

/* Progress bar on stderr, drawn only when stderr is a TTY and not quiet. */
typedef struct {
  int enabled;
  const char *label;
  double start;
  int last_pct;
} cli_progress;
void cli_progress_start(cli_progress *p, const cli_ctx *c, const char *label);
void cli_progress_update(void *p, double fraction);
void cli_progress_end(cli_progress *p);
double cli_now(void);
/* Refuses early, before minutes of work, an output whose directory is not writable (prints why). */
int cli_check_writable(const char *cmd, const char *path);
/* An output file: its name must end in ext and its directory be writable; returns 0,
 * or the exit code after printing why not. */
int cli_check_output(const char *cmd, const char *path, const char *ext);

/* A fit to run (woven fit and woven capture). */
#include "woven/descriptor.h"
#include "woven/fabricnet.h"
#include "woven/fit.h"
#include "woven/params.h"
#include "woven/photo.h"
#include "woven/scene.h"
typedef struct {
  const wv_scene *scene;
  const wv_image *photo;
  wv_descriptor *desc;
  const wv_params *start; /* NULL when resuming */
  wv_fit_opts opts;
  const char *dir, *photo_path, *start_label, *title;
  int resume, iters_given, force;
  const wv_pattern_choice *pattern_choice; /* capture without --pattern: how the start's pattern was chosen */
  /* For fit.json (a new fit): the crop used and the descriptor's weights file. */
  wv_crop crop;
  const char *weights;
  /* A file written with fit.json (capture: network.json), or NULL. */
  const char *extra_name, *extra_text;
  /* Files read by the command: none may lie inside the directory, which is replaced whole. */
  const char *inputs[6];
  /* The mesh scene the report shows the fit on (NULL: the bundled draped cloth; "none": no drape). */
  const char *drape;
  struct fit_result *result; /* filled when not NULL (woven capture-batch) */
} fit_job;
/* The figures of a finished fit, for a caller that runs it (woven capture-batch). */
typedef struct fit_result {
  double ssim_start, ssim_fit;
  double wsc; /* weave-spectrum correlation of the fit against the photo */
  int iterations;
  char pattern[32];
} fit_result;
/* The output directory check, before any slow step: refuses a file, a directory
 * holding files that are not a fit's, an input inside it, and (unless --force or
 * resuming) an earlier fit, finished or not. Returns the exit code (0: fine). */
int fit_check_dir(const cli_ctx *c, const fit_job *job);
/* Runs the fit and writes every output. The directory's life: fit.json and a
 * checkpoint at iteration 0 appear first (one rename), checkpoints follow while
 * fitting, and the results replace the directory whole at the end. When it holds
 * a finished fit (--force, or --resume adding iterations) all of that happens in a
 * temporary directory beside it, so the earlier fit stays whole until then. */
int fit_pipeline(cli_ctx *c, const fit_job *job);
/* The fit's tuning options, shared by woven fit and woven capture: --iters,
 * --iter-spp, --iter-scale, --seed, --align-radius, --threads. Sets *handled;
 * returns EXIT_USAGE after printing a message for a bad value. */
int cli_parse_fit_opt(cli_args *a, const char *s, fit_job *job, int *iters_given, int *handled);
/* x,y,w,h: non-negative integers, w and h positive. */
int cli_parse_crop(const char *s, wv_crop *c);

int cmd_render(int argc, char **argv);
int cmd_fit(int argc, char **argv);
int cmd_maps(int argc, char **argv);
int cmd_compare(int argc, char **argv);
int cmd_dataset(int argc, char **argv);
int cmd_train(int argc, char **argv);
int cmd_predict(int argc, char **argv);
int cmd_capture(int argc, char **argv);
/* woven capture with its arguments (argv[0] the command name); result as in fit_job. */
int cli_capture(int argc, char **argv, fit_result *result);
int cmd_capture_batch(int argc, char **argv);
int cmd_scene(int argc, char **argv);
int cmd_cloth(int argc, char **argv);
int cmd_export(int argc, char **argv);
int cmd_view(int argc, char **argv);

#endif
