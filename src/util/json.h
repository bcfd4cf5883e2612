/* woven: reading JSON files and checked values (internal, shared by every module
 * that parses JSON). Files are read with a size limit; numbers are range-checked
 * with messages that name the key and print the value as written, and integers
 * are taken only when the JSON holds an integer in the int range asked for. */
#ifndef WOVEN_UTIL_JSON_H
#define WOVEN_UTIL_JSON_H

#include <jansson.h>

#include "woven/error.h"

/* The shortest decimal form that reads back as v (so 60.0000000001 is not
 * shown as 60); returns buf, which must hold 32 bytes. */
const char *wv_num_str(double v, char *buf);

/* A whole text file of at most WV_JSON_MAX_BYTES without NUL bytes; caller frees. */
wv_status wv_json_read_text(const char *path, char **text, wv_error *err);
/* wv_json_read_text, then parsed (duplicate keys refused). Messages start with the path. */
wv_status wv_json_load_file(const char *path, json_t **root, wv_error *err);

/* o[key] as a number / integer in lo..hi. Absent: an error when required, otherwise
 * *out is left as it is. Messages name 'obj.key' (just 'key' when obj is NULL or "")
 * and return WV_ERR_INVALID. A JSON real is not an integer, whatever its value. */
wv_status wv_json_number(json_t *o, const char *obj, const char *key, double lo, double hi, int required,
                         double *out, wv_error *err);
wv_status wv_json_integer(json_t *o, const char *obj, const char *key, long long lo, long long hi, int required,
                          long long *out, wv_error *err);
/* The same for an int destination (lo and hi within the int range). */
wv_status wv_json_int(json_t *o, const char *obj, const char *key, int lo, int hi, int required, int *out,
                      wv_error *err);
/* One value (not a member): for array elements; name is the full key for messages. */
wv_status wv_json_number_value(json_t *v, const char *name, double lo, double hi, double *out, wv_error *err);
wv_status wv_json_integer_value(json_t *v, const char *name, long long lo, long long hi, long long *out,
                                wv_error *err);

/* s as a JSON string (each byte of a sequence that is not UTF-8 becomes U+FFFD); null
 * when s is NULL or memory runs out. */
json_t *wv_json_str_lossy(const char *s);

/* A JSON text as a value (null when text is NULL or not JSON); frees text. */
json_t *wv_json_from_text(char *text);

#endif
