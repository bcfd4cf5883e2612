/* Helpers shared by the woven subcommands: the option parser, messages,
 * progress bars, exit codes. */
#ifndef WOVEN_CLI_H
#define WOVEN_CLI_H

#include <stddef.h>
#include <stdio.h>
#include "woven/error.h"

/* Exit codes: 0 success, 1 usage error, otherwise the wv_status of the failure
 * (2 invalid input value, 3 I/O, 4 malformed file, 5 too large/out of memory). */
#define EXIT_USAGE 1

typedef struct {
  int quiet, json;
  const char *cmd; /* subcommand name for messages */
} cli_ctx;

/* The option parser (cli/opts.c). A command lists its options in tables of cli_opt,
 * each field at an offset in the command's argument struct (plus the table's base),
 * and its positional arguments (const char * fields). "--key value" and "--key=value"
 * both work; --quiet (-q), --json and --help (-h) are every command's. */
typedef enum {
  CLI_FLAG,   /* int field set to 1 */
  CLI_CLEAR,  /* int field set to 0 (--no-...) */
  CLI_INT,    /* int field, in lo..hi */
  CLI_REAL,   /* double field, in lo..hi (open bounds: CLI_OPEN_LO/HI) */
  CLI_STR,    /* const char * field */
  CLI_ENUM,   /* int field: the index of the value in meta, "a|b|c" */
  CLI_CUSTOM, /* parse() */
} cli_opt_kind;
enum { CLI_OPEN_LO = 1, CLI_OPEN_HI = 2 };
typedef struct cli_opt cli_opt;
struct cli_opt {
  const char *name, *alias; /* "--output", "-o" (or NULL) */
  cli_opt_kind kind;
  size_t off;
  double lo, hi;
  const char *meta; /* the value's name in the help (N, FILE), or an enum's choices */
  const char *help; /* NULL: not listed by --help */
  /* CLI_CUSTOM: reads v into the struct at base; 0, or the exit code after printing why not */
  int (*parse)(const char *cmd, const cli_opt *o, const char *v, void *base);
  int open;
};
/* Table entries: T is the argument struct, f its field. */
#define CLI_O_STR(n, a, T, f, meta, help) {n, a, CLI_STR, offsetof(T, f), 0, 0, meta, help, NULL, 0}
#define CLI_O_INT(n, a, T, f, lo, hi, meta, help) {n, a, CLI_INT, offsetof(T, f), lo, hi, meta, help, NULL, 0}
#define CLI_O_REAL(n, T, f, lo, hi, open, meta, help) {n, NULL, CLI_REAL, offsetof(T, f), lo, hi, meta, help, NULL, open}
#define CLI_O_FLAG(n, T, f, help) {n, NULL, CLI_FLAG, offsetof(T, f), 0, 0, NULL, help, NULL, 0}
#define CLI_O_CLEAR(n, T, f, help) {n, NULL, CLI_CLEAR, offsetof(T, f), 0, 0, NULL, help, NULL, 0}
#define CLI_O_ENUM(n, T, f, choices, help) {n, NULL, CLI_ENUM, offsetof(T, f), 0, 0, choices, help, NULL, 0}
#define CLI_O_CUSTOM(n, T, f, lo, hi, fn, meta, help) {n, NULL, CLI_CUSTOM, offsetof(T, f), lo, hi, meta, help, fn, 0}
#define CLI_O_END {NULL, NULL, CLI_FLAG, 0, 0, 0, NULL, NULL, NULL, 0}
#define CLI_MAX_TABLES 5
typedef struct {
  const char *name;   /* the subcommand, for messages */
  const char *usage;  /* usage lines and description, before the options */
  const char *epilog; /* after the options, or NULL */
  struct {
    const cli_opt *opts; /* ends with an entry whose name is NULL */
    size_t base;         /* where the table's fields start in the argument struct */
  } tables[CLI_MAX_TABLES];
  int npos;
  size_t pos[3]; /* offsets of the positional arguments' fields */
} cli_cmd;
#define CLI_HELP (-1)
/* Parses argv[1..] into args and c: 0, CLI_HELP after printing the help (exit 0), or
 * the exit code after printing why not. */
