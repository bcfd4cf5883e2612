/* woven: PNG read (8/16-bit, any colour type) and write (8/16-bit RGB) with libpng.
 * libpng reports errors by longjmp; all state that must survive the jump lives in a
 * struct owned by the caller of the function that calls setjmp, so no local of that
 * function is modified after setjmp (C11 7.13.2.1). */
#include <errno.h>
#include <png.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "io/io_internal.h"

typedef struct {
  const char *path;
  FILE *fp;          /* read source */
  wv_io_atomic *out; /* write target */
  png_structp png;
  png_infop info;
  unsigned char *buf; /* one row, or the whole image when interlaced */
  wv_image img;
  wv_image_info meta;
  wv_error *err;
  wv_status code; /* set before a longjmp; WV_OK means "not yet set" */
  char msg[1024]; /* full message, starting with the path */
} png_job;

/* Records the first problem; later messages are usually consequences of it. */
static void job_note(png_job *j, wv_status code, const char *fmt, ...) {
  if (j->code != WV_OK) return;
  j->code = code;
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(j->msg, sizeof j->msg, fmt, ap);
  va_end(ap);
}

/* Messages in png_job.msg always start with the path. */
static void on_png_read_error(png_structp png, png_const_charp msg) {
  png_job *j = png_get_error_ptr(png);
  job_note(j, WV_ERR_FORMAT, "%s: corrupt PNG data: %s", j->path, msg);
  png_longjmp(png, 1);
}

static void on_png_write_error(png_structp png, png_const_charp msg) {
  png_job *j = png_get_error_ptr(png);
  job_note(j, WV_ERR_INTERNAL, "%s: PNG encoding failed: %s", j->path, msg);
  png_longjmp(png, 1);
}

/* Warnings (bad ancillary chunks, ...) do not stop decoding; keep stderr quiet. */
static void on_png_warning(png_structp png, png_const_charp msg) {
  (void)png;
  (void)msg;
}

static void on_png_read(png_structp png, png_bytep data, size_t len) {
  png_job *j = png_get_io_ptr(png);
  if (fread(data, 1, len, j->fp) == len) return;
  char eb[128];
  if (ferror(j->fp))
    job_note(j, WV_ERR_IO, "%s: cannot read: %s", j->path, wv_io_strerror(errno, eb, sizeof eb));
  else
    job_note(j, WV_ERR_FORMAT, "%s: truncated PNG data", j->path);
  png_error(png, j->msg);
}

static void on_png_write(png_structp png, png_bytep data, size_t len) {
  png_job *j = png_get_io_ptr(png);
  wv_error e;
  if (wv_io_atomic_write(j->out, data, len, &e) == WV_OK) return;
  job_note(j, e.code, "%s", e.msg); /* already names the path */
  png_error(png, j->msg);
}

static void on_png_flush(png_structp png) { (void)png; }

/* ---- read ---- */

/* Converts decoded row bytes (n channels, 8 or 16 bits, big endian) to RGB floats. */
static void row_to_float(const unsigned char *src, float *dst, int w, int n, int depth) {
  if (depth == 16) {
    for (int x = 0; x < w; x++, src += 2 * n, dst += 3)
      for (int c = 0; c < 3; c++) dst[c] = (float)((src[2 * c] << 8) | src[2 * c + 1]) / 65535.0f;
  } else {
    for (int x = 0; x < w; x++, src += n, dst += 3)
      for (int c = 0; c < 3; c++) dst[c] = (float)src[c] / 255.0f;
  }
}

/* Asks libpng for 8/16-bit RGB output with alpha removed (should an alpha
 * channel survive, row_to_float skips it). Colour values are left untouched. */
