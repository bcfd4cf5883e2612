/* woven: reading JSON files and checked values (internal, shared by every module
 * that parses JSON). Files are read with a size limit; objects hold only the keys
 * asked for; numbers are range-checked with messages that name the key and print
 * the value as written ('twist_deg' = 60.0000000001 is outside -60..60), and
 * integers are taken only when the JSON holds an integer in the range asked for.
 *
 * Every reader takes the object o, the object's name obj for messages (NULL or ""
 * at the top level; messages name 'obj.key') and the key. An absent key is an error
 * ("missing 'obj.key'") when flags hold WV_JSON_REQUIRED, otherwise *out is left
 * as it is: the caller sets the default first. */
#ifndef WOVEN_UTIL_JSON_H
#define WOVEN_UTIL_JSON_H

#include <float.h>
#include <jansson.h>
#include <stddef.h>

#include "woven/error.h"

/* The shortest decimal form that reads back as v (so 60.0000000001 is not
 * shown as 60); returns buf, which must hold 32 bytes. */
const char *wv_num_str(double v, char *buf);

/* A JSON text (duplicate keys refused); messages start with source
 * ("source:line:column: malformed JSON: ..."). The caller frees *root. */
wv_status wv_json_parse(const char *text, const char *source, json_t **root, wv_error *err);
/* The same for a text whose top level must be an object. */
wv_status wv_json_parse_object(const char *text, const char *source, json_t **root, wv_error *err);
/* JSON files are read by io/json_file.h. */

/* The flags of the readers below (1 and 0 also read as required / optional). */
enum {
  WV_JSON_OPTIONAL = 0,
  WV_JSON_REQUIRED = 1,
  WV_JSON_ONE_FOR_ALL = 2, /* wv_json_numbers: one number stands for every element (a grey colour) */
  WV_JSON_NONEMPTY = 4     /* wv_json_string: "" is refused */
};

/* lo, hi of a number that may take any finite value (JSON holds no other), for values
 * whose ranges are checked later, on the struct they fill. */
#define WV_JSON_FINITE (-DBL_MAX), DBL_MAX

/* A key's name in messages: "obj.key", or "key" when obj is NULL or "". */
void wv_json_key_name(const char *obj, const char *key, char *buf, size_t cap);

/* o must be an object holding only keys (NULL-terminated): a typo must not silently
 * change a result. "'obj' must be an object", "unknown key 'obj.k' (expected a, b or c)". */
wv_status wv_json_only_keys(json_t *o, const char *obj, const char *const *keys, wv_error *err);
/* o[key] as a nested object holding only keys (any keys when keys is NULL); *out is
 * NULL when it is absent and optional. */
wv_status wv_json_object(json_t *o, const char *obj, const char *key, const char *const *keys, int flags,
                         json_t **out, wv_error *err);

/* o[key] as a number / integer in lo..hi (so finite). A JSON real is not an integer,
 * whatever its value. Wrong values return WV_ERR_INVALID. */
wv_status wv_json_number(json_t *o, const char *obj, const char *key, double lo, double hi, int flags,
                         double *out, wv_error *err);
wv_status wv_json_integer(json_t *o, const char *obj, const char *key, long long lo, long long hi, int flags,
                          long long *out, wv_error *err);
/* The same for an int destination (lo and hi within the int range). */
wv_status wv_json_int(json_t *o, const char *obj, const char *key, int lo, int hi, int flags, int *out,
                      wv_error *err);
/* o[key] as n numbers in lo..hi: an array of n ("'obj.key' must be an array of n
 * numbers"), or one number for all n with WV_JSON_ONE_FOR_ALL; elements are named
 * 'obj.key[i]'. */
wv_status wv_json_numbers(json_t *o, const char *obj, const char *key, int n, double lo, double hi, int flags,
                          double *out, wv_error *err);
/* o[key] as a string (valid while o lives); WV_JSON_NONEMPTY refuses "". */
wv_status wv_json_string(json_t *o, const char *obj, const char *key, int flags, const char **out, wv_error *err);
/* o[key] as true (1) or false (0). */
wv_status wv_json_bool(json_t *o, const char *obj, const char *key, int flags, int *out, wv_error *err);

/* A table of names and values, ended by a NULL name. */
typedef struct {
  const char *name;
  int value;
} wv_json_enum;
/* o[key] as one of the table's names, *out its value:
 * "'obj.key' = 'x': expected a, b or c" (and "'obj.key' must be a string: ..."). */
wv_status wv_json_enum_of(json_t *o, const char *obj, const char *key, const wv_json_enum *table, int flags,
                          int *out, wv_error *err);

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
