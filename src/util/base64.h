/* Base64 (RFC 4648, with padding): images and scripts carried inside HTML pages. */
#ifndef WOVEN_BASE64_H
#define WOVEN_BASE64_H

#include <stddef.h>

/* A malloc'ed NUL-terminated encoding of len bytes, or NULL when out of memory. */
char *wv_base64(const void *data, size_t len);

#endif
