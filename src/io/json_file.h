/* JSON files read whole: at most WV_JSON_MAX_BYTES, regular files only (io/file.c),
 * then parsed by util/json.h. Internal to the library. */
#ifndef WOVEN_IO_JSON_FILE_H
#define WOVEN_IO_JSON_FILE_H

#include "util/json.h"
#include "woven/error.h"

/* A whole text file of at most WV_JSON_MAX_BYTES without NUL bytes; caller frees. */
wv_status wv_json_read_text(const char *path, char **text, wv_error *err);
/* wv_json_read_text, then parsed (duplicate keys refused). Messages start with the path. */
wv_status wv_json_load_file(const char *path, json_t **root, wv_error *err);
/* The same for a file whose top level must be an object. */
wv_status wv_json_load_object(const char *path, json_t **root, wv_error *err);

#endif
