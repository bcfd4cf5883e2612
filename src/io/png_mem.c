/* woven: PNG encoding into memory (libpng's simplified API), for files that
 * carry images inside them: the glTF binary's textures, the viewer's photo. */
#include <png.h>
#include <stdlib.h>
#include <string.h>

#include "io/io_internal.h"

wv_status wv_image_encode_png(const wv_image *img, unsigned char **out, size_t *len, wv_error *err) {
  *out = NULL, *len = 0;
  wv_status s = wv_io_check_image("PNG in memory", img, err);
  if (s != WV_OK) return s;
  int ch = img->c == 4 ? 4 : 3; /* grey is replicated, as the file writers do */
  size_t n = (size_t)img->w * img->h;
  unsigned char *px = malloc(n * (size_t)ch);
  if (!px) return wv_fail(err, WV_ERR_NOMEM, "out of memory for a %d x %d PNG", img->w, img->h);
  for (size_t i = 0; i < n; i++)
    for (int c = 0; c < ch; c++)
      px[i * ch + c] = (unsigned char)wv_io_quantise(img->data[i * img->c + (img->c == 1 ? 0 : c)], 255u);
  png_image pi;
  memset(&pi, 0, sizeof pi);
  pi.version = PNG_IMAGE_VERSION;
  pi.width = (png_uint_32)img->w, pi.height = (png_uint_32)img->h;
  pi.format = ch == 4 ? PNG_FORMAT_RGBA : PNG_FORMAT_RGB;
  png_alloc_size_t size = 0;
  /* First call sizes the output, the second fills it. */
  int ok = png_image_write_get_memory_size(pi, size, 0, px, 0, NULL);
  unsigned char *buf = ok ? malloc(size) : NULL;
  if (buf) ok = png_image_write_to_memory(&pi, buf, &size, 0, px, 0, NULL);
  free(px);
  if (!ok || !buf) {
    free(buf);
    png_image_free(&pi);
    if (ok) return wv_fail(err, WV_ERR_NOMEM, "out of memory for a %d x %d PNG", img->w, img->h);
    return wv_fail(err, WV_ERR_INTERNAL, "PNG encoding of a %d x %d image failed: %s", img->w, img->h, pi.message);
  }
  *out = buf, *len = size;
  return WV_OK;
}
