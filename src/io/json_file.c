/* woven: JSON files read whole and parsed (see io/json_file.h). */
#include "io/json_file.h"

#include <stdlib.h>
#include <string.h>

#include "woven/io.h"

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

/* The file parsed; with object set its top level must be an object. */
static wv_status load(const char *path, int object, json_t **root, wv_error *err) {
  char *text;
  *root = NULL;
  wv_status st = wv_json_read_text(path, &text, err);
  if (st) return st;
  st = object ? wv_json_parse_object(text, path, root, err) : wv_json_parse(text, path, root, err);
  free(text);
  return st;
}

wv_status wv_json_load_file(const char *path, json_t **root, wv_error *err) { return load(path, 0, root, err); }

wv_status wv_json_load_object(const char *path, json_t **root, wv_error *err) { return load(path, 1, root, err); }