static void setup_transforms(png_job *j, int color, int depth) {
  png_structp png = j->png;
  if (color == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
  if (color == PNG_COLOR_TYPE_GRAY && depth < 8) png_set_expand_gray_1_2_4_to_8(png);
  if (!(color & PNG_COLOR_MASK_COLOR)) png_set_gray_to_rgb(png);
  png_set_strip_alpha(png);
}

static wv_status png_decode(png_job *j) {
  png_structp png = j->png;
  png_infop info = j->info;
  png_read_info(png, info);
  png_uint_32 w = png_get_image_width(png, info), h = png_get_image_height(png, info);
  int color = png_get_color_type(png, info), depth = png_get_bit_depth(png, info);
  wv_status s = wv_io_check_size(j->path, w, h, j->err);
  if (s != WV_OK) return s;
  j->meta.bit_depth = depth == 16 ? 16 : 8;
  j->meta.is_float = 0;
  j->meta.channels_in_file = color == PNG_COLOR_TYPE_PALETTE
                                 ? (png_get_valid(png, info, PNG_INFO_tRNS) ? 4 : 3)
                                 : png_get_channels(png, info);
  setup_transforms(j, color, depth);
  int passes = png_set_interlace_handling(png);
  png_read_update_info(png, info);
  int n = png_get_channels(png, info), odepth = png_get_bit_depth(png, info);
  size_t rowbytes = png_get_rowbytes(png, info);
  if ((n != 3 && n != 4) || (odepth != 8 && odepth != 16) ||
      rowbytes != (size_t)w * n * (odepth / 8))
    return wv_fail(j->err, WV_ERR_INTERNAL, "%s: unexpected PNG layout after conversion", j->path);
  s = wv_image_alloc(&j->img, (int)w, (int)h, 3, j->err);
  if (s != WV_OK) {
    wv_error_prefix(j->err, "%s", j->path);
    return s;
  }
  /* Interlaced images are assembled over several passes, so need the whole image. */
  j->buf = malloc(rowbytes * (passes > 1 ? h : 1));
  if (!j->buf) return wv_fail(j->err, WV_ERR_NOMEM, "%s: out of memory for PNG rows", j->path);
  for (int p = 0; p < passes; p++)
    for (png_uint_32 y = 0; y < h; y++) {
      unsigned char *row = j->buf + (passes > 1 ? rowbytes * y : 0);
      png_read_row(png, row, NULL);
      if (passes == 1) row_to_float(row, wv_image_px(&j->img, 0, (int)y), (int)w, n, odepth);
    }
  if (passes > 1)
    for (png_uint_32 y = 0; y < h; y++)
      row_to_float(j->buf + rowbytes * y, wv_image_px(&j->img, 0, (int)y), (int)w, n, odepth);
  png_read_end(png, NULL); /* checks the rest of the file up to IEND */
  return WV_OK;
}

static wv_status png_decode_guarded(png_job *j) {
  if (setjmp(png_jmpbuf(j->png))) return j->code != WV_OK ? j->code : WV_ERR_FORMAT;
  return png_decode(j);
}

wv_status wv_io_read_png(const char *path, FILE *fp, wv_image *img, wv_image_info *info,
                         wv_error *err) {
  png_job j = {.path = path, .fp = fp, .err = err, .code = WV_OK};
  j.png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &j, on_png_read_error, on_png_warning);
  j.info = j.png ? png_create_info_struct(j.png) : NULL;
  wv_status s;
  if (!j.info) {
    s = wv_fail(err, WV_ERR_NOMEM, "%s: cannot initialise libpng", path);
  } else {
    png_set_read_fn(j.png, &j, on_png_read);
    s = png_decode_guarded(&j);
    if (s != WV_OK && j.code != WV_OK) wv_fail(err, j.code, "%s", j.msg);
  }
  png_destroy_read_struct(&j.png, &j.info, NULL);
  free(j.buf);
  if (s != WV_OK) {
    wv_image_free(&j.img);
    return s;
  }
  *img = j.img;
  if (info) *info = j.meta;
  return WV_OK;
}

/* ---- integrity check without decoding ---- */

static uint32_t be32(const unsigned char *b) {
  return (uint32_t)b[0] << 24 | (uint32_t)b[1] << 16 | (uint32_t)b[2] << 8 | (uint32_t)b[3];
}

wv_status wv_png_check(const char *path, wv_error *err) {
  static const unsigned char sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  FILE *f;
  wv_status os = wv_fopen_regular(path, &f, err);
  if (os != WV_OK) return os;
  unsigned char h[8], buf[1 << 14];
  wv_status st = WV_OK;
  int chunks = 0, idat = 0, end = 0;
  if (fread(h, 1, 8, f) != 8 || memcmp(h, sig, 8)) st = wv_fail(err, WV_ERR_FORMAT, "%s: not a PNG file", path);
  while (!st && !end) {
    if (fread(h, 1, 8, f) != 8) {
      st = wv_fail(err, WV_ERR_FORMAT, "%s: truncated PNG (no IEND chunk)", path);
      break;
    }
    uint32_t len = be32(h);
    if (len > 0x7fffffffu || (chunks == 0 && memcmp(h + 4, "IHDR", 4))) {
      st = wv_fail(err, WV_ERR_FORMAT, "%s: corrupt PNG chunk structure", path);
      break;
    }
    uLong crc = crc32(crc32(0L, Z_NULL, 0), h + 4, 4);
    for (uint32_t left = len; left > 0 && !st;) {
      size_t want = left < sizeof buf ? left : sizeof buf;
      if (fread(buf, 1, want, f) != want) st = wv_fail(err, WV_ERR_FORMAT, "%s: truncated PNG data", path);
      crc = crc32(crc, buf, (uInt)want);
      left -= (uint32_t)want;
    }
    if (!st && (fread(buf, 1, 4, f) != 4 || be32(buf) != (uint32_t)crc))
      st = wv_fail(err, WV_ERR_FORMAT, "%s: corrupt PNG data (chunk checksum mismatch)", path);
    idat |= !memcmp(h + 4, "IDAT", 4);
    end = !memcmp(h + 4, "IEND", 4);
    chunks++;
  }
  if (!st && !idat) st = wv_fail(err, WV_ERR_FORMAT, "%s: PNG without image data", path);
  fclose(f);
  return st;
}

