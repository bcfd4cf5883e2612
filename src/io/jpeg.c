/* woven: JPEG read with libjpeg(-turbo), 8-bit grey or colour, and an in-memory
 * compress/decompress round trip (what a camera's JPEG does to an image).
 * libjpeg's default error handler exits the process; ours longjmps back instead.
 * As with PNG, state that must survive the jump lives in a caller-owned struct. */
#include <setjmp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jpeglib.h>
#include <jerror.h>

#include "io/io_internal.h"

typedef struct {
  struct jpeg_error_mgr pub; /* first, so libjpeg's err pointer converts back */
  jmp_buf jump;
  const char *path;
  wv_status code;
  char msg[1024]; /* full message, starting with the path */
} jpeg_errors;

typedef struct {
  const char *path;
  FILE *fp;
  const unsigned char *mem; /* the data to decode when fp is NULL */
  unsigned long mem_len;
  struct jpeg_decompress_struct cinfo;
  jpeg_errors jerr;
  unsigned char *row;
  wv_image img;
  wv_image_info meta;
  wv_error *err;
} jpeg_job;

static void on_jpeg_error(j_common_ptr cinfo) {
  jpeg_errors *e = (jpeg_errors *)cinfo->err;
  char text[JMSG_LENGTH_MAX];
  e->pub.format_message(cinfo, text);
  e->code = e->pub.msg_code == JERR_OUT_OF_MEMORY ? WV_ERR_NOMEM : WV_ERR_FORMAT;
  snprintf(e->msg, sizeof e->msg, "%s: %s: %s", e->path,
           e->code == WV_ERR_NOMEM ? "out of memory decoding JPEG" : "corrupt JPEG data", text);
  longjmp(e->jump, 1);
}

/* libjpeg only warns when pixel data is missing or damaged (it pads with grey and
 * carries on); for us such a photo is an error. Harmless warnings (extraneous
 * bytes, unknown JFIF revision, ...) are common in camera files and are ignored,
 * and none of them reach stderr. */
static int loses_pixels(int code) {
  return code == JWRN_HIT_MARKER || code == JWRN_HUFF_BAD_CODE || code == JWRN_ARITH_BAD_CODE ||
         code == JWRN_MUST_RESYNC;
}

static void on_jpeg_message(j_common_ptr cinfo, int level) {
  jpeg_errors *e = (jpeg_errors *)cinfo->err;
  if (level >= 0) return; /* trace messages */
  static const char prefix[] = "Corrupt JPEG data: ";
  int code = e->pub.msg_code;
  if (code == JWRN_JPEG_EOF || loses_pixels(code)) {
    char text[JMSG_LENGTH_MAX] = "";
    if (code != JWRN_JPEG_EOF) e->pub.format_message(cinfo, text);
    e->code = WV_ERR_FORMAT;
    if (code == JWRN_JPEG_EOF)
      snprintf(e->msg, sizeof e->msg, "%s: truncated JPEG data", e->path);
    else /* drop libjpeg's own "Corrupt JPEG data: " so messages read alike */
      snprintf(e->msg, sizeof e->msg, "%s: corrupt JPEG data: %s", e->path,
               strncmp(text, prefix, sizeof prefix - 1) == 0 ? text + sizeof prefix - 1 : text);
    longjmp(e->jump, 1);
  }
  e->pub.num_warnings++;
}

/* Chooses the output colour space; CMYK and exotic spaces are refused. */
static wv_status choose_colour(jpeg_job *j) {
  switch (j->cinfo.jpeg_color_space) {
    case JCS_GRAYSCALE: j->cinfo.out_color_space = JCS_GRAYSCALE; return WV_OK;
    case JCS_RGB:
    case JCS_YCbCr: j->cinfo.out_color_space = JCS_RGB; return WV_OK;
    case JCS_CMYK:
    case JCS_YCCK:
      return wv_fail(j->err, WV_ERR_FORMAT, "%s: CMYK JPEG files are not supported", j->path);
    default:
      return wv_fail(j->err, WV_ERR_FORMAT, "%s: unsupported JPEG colour space %d", j->path,
                     (int)j->cinfo.jpeg_color_space);
  }
}

static void row_to_float(const unsigned char *src, float *dst, int w, int n) {
  for (int x = 0; x < w; x++, src += n, dst += 3)
    for (int c = 0; c < 3; c++) dst[c] = (float)src[n == 1 ? 0 : c] / 255.0f;
}

static wv_status jpeg_decode(jpeg_job *j) {
  struct jpeg_decompress_struct *ci = &j->cinfo;
  jpeg_create_decompress(ci);
  if (j->fp)
    jpeg_stdio_src(ci, j->fp);
  else
    jpeg_mem_src(ci, j->mem, j->mem_len);
  jpeg_read_header(ci, TRUE);
  wv_status s = wv_io_check_size(j->path, ci->image_width, ci->image_height, j->err);
  if (s == WV_OK) s = choose_colour(j);
  if (s != WV_OK) return s;
  j->meta = (wv_image_info){.bit_depth = 8, .is_float = 0, .channels_in_file = ci->num_components};
  jpeg_start_decompress(ci);
  int w = (int)ci->output_width, n = ci->output_components;
  s = wv_image_alloc(&j->img, w, (int)ci->output_height, 3, j->err);
  if (s != WV_OK) {
    wv_error_prefix(j->err, "%s", j->path);
    return s;
  }
  j->row = malloc((size_t)w * n);
  if (!j->row) return wv_fail(j->err, WV_ERR_NOMEM, "%s: out of memory for JPEG rows", j->path);
  while (ci->output_scanline < ci->output_height) {
    int y = (int)ci->output_scanline;
    JSAMPROW rows[1] = {j->row};
    if (jpeg_read_scanlines(ci, rows, 1) != 1)
      return wv_fail(j->err, WV_ERR_FORMAT, "%s: truncated JPEG data", j->path);
    row_to_float(j->row, wv_image_px(&j->img, 0, y), w, n);
  }
  jpeg_finish_decompress(ci);
  return WV_OK;
}

