/* woven: capture batches (include/woven/batch.h): the photo list, the share of each
 * rank, the per-photo records and the summary table (JSON and HTML). */
#include <ctype.h>
#include <dirent.h>
#include <errno.h>
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <stdint.h>
#include <strings.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "io/json_file.h"
#include "util/json.h"
#include "woven/batch.h"
#include "woven/io.h"

static double now_s(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static int has_image_ext(const char *name) {
  static const char *const EXTS[] = {".png", ".jpg", ".jpeg", ".exr"};
  const char *dot = strrchr(name, '.');
  if (!dot) return 0;
  for (size_t i = 0; i < sizeof EXTS / sizeof EXTS[0]; i++)
    if (!strcasecmp(dot, EXTS[i])) return 1;
  return 0;
}

static int cmp_item(const void *a, const void *b) {
  return strcmp(((const wv_batch_item *)a)->photo, ((const wv_batch_item *)b)->photo);
}

/* Appends photo (relative to base when not absolute) to the list, named by its stem. */
static wv_status add_item(wv_batch_item **items, int *n, int *cap, const char *base, const char *photo,
                          const char *where, wv_error *err) {
  if (*n == *cap) {
    int nc = *cap ? 2 * *cap : 64;
    wv_batch_item *ni = realloc(*items, sizeof **items * (size_t)nc);
    if (!ni) return wv_fail(err, WV_ERR_NOMEM, "%s: out of memory for the photo list", where);
    *items = ni, *cap = nc;
  }
  wv_batch_item *it = &(*items)[*n];
  int len = photo[0] == '/' || !base ? snprintf(it->photo, sizeof it->photo, "%s", photo)
                                     : snprintf(it->photo, sizeof it->photo, "%s/%s", base, photo);
  if (len < 0 || (size_t)len >= sizeof it->photo) return wv_fail(err, WV_ERR_INVALID, "%s: path too long", where);
  const char *slash = strrchr(it->photo, '/'), *file = slash ? slash + 1 : it->photo;
  const char *dot = strrchr(file, '.');
  size_t nlen = dot && dot > file ? (size_t)(dot - file) : strlen(file);
  if (nlen == 0 || file[0] == '.' || nlen >= sizeof it->name)
    return wv_fail(err, WV_ERR_INVALID, "%s: %s: the photo's file name cannot name an output directory", where,
                   it->photo);
  memcpy(it->name, file, nlen);
  it->name[nlen] = 0;
  (*n)++;
  return WV_OK;
}

static wv_status list_dir(const char *list, wv_batch_item **items, int *n, int *cap, wv_error *err) {
  DIR *d = opendir(list);
  if (!d) return wv_fail(err, WV_ERR_IO, "%s: cannot open directory: %s", list, strerror(errno));
  wv_status st = WV_OK;
  for (struct dirent *e; !st && (e = readdir(d));)
    if (e->d_name[0] != '.' && has_image_ext(e->d_name)) st = add_item(items, n, cap, list, e->d_name, list, err);
  closedir(d);
  if (!st && *n > 1) qsort(*items, (size_t)*n, sizeof **items, cmp_item);
  return st;
}

static wv_status list_file(const char *list, wv_batch_item **items, int *n, int *cap, wv_error *err) {
  char *text;
  wv_status st = wv_read_file_max(list, WV_JSON_MAX_BYTES, &text, NULL, err);
  if (st) return st;
  char base[4096];
  snprintf(base, sizeof base, "%s", list);
  char *slash = strrchr(base, '/');
  if (slash) *slash = 0;
  int line = 0;
  for (char *s = text, *next; s && *s && !st; s = next) {
    next = strchr(s, '\n');
    if (next) *next++ = 0;
    line++;
    size_t len = strlen(s);
    while (len && isspace((unsigned char)s[len - 1])) s[--len] = 0;
    while (isspace((unsigned char)*s)) s++;
    if (!*s || *s == '#') continue;
    char where[4200];
    snprintf(where, sizeof where, "%s:%d", list, line);
    st = add_item(items, n, cap, slash ? base : NULL, s, where, err);
  }
  free(text);
  return st;
}

/* Names the batch's own files take in DIR: a photo may not be captured into one. */
static int reserved_name(const char *name) {
  return !strcmp(name, "summary.json") || !strcmp(name, "summary.html") || !strncmp(name, "woven.lock", 10) ||
         wv_is_temp_name(name);
}

static uint64_t name_hash(const char *s) {
  uint64_t h = 1469598103934665603ULL; /* FNV-1a */
  for (; *s; s++) h = (h ^ (unsigned char)*s) * 1099511628211ULL;
  return h;
}

/* Every photo gets its own output directory: reserved names are refused, and
 * duplicates found with a hash set (open addressing, at most half full). */
static wv_status check_names(const char *list, const wv_batch_item *items, int n, wv_error *err) {
  size_t cap = 16;
  while (cap < 2 * (size_t)n) cap *= 2;
  int *slot = malloc(cap * sizeof *slot);
  if (!slot) return wv_fail(err, WV_ERR_NOMEM, "%s: out of memory for the photo list", list);
  for (size_t i = 0; i < cap; i++) slot[i] = -1;
  wv_status st = WV_OK;
  for (int i = 0; i < n && !st; i++) {
    if (reserved_name(items[i].name)) {
      st = wv_fail(err, WV_ERR_INVALID, "%s: %s would be captured into '%s', a name the batch keeps for its own files "
                   "(summary.json, summary.html, woven.lock*); rename the photo", list, items[i].photo, items[i].name);
      break;
    }
    for (size_t k = name_hash(items[i].name) & (cap - 1);; k = (k + 1) & (cap - 1)) {
      if (slot[k] < 0) {
        slot[k] = i;
        break;
      }
      if (!strcmp(items[slot[k]].name, items[i].name)) {
        st = wv_fail(err, WV_ERR_INVALID, "%s: %s and %s would both be captured into '%s'; rename one", list,
                     items[slot[k]].photo, items[i].photo, items[i].name);
        break;
      }
    }
  }
  free(slot);
  return st;
}

wv_status wv_batch_list(const char *list, wv_batch_item **items, int *n, wv_error *err) {
  *items = NULL, *n = 0;
  int cap = 0;
  struct stat sb;
  if (stat(list, &sb) != 0) return wv_fail(err, WV_ERR_IO, "%s: cannot read the photo list: %s", list, strerror(errno));
  wv_status st = S_ISDIR(sb.st_mode) ? list_dir(list, items, n, &cap, err) : list_file(list, items, n, &cap, err);
  if (!st && *n == 0)
    st = wv_fail(err, WV_ERR_INVALID, "%s: no photos (a directory of .png/.jpg/.exr files, or a file of paths)", list);
  if (!st) st = check_names(list, *items, *n, err);
  if (st) free(*items), *items = NULL, *n = 0;
  return st;
}

/* ---- per-photo records: DIR/.batch/<name>.json ---- */

static void path_of(char *buf, size_t cap, const char *dir, const char *sub, const char *name, const char *ext) {
  snprintf(buf, cap, "%s%s/%s%s", dir, sub, name, ext);
}

static int finished(const char *dir, const char *name) {
  char p[8192];
  struct stat sb;
  path_of(p, sizeof p, dir, "", name, "/params.json");
  return stat(p, &sb) == 0;
}

static json_t *num_or_null(double v) { return isfinite(v) ? json_real(v) : json_null(); }

static wv_status write_record(const char *dir, const wv_batch_item *it, const wv_batch_result *r, double seconds,
                              int rank, wv_error *err) {
  char host[256] = "", path[8192];
  if (gethostname(host, sizeof host) != 0) host[0] = 0;
  host[sizeof host - 1] = 0;
  json_t *o = json_pack("{s:s,s:s,s:s,s:i,s:s,s:s,s:o,s:o,s:o,s:i,s:f,s:s,s:i}", "photo", it->photo, "name",
                        it->name, "status", r->status ? "failed" : "ok", "code", r->status, "error", r->error,
                        "pattern", r->pattern, "ssim_start", num_or_null(r->ssim_start), "ssim_fit",
                        num_or_null(r->ssim_fit), "wsc", num_or_null(r->wsc), "iterations", r->iterations,
                        "seconds", seconds, "host", host, "rank", rank);
  char *text = o ? json_dumps(o, JSON_INDENT(2) | JSON_PRESERVE_ORDER | JSON_REAL_PRECISION(8)) : NULL;
  json_decref(o);
  path_of(path, sizeof path, dir, "/.batch", it->name, ".json");
  wv_status st = text ? wv_write_file_atomic(path, text, strlen(text), err)
                      : wv_fail(err, WV_ERR_NOMEM, "%s: out of memory", path);
  free(text);
  return st;
}

/* ---- the summary ---- */

static void html_text(FILE *f, const char *s) {
  for (; *s; s++) switch (*s) {
      case '&': fputs("&amp;", f); break;
      case '<': fputs("&lt;", f); break;
      case '>': fputs("&gt;", f); break;
      case '"': fputs("&quot;", f); break;
      default: fputc(*s, f);
    }
}

static void html_url(FILE *f, const char *s) {
  for (; *s; s++)
    if (isalnum((unsigned char)*s) || strchr("._-", *s))
      fputc(*s, f);
    else
      fprintf(f, "%%%02X", (unsigned char)*s);
}

static void html_num(FILE *f, json_t *v, const char *fmt) {
  if (json_is_number(v))
    fprintf(f, fmt, json_number_value(v));
  else
    fputs("&ndash;", f);
}

static wv_status write_summary(const char *dir, const char *list, const wv_batch_item *items, int n, wv_error *err) {
  json_t *rows = json_array();
  int ok = 0, failed = 0;
  for (int i = 0; i < n; i++) {
    char path[8192];
    path_of(path, sizeof path, dir, "/.batch", items[i].name, ".json");
    json_t *rec = NULL;
    wv_error e;
    if (access(path, F_OK) == 0 && wv_json_load_file(path, &rec, &e)) rec = NULL;
    const char *status = finished(dir, items[i].name) ? "ok" : rec ? "failed" : "not done";
    ok += !strcmp(status, "ok"), failed += !strcmp(status, "failed");
    json_t *row = json_pack("{s:s,s:s,s:s}", "name", items[i].name, "photo", items[i].photo, "status", status);
    static const char *const KEYS[] = {"pattern", "ssim_start", "ssim_fit", "wsc", "iterations", "seconds", "error"};
    for (size_t k = 0; k < sizeof KEYS / sizeof KEYS[0]; k++) {
      json_t *v = rec ? json_object_get(rec, KEYS[k]) : NULL;
      /* a finished capture's record is its own; an older failure's error no longer applies */
      if (!strcmp(KEYS[k], "error") && strcmp(status, "failed")) v = NULL;
      json_object_set(row, KEYS[k], v ? v : json_null());
    }
    json_decref(rec);
    json_array_append_new(rows, row);
  }
  json_t *o = json_pack("{s:s,s:i,s:s,s:i,s:i,s:i,s:i,s:o}", "kind", "woven-capture-batch", "version", 1, "list",
                        list, "photos", n, "ok", ok, "failed", failed, "not_done", n - ok - failed, "items", rows);
  char *text = o ? json_dumps(o, JSON_INDENT(2) | JSON_PRESERVE_ORDER | JSON_REAL_PRECISION(8)) : NULL;
  char path[8192];
  snprintf(path, sizeof path, "%s/summary.json", dir);
  wv_status st = text ? wv_write_file_atomic(path, text, strlen(text), err)
                      : wv_fail(err, WV_ERR_NOMEM, "%s: out of memory", path);
  free(text);
  char *html = NULL;
  size_t hlen = 0;
  FILE *f = st ? NULL : open_memstream(&html, &hlen);
  if (!st && !f) st = wv_fail(err, WV_ERR_NOMEM, "out of memory for summary.html");
  if (f) {
    fputs("<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>woven capture batch</title>\n<style>"
          "body{font-family:sans-serif;margin:2em}table{border-collapse:collapse}td,th{border:1px solid #ccc;"
          "padding:4px 8px;text-align:left}td.n{text-align:right}.failed{color:#b00}img{height:60px}"
          "</style></head><body>\n<h1>woven capture batch</h1>\n<p>",
          f);
    html_text(f, list);
    fprintf(f, ": %d photos, %d captured, %d failed, %d not done. SSIM is the luma SSIM of the render against the "
               "photo (network estimate &rarr; fit); WSC: the weave-spectrum correlation of the fit with the photo.</p>\n<table>\n"
               "<tr><th>photo</th><th>status</th><th>pattern</th><th>SSIM network</th><th>SSIM fit</th><th>WSC</th>"
               "<th>iterations</th><th>time (s)</th><th>result</th></tr>\n",
            n, ok, failed, n - ok - failed);
    for (int i = 0; i < n; i++) {
      json_t *r = json_array_get(rows, (size_t)i);
      const char *status = json_string_value(json_object_get(r, "status"));
      const char *pat = json_string_value(json_object_get(r, "pattern"));
      fputs("<tr><td>", f);
      html_text(f, items[i].photo);
      fprintf(f, "</td><td class=\"%s\">%s", !strcmp(status, "failed") ? "failed" : "", status);
      const char *why = json_string_value(json_object_get(r, "error"));
      if (why && *why) fputs(": ", f), html_text(f, why);
      fputs("</td><td>", f);
      html_text(f, pat && *pat ? pat : "");
      fputs("</td><td class=\"n\">", f);
      html_num(f, json_object_get(r, "ssim_start"), "%.4f");
      fputs("</td><td class=\"n\">", f);
      html_num(f, json_object_get(r, "ssim_fit"), "%.4f");
      fputs("</td><td class=\"n\">", f);
      html_num(f, json_object_get(r, "wsc"), "%.4f");
      fputs("</td><td class=\"n\">", f);
      html_num(f, json_object_get(r, "iterations"), "%.0f");
      fputs("</td><td class=\"n\">", f);
      html_num(f, json_object_get(r, "seconds"), "%.1f");
      fputs("</td><td>", f);
      if (!strcmp(status, "ok")) {
        fputs("<a href=\"", f), html_url(f, items[i].name), fputs("/report.html\"><img src=\"", f);
        html_url(f, items[i].name), fputs("/compare.png\" alt=\"photo | network | fit\"></a>", f);
      }
      fputs("</td></tr>\n", f);
    }
    fputs("</table>\n</body></html>\n", f);
    fclose(f);
    snprintf(path, sizeof path, "%s/summary.html", dir);
    st = html ? wv_write_file_atomic(path, html, hlen, err) : wv_fail(err, WV_ERR_NOMEM, "out of memory");
  }
  free(html);
  json_decref(o);
  return st;
}

static int item_done(void *user, int k) {
  const void *const *u = user;
  const wv_batch_item *items = u[1];
  return finished(u[0], items[k].name);
}

static int mkdir_ok(const char *p) {
  struct stat sb;
  if (stat(p, &sb) == 0) return S_ISDIR(sb.st_mode);
  return mkdir(p, 0777) == 0;
}

wv_status wv_batch_run(const wv_dist *d, const wv_batch_opts *o, wv_batch_summary *sum, char *note, size_t note_cap,
                       wv_error *err) {
  memset(sum, 0, sizeof *sum);
  if (note_cap) note[0] = 0;
  wv_batch_item *items = NULL;
  int n = 0, *mine = NULL, nmine = 0, ntodo = 0;
  wv_status st = wv_batch_list(o->list, &items, &n, err);
  wv_dir_lock lock = {{0}, 0};
  char path[8192];
  /* rank 0 prepares the directory; the others start once it is ready */
  if (!st && d->rank == 0) {
    char work[8192];
    snprintf(path, sizeof path, "%s/.batch", o->dir);
    snprintf(work, sizeof work, "%s/.batch/work", o->dir);
    if (!mkdir_ok(o->dir))
      st = wv_fail(err, WV_ERR_IO, "%s: cannot create the output directory: %s", o->dir, strerror(errno));
    else if (!(st = wv_dir_lock_acquire(o->dir, &lock, note, note_cap, err)) && (!mkdir_ok(path) || !mkdir_ok(work)))
      st = wv_fail(err, WV_ERR_IO, "%s: cannot create a directory: %s", work, strerror(errno));
    /* what killed runs left: temporary files of records, of captures and of the summary */
    if (!st) wv_remove_stale_temps(path, NULL), wv_remove_stale_temps(work, NULL), wv_remove_stale_temps(o->dir, NULL);
  }
  int st0 = st;
  wv_dist_bcast_ints(d, &st0, 1);
  int any = wv_dist_max_int(d, st ? (int)st : st0);
  if (any && !st) st = (wv_status)any; /* failed elsewhere: the message is there */
  const void *u[2] = {o->dir, items};
  if (!st) st = wv_dist_share(d, n, item_done, (void *)u, &mine, &nmine, &ntodo, err);
  sum->photos = n, sum->done_before = n - ntodo;
  double t0 = now_s();
  int captured = 0, failed = 0;
  for (int t = 0; t < nmine && !st; t++) {
    const wv_batch_item *it = &items[mine[t]];
    char work[8192], final[8192];
    path_of(work, sizeof work, o->dir, "/.batch/work", it->name, "");
    path_of(final, sizeof final, o->dir, "", it->name, "");
    wv_batch_result r;
    memset(&r, 0, sizeof r);
    r.ssim_start = r.ssim_fit = r.wsc = NAN;
    double t1 = now_s();
    r.status = o->capture(o->user, it->photo, work, &r);
    double secs = now_s() - t1;
    if (!r.status && access(final, F_OK) == 0) {
      r.status = WV_ERR_IO;
      snprintf(r.error, sizeof r.error, "%.900s exists and holds no finished capture (no params.json); remove it", final);
    }
    if (r.status && !r.error[0]) snprintf(r.error, sizeof r.error, "the capture failed (exit %d)", r.status);
    /* the record first: a capture in place always has one */
    st = write_record(o->dir, it, &r, secs, d->rank, err);
    if (!st && !r.status && rename(work, final) != 0) {
      r.status = WV_ERR_IO;
      snprintf(r.error, sizeof r.error, "cannot move %.450s to %.450s: %.80s", work, final, strerror(errno));
      st = write_record(o->dir, it, &r, secs, d->rank, err);
    }
    if (st) break;
    if (r.status)
      failed++;
    else
      captured++;
    if (o->on_photo) o->on_photo(o->user, it, &r, secs, captured + failed, nmine);
  }
  sum->seconds = wv_dist_max_double(d, now_s() - t0);
  sum->captured = wv_dist_sum_int(d, captured);
  int fails_now = wv_dist_sum_int(d, failed);
  int bad = wv_dist_max_int(d, (int)st);
  if (!st && bad) st = (wv_status)bad;
  if (!bad && d->rank == 0) st = write_summary(o->dir, o->list, items, n, err);
  if (!bad) sum->failed = fails_now;
  wv_dir_lock_release(&lock);
  free(items);
  free(mine);
  return st;
}
