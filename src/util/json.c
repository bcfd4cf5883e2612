/* woven: bounded JSON file reads and range-checked JSON values (see util/json.h). */
#include "util/json.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "woven/io.h"

const char *wv_num_str(double v, char *buf) {
  if (!isfinite(v)) {
    snprintf(buf, 32, "%s", isnan(v) ? "nan" : v > 0 ? "inf" : "-inf");
    return buf;
  }
  /* The fewest significant digits that read back as v, then written positionally
   * unless the exponent is large ("60", "10000", "60.0000000001", "1e+300"). */
  int prec = 1;
  for (; prec < 17; prec++) {
    snprintf(buf, 32, "%.*e", prec - 1, v);
    if (strtod(buf, NULL) == v) break;
  }
  snprintf(buf, 32, "%.*e", prec - 1, v);
  int e10 = atoi(strchr(buf, 'e') + 1);
  snprintf(buf, 32, "%.*g", e10 >= prec && e10 < 17 ? e10 + 1 : prec, v);
  return buf;
}

wv_status wv_json_read_text(const char *path, char **text, wv_error *err) {
  size_t len;
  wv_status st = wv_read_file_max(path, WV_JSON_MAX_BYTES, text, &len, err);
  if (st) return st;
  if (strlen(*text) != len) {
    free(*text);
    *text = NULL;
    return wv_fail(err, WV_ERR_FORMAT, "%s: file contains a NUL byte; not a JSON text", path);
  }
  return WV_OK;
}

wv_status wv_json_load_file(const char *path, json_t **root, wv_error *err) {
  char *text;
  *root = NULL;
  wv_status st = wv_json_read_text(path, &text, err);
  if (st) return st;
  json_error_t je;
  *root = json_loads(text, JSON_REJECT_DUPLICATES, &je);
  free(text);
  if (!*root) return wv_fail(err, WV_ERR_FORMAT, "%s:%d:%d: malformed JSON: %s", path, je.line, je.column, je.text);
  return WV_OK;
}

static void key_name(const char *obj, const char *key, char *buf, size_t cap) {
  snprintf(buf, cap, "%s%s%s", obj && *obj ? obj : "", obj && *obj ? "." : "", key);
}

wv_status wv_json_number_value(json_t *v, const char *name, double lo, double hi, double *out, wv_error *err) {
  char a[32], b[32], c[32];
  if (!json_is_number(v)) return wv_fail(err, WV_ERR_INVALID, "'%s' must be a number", name);
  double x = json_number_value(v);
  if (!(x >= lo && x <= hi))
    return wv_fail(err, WV_ERR_INVALID, "'%s' = %s is outside %s..%s", name, wv_num_str(x, a), wv_num_str(lo, b),
                   wv_num_str(hi, c));
  *out = x;
  return WV_OK;
}

wv_status wv_json_integer_value(json_t *v, const char *name, long long lo, long long hi, long long *out,
                                wv_error *err) {
  char a[32];
  if (!json_is_integer(v)) {
    if (json_is_real(v))
      return wv_fail(err, WV_ERR_INVALID, "'%s' must be an integer in %lld..%lld, not %s", name, lo, hi,
                     wv_num_str(json_real_value(v), a));
    return wv_fail(err, WV_ERR_INVALID, "'%s' must be an integer in %lld..%lld", name, lo, hi);
  }
  json_int_t x = json_integer_value(v);
  if (x < lo || x > hi)
    return wv_fail(err, WV_ERR_INVALID, "'%s' = %lld is outside %lld..%lld", name, (long long)x, lo, hi);
  *out = (long long)x;
  return WV_OK;
}

wv_status wv_json_number(json_t *o, const char *obj, const char *key, double lo, double hi, int required,
                         double *out, wv_error *err) {
  char name[256];
  key_name(obj, key, name, sizeof name);
  json_t *v = json_is_object(o) ? json_object_get(o, key) : NULL;
  if (!v) return required ? wv_fail(err, WV_ERR_INVALID, "missing '%s'", name) : WV_OK;
  return wv_json_number_value(v, name, lo, hi, out, err);
}

wv_status wv_json_integer(json_t *o, const char *obj, const char *key, long long lo, long long hi, int required,
                          long long *out, wv_error *err) {
  char name[256];
  key_name(obj, key, name, sizeof name);
  json_t *v = json_is_object(o) ? json_object_get(o, key) : NULL;
  if (!v) return required ? wv_fail(err, WV_ERR_INVALID, "missing '%s'", name) : WV_OK;
  return wv_json_integer_value(v, name, lo, hi, out, err);
}

wv_status wv_json_int(json_t *o, const char *obj, const char *key, int lo, int hi, int required, int *out,
                      wv_error *err) {
  long long x = *out;
  wv_status st = wv_json_integer(o, obj, key, lo, hi, required, &x, err);
  if (!st) *out = (int)x;
  return st;
}

json_t *wv_json_str_lossy(const char *s) {
  if (!s) return json_null();
  json_t *v = json_string(s);
  if (v) return v;
  /* Not UTF-8: each byte of an invalid sequence becomes U+FFFD. */
  size_t n = strlen(s), k = 0;
  char *b = malloc(3 * n + 1);
  if (!b) return json_null();
  for (size_t i = 0; i < n;) {
    unsigned char ch = (unsigned char)s[i];
    size_t len = ch < 0x80 ? 1 : (ch >> 5) == 6 ? 2 : (ch >> 4) == 14 ? 3 : (ch >> 3) == 30 ? 4 : 0;
    json_t *probe = len && i + len <= n ? json_stringn(s + i, len) : NULL; /* checks the sequence */
    if (probe) {
      json_decref(probe);
      memcpy(b + k, s + i, len), k += len, i += len;
    } else {
      memcpy(b + k, "\xef\xbf\xbd", 3), k += 3, i++;
    }
  }
  v = json_stringn(b, k);
  free(b);
  return v ? v : json_null();
}

json_t *wv_json_from_text(char *text) {
  json_t *v = text ? json_loads(text, 0, NULL) : NULL;
  free(text);
  return v ? v : json_null();
}