int cli_parse(const cli_cmd *cmd, int argc, char **argv, void *args, cli_ctx *c);
void cli_print_help(const cli_cmd *cmd, FILE *f);
/* For CLI_CUSTOM parsers: a number in o's range, or the exit code after printing why not. */
int cli_opt_int(const char *cmd, const cli_opt *o, const char *v, int *out);
int cli_opt_real(const char *cmd, const cli_opt *o, const char *v, double *out);
/* Runs cli_parse and turns CLI_HELP into *done = 1 with exit code 0. */
#define CLI_PARSE(cmd, argc, argv, args, c)                 \
  do {                                                      \
    int rc_ = cli_parse(cmd, argc, argv, args, c);          \
    if (rc_) return rc_ == CLI_HELP ? 0 : rc_;              \
  } while (0)

int cli_fail(const cli_ctx *c, const wv_error *err);       /* prints "woven CMD: msg", returns exit code */
int cli_usage_error(const char *cmd, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
void cli_info(const cli_ctx *c, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/* --json summaries are built with jansson (paths and names escaped), one line on
 * stdout. cli_real rounds to the given decimals (NaN and infinities become null). */
#include <jansson.h>
void cli_print_json(json_t *o); /* prints and releases o */
json_t *cli_real(double v, int decimals);
/* A count held in a double, as a JSON integer (rounded; null when not finite or out of range). */
json_t *cli_count(double v);
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

/* The fit's progress and summary (woven fit and woven capture). */
#include "woven/capture.h"
typedef struct {
  cli_ctx *c;
  cli_progress bar;
} cli_fit_ui;
/* The progress callbacks of a fit job: messages, and a progress line on a terminal. */
wv_capture_progress cli_fit_progress(cli_fit_ui *u, cli_ctx *c);
/* Prints the finished fit (a line, and the --json summary) and frees r's state; returns 0. */
int cli_fit_summary(cli_ctx *c, const char *dir, const wv_pattern_choice *pc, wv_fit_outcome *r);

/* The options of woven fit, predict, capture and capture-batch, parsed by the tables
 * below (each command takes the tables that apply to it). */
typedef struct {
  const char *photo, *scene, *pattern, *model, *descriptor, *weights, *out, *init, *resume, *drape;
  const char *transmission, *transmission_scene; /* a photo pair (woven fit, woven capture) */
  const char *pair_model;                        /* woven capture: the pair model */
  wv_crop crop;
  int force, iters_given, align_given;
  wv_fit_opts fit;
} capture_args;
void cli_capture_args_init(capture_args *a);
/* --scene, --pattern, --descriptor, --vgg19-weights, --crop, -o, --force */
extern const cli_opt CLI_PHOTO_OPTS[];
/* --model */
extern const cli_opt CLI_MODEL_OPTS[];
/* --transmission, --transmission-scene (woven fit, woven capture) */
extern const cli_opt CLI_PAIR_OPTS[];
/* --pair-model (woven capture) */
extern const cli_opt CLI_PAIR_MODEL_OPTS[];
/* The fit's tuning: --iters, --iter-spp, --iter-scale, --seed, --align-radius,
 * --register-radius, --distort-degree, --w-struct, --w-colour, --camera-blur, --colour-split, --no-colour-split, --threads, --drape. */
extern const cli_opt CLI_FIT_OPTS[];
/* The capture's options from the parsed ones (photo, directory and all). */
void cli_capture_opts(const capture_args *a, wv_capture_opts *o);

int cmd_render(int argc, char **argv);
int cmd_fit(int argc, char **argv);
int cmd_maps(int argc, char **argv);
int cmd_compare(int argc, char **argv);
int cmd_dataset(int argc, char **argv);
int cmd_train(int argc, char **argv);
int cmd_predict(int argc, char **argv);
int cmd_capture(int argc, char **argv);
int cmd_capture_batch(int argc, char **argv);
int cmd_scene(int argc, char **argv);
int cmd_cloth(int argc, char **argv);
int cmd_export(int argc, char **argv);
int cmd_view(int argc, char **argv);

#endif
