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

wv_status wv_json_load_file(const char *path, json_t **root, wv_error *err) {
  char *text;
  *root = NULL;
  wv_status st = wv_json_read_text(path, &text, err);
  if (st) return st;
  st = wv_json_parse(text, path, root, err);
  free(text);
  return st;
}

wv_status wv_json_load_object(const char *path, json_t **root, wv_error *err) {
  char *text;
  *root = NULL;
  wv_status st = wv_json_read_text(path, &text, err);
  if (st) return st;
  st = wv_json_parse_object(text, path, root, err);
  free(text);
  return st;
}
