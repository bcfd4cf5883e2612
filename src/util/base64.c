/* Base64 encoding (RFC 4648): three bytes become four characters of the
 * 64-letter alphabet, the last group padded with '='. */
#include "util/base64.h"

#include <stdlib.h>

char *wv_base64(const void *data, size_t len) {
  static const char tab[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  if (len > ((size_t)-1 / 4 - 1) / 4 * 3) return NULL;
  char *out = malloc((len + 2) / 3 * 4 + 1);
  if (!out) return NULL;
  const unsigned char *d = data;
  char *o = out;
  for (size_t i = 0; i < len; i += 3) {
    unsigned v = (unsigned)d[i] << 16 | (i + 1 < len ? (unsigned)d[i + 1] << 8 : 0) | (i + 2 < len ? d[i + 2] : 0);
    *o++ = tab[v >> 18 & 63];
    *o++ = tab[v >> 12 & 63];
    *o++ = i + 1 < len ? tab[v >> 6 & 63] : '=';
    *o++ = i + 2 < len ? tab[v & 63] : '=';
  }
  *o = '\0';
  return out;
}
