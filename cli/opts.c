/* The one option parser of the woven subcommands: each command describes its
 * options in a table (cli_opt) and its positional arguments in a cli_cmd; this file
 * parses argv against them, checks numbers against their ranges, and writes
 * 'woven CMD --help' from the same tables. */
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"

/* The flags every command takes, stored in cli_ctx rather than the command's fields. */
static const cli_opt COMMON[] = {
    {"--quiet", "-q", CLI_FLAG, 0, 0, 0, NULL, "no messages on stderr (errors still go there)", NULL, 0},
    {"--json", NULL, CLI_FLAG, 0, 0, 0, NULL, "a one-line JSON summary on stdout", NULL, 0},
    {"--help", "-h", CLI_FLAG, 0, 0, 0, NULL, "this text", NULL, 0},
    CLI_O_END};

int cli_opt_int(const char *cmd, const cli_opt *o, const char *v, int *out) {
  char *end;
  errno = 0;
  long x = strtol(v, &end, 10);
  if (*v == '\0' || *end != '\0' || errno == ERANGE || x < (long)o->lo || x > (long)o->hi)
    return cli_usage_error(cmd, "%s: '%s' is not an integer in %ld..%ld", o->name, v, (long)o->lo, (long)o->hi);
  *out = (int)x;
  return 0;
}

int cli_opt_real(const char *cmd, const cli_opt *o, const char *v, double *out) {
  char *end;
  double x = strtod(v, &end);
  int lo_ok = o->open & CLI_OPEN_LO ? x > o->lo : x >= o->lo, hi_ok = o->open & CLI_OPEN_HI ? x < o->hi : x <= o->hi;
  if (*v == '\0' || *end != '\0' || !(lo_ok && hi_ok)) {
    if (o->open)
      return cli_usage_error(cmd, "%s: '%s' is not a number in %c%g, %g%c", o->name, v,
                             o->open & CLI_OPEN_LO ? '(' : '[', o->lo, o->hi, o->open & CLI_OPEN_HI ? ')' : ']');
    return cli_usage_error(cmd, "%s: '%s' is not a number in %g..%g", o->name, v, o->lo, o->hi);
  }
  *out = x;
  return 0;
}

/* "a|b|c" holds v as one of its words. */
static int choice_index(const char *choices, const char *v) {
  size_t n = strlen(v);
  int i = 0;
  for (const char *p = choices; p; i++) {
    const char *bar = strchr(p, '|');
    size_t len = bar ? (size_t)(bar - p) : strlen(p);
    if (len == n && !strncmp(p, v, n)) return i;
    p = bar ? bar + 1 : NULL;
  }
  return -1;
}

static int choice_error(const char *cmd, const cli_opt *o, const char *v) {
  char list[256];
  size_t k = 0;
  const char *last = strrchr(o->meta, '|');
  for (const char *p = o->meta; *p && k + 8 < sizeof list; p++) {
    if (*p != '|') {
      list[k++] = *p;
    } else if (p == last) {
      memcpy(list + k, " or ", 4), k += 4;
    } else {
      memcpy(list + k, ", ", 2), k += 2;
    }
  }
  list[k] = '\0';
  return cli_usage_error(cmd, "%s must be %s, not '%s'", o->name, list, v);
}

static int set_value(const char *cmd, const cli_opt *o, const char *v, char *base) {
  void *field = base + o->off;
  switch (o->kind) {
    case CLI_INT: return cli_opt_int(cmd, o, v, field);
    case CLI_REAL: return cli_opt_real(cmd, o, v, field);
    case CLI_STR: *(const char **)field = v; return 0;
    case CLI_ENUM: {
      int i = choice_index(o->meta, v);
      if (i < 0) return choice_error(cmd, o, v);
      *(int *)field = i;
      return 0;
    }
    case CLI_CUSTOM: return o->parse(cmd, o, v, base);
    default: return 0;
  }
}

