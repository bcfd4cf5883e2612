/* woven: error reporting shared by every module.
 * Functions return a wv_status and, on failure, fill a wv_error the caller owns. */
#ifndef WOVEN_ERROR_H
#define WOVEN_ERROR_H

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
  WV_OK = 0,
  WV_ERR_INVALID = 2, /* bad parameter or input value */
  WV_ERR_IO = 3,      /* file cannot be read or written */
  WV_ERR_FORMAT = 4,  /* file exists but its content is malformed */
  WV_ERR_NOMEM = 5,   /* allocation failed or request too large */
  WV_ERR_INTERNAL = 6
} wv_status;

typedef struct {
  wv_status code;
  char msg[1024];
} wv_error;

/* Record an error (printf-style) and return its code; err may be NULL. */
wv_status wv_fail(wv_error *err, wv_status code, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
/* Prefix an existing message, e.g. with a file name. */
void wv_error_prefix(wv_error *err, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

#ifdef __cplusplus
}
#endif
#endif
