/* woven: the status-and-message error type every library function fills (woven/error.h). */
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
  /* Assemble by hand: very long messages are truncated, never overflowed. */
  size_t cap = sizeof err->msg - 1, n = 0;
  for (const char *p = pre; *p && n < cap; p++) err->msg[n++] = *p;
  for (const char *p = ": "; *p && n < cap; p++) err->msg[n++] = *p;
  for (const char *p = old; *p && n < cap; p++) err->msg[n++] = *p;
  err->msg[n] = '\0';
}
