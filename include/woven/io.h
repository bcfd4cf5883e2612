/* woven: image and file I/O. PNG (8/16-bit, libpng), JPEG (libjpeg-turbo), EXR (OpenEXR C API).
 * Readers return the file's values as floats without colour decoding: 8/16-bit
 * integers map to [0,1], EXR keeps its float values. Colour encoding is the caller's
 * business (the scene says whether a photo is sRGB, gamma or linear).
 * Writers never leave a partial file: they write to a temporary file next to the
 * target and rename it into place, so an earlier result survives any failure. */
#ifndef WOVEN_IO_H
#define WOVEN_IO_H

#include <stddef.h>
#include "woven/error.h"
#include "woven/image.h"

typedef struct {
  int bit_depth;        /* 8 or 16 for PNG/JPEG, 16 (half) or 32 for EXR */
  int is_float;         /* 1 for EXR */
  int channels_in_file; /* 1 (grey), 2 (grey+alpha), 3 or 4 */
} wv_image_info;

/* Reads any supported image (detected from its magic bytes, not its name) and
 * returns it with 3 channels (grey is replicated, alpha dropped). info may be NULL.
 * Images over WV_IMAGE_MAX_PIXELS are rejected before decoding.
 * Limits: CMYK JPEGs are refused; for EXR the first part is read, it must be a
 * scanline part (tiled and deep are refused) with half or float R,G,B or Y channels,
 * and its data window becomes the image. On failure *img is left empty. */
wv_status wv_image_read(const char *path, wv_image *img, wv_image_info *info, wv_error *err);

/* Writes by extension: .png (8-bit, values clamped to [0,1], no colour encoding
 * applied: pass already-encoded values), .exr (32-bit float, linear).
 * Files are always RGB: a 1-channel image is replicated, a 4th channel is not stored.
 * wv_image_write_png takes bit_depth 8 or 16; EXR output is ZIP-compressed scanlines. */
wv_status wv_image_write(const char *path, const wv_image *img, wv_error *err);
wv_status wv_image_write_png(const char *path, const wv_image *img, int bit_depth, wv_error *err);
wv_status wv_image_write_exr(const char *path, const wv_image *img, wv_error *err);

/* Compresses an image (values in [0,1], 1 or 3+ channels) to JPEG at quality 1..100 in
 * memory and decodes it again into out (3 channels, allocated here). */
wv_status wv_image_jpeg_roundtrip(const wv_image *in, int quality, wv_image *out, wv_error *err);

/* Atomically replaces path with len bytes of data. */
wv_status wv_write_file_atomic(const char *path, const void *data, size_t len, wv_error *err);
/* Reads a whole file (NUL-terminated for convenience); caller frees *data.
 * len may be NULL. */
wv_status wv_read_file(const char *path, char **data, size_t *len, wv_error *err);

#endif