static wv_status jpeg_decode_guarded(jpeg_job *j) {
  if (setjmp(j->jerr.jump)) return j->jerr.code;
  return jpeg_decode(j);
}

static wv_status read_jpeg(const char *path, FILE *fp, const unsigned char *mem, unsigned long mem_len,
                           wv_image *img, wv_image_info *info, wv_error *err) {
  jpeg_job *j = calloc(1, sizeof *j); /* large (jmp_buf, libjpeg state): keep it off the stack */
  if (!j) return wv_fail(err, WV_ERR_NOMEM, "%s: out of memory", path);
  j->path = path;
  j->fp = fp;
  j->mem = mem, j->mem_len = mem_len;
  j->err = err;
  j->cinfo.err = jpeg_std_error(&j->jerr.pub);
  j->jerr.pub.error_exit = on_jpeg_error;
  j->jerr.pub.emit_message = on_jpeg_message;
  j->jerr.path = path;
  wv_status s = jpeg_decode_guarded(j);
  if (s != WV_OK && j->jerr.code != WV_OK) wv_fail(err, j->jerr.code, "%s", j->jerr.msg);
  jpeg_destroy_decompress(&j->cinfo); /* safe on a partly created or failed decoder */
  free(j->row);
  if (s == WV_OK) {
    *img = j->img;
    if (info) *info = j->meta;
  } else {
    wv_image_free(&j->img);
  }
  free(j);
  return s;
}

wv_status wv_io_read_jpeg(const char *path, FILE *fp, wv_image *img, wv_image_info *info,
                          wv_error *err) {
  return read_jpeg(path, fp, NULL, 0, img, info, err);
}

/* ---- in-memory round trip ---- */

typedef struct {
  struct jpeg_compress_struct cinfo;
  jpeg_errors jerr;
  unsigned char *buf; /* libjpeg's output buffer (malloc'ed by jpeg_mem_dest) */
  unsigned long len;
  unsigned char *row;
} jpeg_enc;

static wv_status jpeg_encode_guarded(jpeg_enc *e, const wv_image *in, int quality) {
  if (setjmp(e->jerr.jump)) return e->jerr.code;
  struct jpeg_compress_struct *ci = &e->cinfo;
  jpeg_create_compress(ci);
  jpeg_mem_dest(ci, &e->buf, &e->len);
  ci->image_width = (JDIMENSION)in->w, ci->image_height = (JDIMENSION)in->h;
  ci->input_components = 3, ci->in_color_space = JCS_RGB;
  jpeg_set_defaults(ci);
  jpeg_set_quality(ci, quality, TRUE);
  jpeg_start_compress(ci, TRUE);
  while (ci->next_scanline < ci->image_height) {
    const float *src = wv_image_px(in, 0, (int)ci->next_scanline);
    for (int x = 0; x < in->w; x++)
      for (int c = 0; c < 3; c++) {
        float v = src[(size_t)x * in->c + (in->c >= 3 ? c : 0)];
        v = v < 0 ? 0 : v > 1 ? 1 : v;
        e->row[3 * x + c] = (unsigned char)(v * 255.0f + 0.5f);
      }
    JSAMPROW rows[1] = {e->row};
    jpeg_write_scanlines(ci, rows, 1);
  }
  jpeg_finish_compress(ci);
  return WV_OK;
}

wv_status wv_image_jpeg_roundtrip(const wv_image *in, int quality, wv_image *out, wv_error *err) {
  if (quality < 1 || quality > 100) return wv_fail(err, WV_ERR_INVALID, "JPEG quality %d is outside 1..100", quality);
  if (!in->data || in->w < 1 || in->h < 1 || (in->c != 1 && in->c < 3))
    return wv_fail(err, WV_ERR_INVALID, "JPEG round trip: not an image");
  jpeg_enc *e = calloc(1, sizeof *e);
  if (!e) return wv_fail(err, WV_ERR_NOMEM, "out of memory for JPEG compression");
  e->row = malloc(3 * (size_t)in->w);
  e->cinfo.err = jpeg_std_error(&e->jerr.pub);
  e->jerr.pub.error_exit = on_jpeg_error;
  e->jerr.pub.emit_message = on_jpeg_message;
  e->jerr.path = "in-memory JPEG";
  wv_status s = e->row ? jpeg_encode_guarded(e, in, quality) : (e->jerr.code = WV_ERR_NOMEM);
  if (s != WV_OK) wv_fail(err, s, "%s", e->row ? e->jerr.msg : "out of memory for JPEG compression");
  jpeg_destroy_compress(&e->cinfo);
  if (s == WV_OK) s = read_jpeg("in-memory JPEG", NULL, e->buf, e->len, out, NULL, err);
  free(e->buf); /* jpeg_mem_dest's buffer is the caller's to free */
  free(e->row);
  free(e);
  return s;
}
