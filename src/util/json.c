/* woven: range-checked JSON values (see util/json.h). */
#include "util/json.h"

#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>


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

wv_status wv_json_parse(const char *text, const char *source, json_t **root, wv_error *err) {
  json_error_t je;
  *root = json_loads(text, JSON_REJECT_DUPLICATES, &je);
  if (!*root) return wv_fail(err, WV_ERR_FORMAT, "%s:%d:%d: malformed JSON: %s", source, je.line, je.column, je.text);
  return WV_OK;
}

static wv_status need_object(const char *source, json_t **root, wv_error *err) {
  if (json_is_object(*root)) return WV_OK;
  json_decref(*root);
  *root = NULL;
  return wv_fail(err, WV_ERR_INVALID, "%s: top level must be a JSON object", source);
}

wv_status wv_json_parse_object(const char *text, const char *source, json_t **root, wv_error *err) {
  wv_status st = wv_json_parse(text, source, root, err);
  return st ? st : need_object(source, root, err);
}

void wv_json_key_name(const char *obj, const char *key, char *buf, size_t cap) {
  snprintf(buf, cap, "%s%s%s", obj && *obj ? obj : "", obj && *obj ? "." : "", key);
}

/* o[key], or NULL when absent (then an error when required: *st says which). */
static json_t *member(json_t *o, const char *obj, const char *key, int flags, char *name, size_t cap,
                      wv_status *st, wv_error *err) {
  wv_json_key_name(obj, key, name, cap);
  json_t *v = json_is_object(o) ? json_object_get(o, key) : NULL;
  *st = !v && (flags & WV_JSON_REQUIRED) ? wv_fail(err, WV_ERR_INVALID, "missing '%s'", name) : WV_OK;
  return v;
}

/* "a, b or c" from names one stride of bytes apart up to a NULL (a list of names, or
 * the names of a table), cut to fit cap. */
static void or_list(const char *const *names, size_t stride, char *buf, size_t cap) {
  size_t n = 0, len = 0;
  while (*(const char *const *)((const char *)names + n * stride)) n++;
  buf[0] = '\0';
  for (size_t i = 0; i < n && len < cap; i++) {
    const char *s = *(const char *const *)((const char *)names + i * stride);
    int w = snprintf(buf + len, cap - len, "%s%s", i == 0 ? "" : i + 1 == n ? " or " : ", ", s);
    len += w > 0 ? (size_t)w : 0;
  }
}

wv_status wv_json_only_keys(json_t *o, const char *obj, const char *const *keys, wv_error *err) {
  if (!json_is_object(o)) return wv_fail(err, WV_ERR_INVALID, "'%s' must be an object", obj ? obj : "");
  const char *k;
  json_t *v;
  json_object_foreach(o, k, v) {
    int known = 0;
    for (int i = 0; keys[i] && !known; i++) known = !strcmp(k, keys[i]);
    if (!known) {
      char name[256], list[512];
      wv_json_key_name(obj, k, name, sizeof name);
      or_list(keys, sizeof *keys, list, sizeof list);
      return wv_fail(err, WV_ERR_INVALID, "unknown key '%s' (expected %s)", name, list);
    }
  }
  return WV_OK;
}

wv_status wv_json_object(json_t *o, const char *obj, const char *key, const char *const *keys, int flags,
                         json_t **out, wv_error *err) {
  char name[256];
  wv_status st;
  json_t *v = member(o, obj, key, flags, name, sizeof name, &st, err);
  *out = NULL;
  if (!v) return st;
  if (!json_is_object(v)) return wv_fail(err, WV_ERR_INVALID, "'%s' must be an object", name);
  if (keys && (st = wv_json_only_keys(v, name, keys, err))) return st;
  *out = v;
  return WV_OK;
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
  char a[32], range[64] = "";
  if (lo != LLONG_MIN || hi != LLONG_MAX) snprintf(range, sizeof range, " in %lld..%lld", lo, hi);
  if (!json_is_integer(v)) {
    if (json_is_real(v))
      return wv_fail(err, WV_ERR_INVALID, "'%s' must be an integer%s, not %s", name, range,
                     wv_num_str(json_real_value(v), a));
    return wv_fail(err, WV_ERR_INVALID, "'%s' must be an integer%s", name, range);
  }
  json_int_t x = json_integer_value(v);
  if (x < lo || x > hi)
    return wv_fail(err, WV_ERR_INVALID, "'%s' = %lld is outside %lld..%lld", name, (long long)x, lo, hi);
  *out = (long long)x;
  return WV_OK;
}

