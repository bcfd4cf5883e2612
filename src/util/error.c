#include "woven/error.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

wv_status wv_fail(wv_error *err, wv_status code, const char *fmt, ...) {
  if (err) {
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err->msg, sizeof err->msg, fmt, ap);
    va_end(ap);
    err->code = code;
  }
  return code;
}

void wv_error_prefix(wv_error *err, const char *fmt, ...) {
  if (!err) return;
  char pre[512], old[sizeof err->msg];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(pre, sizeof pre, fmt, ap);
  va_end(ap);
  memcpy(old, err->msg, sizeof old);
  int n = snprintf(err->msg, sizeof err->msg, "%s: %s", pre, old);
  (void)n; /* truncation of very long messages is acceptable */
}