/* The entry of the tables named by arg ("--name", "--name=value" or the alias);
 * *inline_v receives the value after '='. */
static const cli_opt *find(const cli_cmd *cmd, const char *arg, const char **inline_v, char **base, char *args) {
  for (int t = -1; t < CLI_MAX_TABLES; t++) {
    const cli_opt *tab = t < 0 ? COMMON : cmd->tables[t].opts;
    if (!tab) break;
    for (const cli_opt *o = tab; o->name; o++) {
      for (int which = 0; which < 2; which++) {
        const char *name = which ? o->alias : o->name;
        if (!name) continue;
        size_t n = strlen(name);
        if (strncmp(arg, name, n)) continue;
        if (arg[n] == '\0' || (arg[n] == '=' && o->kind != CLI_FLAG)) {
          *inline_v = arg[n] ? arg + n + 1 : NULL;
          *base = t < 0 ? NULL : args + cmd->tables[t].base;
          return o;
        }
      }
    }
  }
  return NULL;
}

int cli_parse(const cli_cmd *cmd, int argc, char **argv, void *args, cli_ctx *c) {
  int npos = 0;
  for (int i = 1; i < argc; i++) {
    const char *s = argv[i];
    if (s[0] != '-' || !s[1]) {
      if (npos >= cmd->npos) return cli_usage_error(cmd->name, "unexpected argument '%s'", s);
      *(const char **)((char *)args + cmd->pos[npos++]) = s;
      continue;
    }
    const char *v;
    char *base;
    const cli_opt *o = find(cmd, s, &v, &base, args);
    if (!o) return cli_usage_error(cmd->name, "unknown option '%s'", s);
    if (!base) { /* the common flags */
      if (!strcmp(o->name, "--help")) {
        cli_print_help(cmd, stdout);
        return CLI_HELP;
      }
      if (!strcmp(o->name, "--quiet")) c->quiet = 1;
      else c->json = 1;
      continue;
    }
    if (o->kind == CLI_FLAG || o->kind == CLI_CLEAR) {
      *(int *)(base + o->off) = o->kind == CLI_FLAG;
      continue;
    }
    if (!v) {
      if (i + 1 >= argc) return cli_usage_error(cmd->name, "option %s needs a value", s);
      v = argv[++i];
    }
    int rc = set_value(cmd->name, o, v, base);
    if (rc) return rc;
  }
  return 0;
}

/* One option's help: the left column, then the text, its later lines indented alike. */
static void print_opt(FILE *f, const cli_opt *o) {
  char left[96];
  int n = snprintf(left, sizeof left, "  %s%s%s", o->alias ? o->alias : "", o->alias ? ", " : "", o->name);
  if (o->kind != CLI_FLAG && o->kind != CLI_CLEAR && n > 0 && (size_t)n < sizeof left)
    snprintf(left + n, sizeof left - (size_t)n, " %s", o->meta ? o->meta : "X");
  const int col = 26;
  fputs(left, f);
  int len = (int)strlen(left);
  if (len + 1 > col) fputc('\n', f), len = 0;
  for (const char *p = o->help ? o->help : ""; *p;) {
    const char *nl = strchr(p, '\n');
    int k = nl ? (int)(nl - p) : (int)strlen(p);
    fprintf(f, "%*s%.*s\n", col - len, "", k, p);
    len = 0;
    p = nl ? nl + 1 : p + k;
  }
  if (!o->help || !*o->help) fputc('\n', f);
}

void cli_print_help(const cli_cmd *cmd, FILE *f) {
  fputs(cmd->usage, f);
  fputs("\noptions:\n", f);
  for (int t = 0; t < CLI_MAX_TABLES && cmd->tables[t].opts; t++)
    for (const cli_opt *o = cmd->tables[t].opts; o->name; o++)
      if (o->help) print_opt(f, o);
  for (const cli_opt *o = COMMON; o->name; o++) print_opt(f, o);
  if (cmd->epilog) fprintf(f, "\n%s", cmd->epilog);
}