wv_status wv_json_number(json_t *o, const char *obj, const char *key, double lo, double hi, int flags,
                         double *out, wv_error *err) {
  char name[256];
  wv_status st;
  json_t *v = member(o, obj, key, flags, name, sizeof name, &st, err);
  return v ? wv_json_number_value(v, name, lo, hi, out, err) : st;
}

wv_status wv_json_integer(json_t *o, const char *obj, const char *key, long long lo, long long hi, int flags,
                          long long *out, wv_error *err) {
  char name[256];
  wv_status st;
  json_t *v = member(o, obj, key, flags, name, sizeof name, &st, err);
  return v ? wv_json_integer_value(v, name, lo, hi, out, err) : st;
}

wv_status wv_json_int(json_t *o, const char *obj, const char *key, int lo, int hi, int flags, int *out,
                      wv_error *err) {
  long long x = *out;
  wv_status st = wv_json_integer(o, obj, key, lo, hi, flags, &x, err);
  if (!st) *out = (int)x;
  return st;
}

wv_status wv_json_numbers(json_t *o, const char *obj, const char *key, int n, double lo, double hi, int flags,
                          double *out, wv_error *err) {
  char name[256], elem[280];
  wv_status st;
  json_t *v = member(o, obj, key, flags, name, sizeof name, &st, err);
  if (!v) return st;
  if ((flags & WV_JSON_ONE_FOR_ALL) && json_is_number(v)) {
    double x;
    if ((st = wv_json_number_value(v, name, lo, hi, &x, err))) return st;
    for (int i = 0; i < n; i++) out[i] = x;
    return WV_OK;
  }
  if (!json_is_array(v) || json_array_size(v) != (size_t)n)
    return wv_fail(err, WV_ERR_INVALID, "'%s' must be an array of %d numbers", name, n);
  for (int i = 0; i < n; i++) {
    snprintf(elem, sizeof elem, "%s[%d]", name, i);
    if ((st = wv_json_number_value(json_array_get(v, (size_t)i), elem, lo, hi, &out[i], err))) return st;
  }
  return WV_OK;
}

wv_status wv_json_string(json_t *o, const char *obj, const char *key, int flags, const char **out, wv_error *err) {
  char name[256];
  wv_status st;
  json_t *v = member(o, obj, key, flags, name, sizeof name, &st, err);
  if (!v) return st;
  int nonempty = (flags & WV_JSON_NONEMPTY) != 0;
  if (!json_is_string(v) || (nonempty && !json_string_length(v)))
    return wv_fail(err, WV_ERR_INVALID, "'%s' must be a %sstring", name, nonempty ? "non-empty " : "");
  *out = json_string_value(v);
  return WV_OK;
}

wv_status wv_json_bool(json_t *o, const char *obj, const char *key, int flags, int *out, wv_error *err) {
  char name[256];
  wv_status st;
  json_t *v = member(o, obj, key, flags, name, sizeof name, &st, err);
  if (!v) return st;
  if (!json_is_boolean(v)) return wv_fail(err, WV_ERR_INVALID, "'%s' must be true or false", name);
  *out = json_is_true(v);
  return WV_OK;
}

wv_status wv_json_enum_of(json_t *o, const char *obj, const char *key, const wv_json_enum *table, int flags,
                          int *out, wv_error *err) {
  char name[256], list[512];
  wv_status st;
  json_t *v = member(o, obj, key, flags, name, sizeof name, &st, err);
  if (!v) return st;
  const char *s = json_string_value(v); /* NULL when not a string */
  for (int i = 0; s && table[i].name; i++)
    if (!strcmp(s, table[i].name)) {
      *out = table[i].value;
      return WV_OK;
    }
  or_list(&table[0].name, sizeof *table, list, sizeof list);
  if (!s) return wv_fail(err, WV_ERR_INVALID, "'%s' must be a string: expected %s", name, list);
  return wv_fail(err, WV_ERR_INVALID, "'%s' = '%s': expected %s", name, s, list);
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
