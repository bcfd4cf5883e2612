/* woven: image format dispatch. Reading trusts the magic bytes, never the name;
 * writing picks the format from the extension. */
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include "io/io_internal.h"

typedef enum { FMT_UNKNOWN, FMT_PNG, FMT_JPEG, FMT_EXR } image_format;

static image_format detect(const unsigned char *m, size_t n) {
  static const unsigned char png[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  static const unsigned char jpeg[3] = {0xff, 0xd8, 0xff};
  static const unsigned char exr[4] = {0x76, 0x2f, 0x31, 0x01};
  if (n >= sizeof png && memcmp(m, png, sizeof png) == 0) return FMT_PNG;
  if (n >= sizeof jpeg && memcmp(m, jpeg, sizeof jpeg) == 0) return FMT_JPEG;
  if (n >= sizeof exr && memcmp(m, exr, sizeof exr) == 0) return FMT_EXR;
  return FMT_UNKNOWN;
}

/* Reads the first bytes and rewinds, so decoders see the whole file. */
static wv_status sniff(const char *path, FILE *fp, image_format *fmt, wv_error *err) {
  unsigned char magic[8];
  char eb[128];
  size_t n = fread(magic, 1, sizeof magic, fp);
  if (ferror(fp))
    return wv_fail(err, WV_ERR_IO, "%s: cannot read: %s", path,
                   wv_io_strerror(errno, eb, sizeof eb));
  if (n == 0) return wv_fail(err, WV_ERR_FORMAT, "%s: empty file", path);
  *fmt = detect(magic, n);
  if (*fmt == FMT_UNKNOWN)
    return wv_fail(err, WV_ERR_FORMAT, "%s: not a PNG, JPEG or EXR image", path);
  if (fseek(fp, 0, SEEK_SET) != 0)
    return wv_fail(err, WV_ERR_IO, "%s: cannot seek: %s", path,
                   wv_io_strerror(errno, eb, sizeof eb));
  return WV_OK;
}

wv_status wv_image_read(const char *path, wv_image *img, wv_image_info *info, wv_error *err) {
  if (!path || !img) return wv_fail(err, WV_ERR_INVALID, "wv_image_read: missing path or image");
  *img = (wv_image){0};
  FILE *fp = NULL;
  wv_status s = wv_fopen_regular(path, &fp, err);
  if (s != WV_OK) return s;
  image_format fmt = FMT_UNKNOWN;
  s = sniff(path, fp, &fmt, err);
  if (s == WV_OK) {
    switch (fmt) {
      case FMT_PNG: s = wv_io_read_png(path, fp, img, info, err); break;
      case FMT_JPEG: s = wv_io_read_jpeg(path, fp, img, info, err); break;
      case FMT_EXR: s = wv_io_read_exr(path, fileno(fp), img, info, err); break;
      default: s = wv_fail(err, WV_ERR_INTERNAL, "%s: unhandled format", path); break;
    }
  }
  fclose(fp); /* read-only: a close error cannot lose data */
  return s;
}

static int has_extension(const char *path, const char *ext) {
  size_t n = strlen(path), e = strlen(ext);
  return n > e && strcasecmp(path + n - e, ext) == 0;
}

wv_status wv_image_write(const char *path, const wv_image *img, wv_error *err) {
  if (!path) return wv_fail(err, WV_ERR_INVALID, "wv_image_write: missing path");
  if (has_extension(path, ".png")) return wv_image_write_png(path, img, 8, err);
  if (has_extension(path, ".exr")) return wv_image_write_exr(path, img, err);
  return wv_fail(err, WV_ERR_INVALID, "%s: unknown output format (use a .png or .exr name)", path);
}
