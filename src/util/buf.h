/* A growing byte buffer for files assembled in memory (the glTF binary, the
 * viewer page). A failed allocation sets `failed` and later appends do nothing,
 * so a writer checks once at the end. */
#ifndef WOVEN_BUF_H
#define WOVEN_BUF_H

#include <stdlib.h>
#include <string.h>

typedef struct {
  unsigned char *data; /* NUL-terminated after every append */
  size_t len, cap;
  int failed;
} wv_buf;

static inline void wv_buf_put(wv_buf *b, const void *src, size_t n) {
  if (b->failed) return;
  if (b->len + n + 1 > b->cap) {
    size_t cap = (b->len + n + 1) * 2;
    unsigned char *d = realloc(b->data, cap);
    if (!d) {
      b->failed = 1;
      return;
    }
    b->data = d, b->cap = cap;
  }
  memcpy(b->data + b->len, src, n);
  b->len += n;
  b->data[b->len] = 0;
}

static inline void wv_buf_puts(wv_buf *b, const char *s) { wv_buf_put(b, s, strlen(s)); }

#endif