/* ---- write ---- */

/* Fills one output row (RGB, 8 or 16 bits big endian) from image row y. */
static void float_to_row(const wv_image *src, int y, unsigned char *row, int depth) {
  const float *px = wv_image_px(src, 0, y);
  unsigned maxval = depth == 16 ? 65535u : 255u;
  for (int x = 0; x < src->w; x++, px += src->c)
    for (int c = 0; c < 3; c++) {
      unsigned v = wv_io_quantise(px[src->c == 1 ? 0 : c], maxval);
      if (depth == 16) {
        *row++ = (unsigned char)(v >> 8);
        *row++ = (unsigned char)(v & 0xff);
      } else {
        *row++ = (unsigned char)v;
      }
    }
}

static wv_status png_encode(png_job *j, const wv_image *src, int depth) {
  png_set_IHDR(j->png, j->info, (png_uint_32)src->w, (png_uint_32)src->h, depth, PNG_COLOR_TYPE_RGB,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  /* Renders are noisy at the pixel scale: deflate's match search finds little in
   * them, and run-length matches alone (what the filtered rows of flat regions
   * need) give files 0.1% larger in half the time (800 x 300 render: 21 ms, not 42). */
  png_set_compression_strategy(j->png, Z_RLE);
  png_write_info(j->png, j->info);
  for (int y = 0; y < src->h; y++) {
    float_to_row(src, y, j->buf, depth);
    png_write_row(j->png, j->buf);
  }
  png_write_end(j->png, NULL);
  return WV_OK;
}

static wv_status png_encode_guarded(png_job *j, const wv_image *src, int depth) {
  if (setjmp(png_jmpbuf(j->png))) return j->code != WV_OK ? j->code : WV_ERR_FORMAT;
  return png_encode(j, src, depth);
}

/* Encodes into an already opened temporary file. */
static wv_status png_write_to(const char *path, wv_io_atomic *out, const wv_image *src, int depth,
                              wv_error *err) {
  png_job j = {.path = path, .out = out, .err = err, .code = WV_OK};
  j.png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &j, on_png_write_error, on_png_warning);
  j.info = j.png ? png_create_info_struct(j.png) : NULL;
  j.buf = malloc((size_t)src->w * 3 * (depth / 8));
  wv_status s;
  if (!j.info || !j.buf) {
    s = wv_fail(err, WV_ERR_NOMEM, "%s: out of memory for PNG encoding", path);
  } else {
    png_set_write_fn(j.png, &j, on_png_write, on_png_flush);
    s = png_encode_guarded(&j, src, depth);
    if (s != WV_OK && j.code != WV_OK) wv_fail(err, j.code, "%s", j.msg);
  }
  png_destroy_write_struct(&j.png, &j.info);
  free(j.buf);
  return s;
}

wv_status wv_image_write_png(const char *path, const wv_image *img, int bit_depth, wv_error *err) {
  if (!path) return wv_fail(err, WV_ERR_INVALID, "missing output path");
  if (bit_depth != 8 && bit_depth != 16)
    return wv_fail(err, WV_ERR_INVALID, "%s: PNG bit depth must be 8 or 16, not %d", path,
                   bit_depth);
  wv_status s = wv_io_check_image(path, img, err);
  if (s != WV_OK) return s;
  wv_io_atomic out;
  s = wv_io_atomic_open(&out, path, err);
  if (s != WV_OK) return s;
  s = png_write_to(path, &out, img, bit_depth, err);
  if (s != WV_OK) {
    wv_io_atomic_abort(&out);
    return s;
  }
  return wv_io_atomic_commit(&out, err);
}
