/* Helpers shared by the woven subcommands: messages, --json
 * output, output checks, progress bars. */
#include "cli.h"

#include <math.h>
#include <libgen.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <time.h>
#include <unistd.h>

#include "util/json.h"
#include "woven/io.h"

int cli_fail(const cli_ctx *c, const wv_error *err) {
  fprintf(stderr, "woven %s: error: %s\n", c->cmd, err->msg);
  return err->code ? (int)err->code : 2;
}

int cli_usage_error(const char *cmd, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  fprintf(stderr, "woven %s: ", cmd);
  vfprintf(stderr, fmt, ap);
  fprintf(stderr, "\nTry 'woven %s --help'.\n", cmd);
  va_end(ap);
  return EXIT_USAGE;
}

void cli_info(const cli_ctx *c, const char *fmt, ...) {
  if (c->quiet || c->json) return;
  va_list ap;
  va_start(ap, fmt);
  vfprintf(stderr, fmt, ap);
  va_end(ap);
}

double cli_now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec + ts.tv_nsec * 1e-9;
}

void cli_progress_start(cli_progress *p, const cli_ctx *c, const char *label) {
  p->enabled = !c->quiet && isatty(STDERR_FILENO);
  p->label = label;
  p->start = cli_now();
  p->last_pct = -1;
}

void cli_progress_update(void *vp, double f) {
  cli_progress *p = vp;
  if (!p->enabled) return;
  int pct = (int)(f * 100.0);
  if (pct == p->last_pct) return;
  p->last_pct = pct;
  double el = cli_now() - p->start;
  double left = f > 0.01 ? el * (1.0 - f) / f : 0.0;
  char bar[31];
  int fill = (int)(f * 30.0);
  for (int i = 0; i < 30; i++) bar[i] = i < fill ? '#' : '.';
  bar[30] = '\0';
  fprintf(stderr, "\r%s [%s] %3d%%  %.1fs, %.1fs left ", p->label, bar, pct, el, left);
  fflush(stderr);
}

void cli_progress_end(cli_progress *p) {
  if (p->enabled) fprintf(stderr, "\r\033[K");
}

void cli_print_json(json_t *o) {
  char *t = o ? json_dumps(o, JSON_PRESERVE_ORDER | JSON_REAL_PRECISION(15)) : NULL;
  if (t) printf("%s\n", t);
  free(t);
  json_decref(o);
}

json_t *cli_real(double v, int decimals) {
  if (!isfinite(v)) return json_null();
  double k = pow(10.0, decimals);
  return json_real(round(v * k) / k);
}

json_t *cli_count(double v) {
  if (!(fabs(v) < 9e18)) return json_null();
  return json_integer((json_int_t)llround(v));
}

json_t *cli_str(const char *s) { return wv_json_str_lossy(s); }

json_t *cli_json_text(char *text) { return wv_json_from_text(text); }

int cli_check_not_input(const cli_ctx *c, const char *out, int out_is_dir, const char *const *inputs, int n) {
  wv_error err = {0};
  if (wv_check_not_input(out, out_is_dir, inputs, n, &err)) return cli_fail(c, &err);
  return 0;
}

void cli_clean_temps_beside(const char *path) { wv_remove_stale_temps_beside(path); }

/* Refuse early, before minutes of work, when the output cannot be written. */
int cli_check_writable(const char *cmd, const char *path) {
  char *copy = strdup(path);
  if (!copy) return 0;
  const char *dir = dirname(copy);
  int ok = access(dir, W_OK) == 0;
  if (!ok) fprintf(stderr, "woven %s: error: %s: directory '%s' is not writable or does not exist\n", cmd, path, dir);
  free(copy);
  return ok;
}

int cli_check_output(const char *cmd, const char *path, const char *ext) {
  size_t n = strlen(path), e = strlen(ext);
  if (n <= e || strcasecmp(path + n - e, ext)) return cli_usage_error(cmd, "output '%s' must end in %s", path, ext);
  return cli_check_writable(cmd, path) ? 0 : WV_ERR_IO;
}
