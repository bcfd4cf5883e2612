/* woven: OpenEXR read (scanline, half or float, R/G/B or Y) and write (float RGB,
 * ZIP) with the OpenEXR core C API. The file is accessed through our own
 * read/write callbacks so that writes go to the atomic temporary file. */
#include <errno.h>
#include <limits.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <openexr.h>

#include "io/io_internal.h"

/* Largest single pread/pwrite request (keeps counts well inside ssize_t). */
#define EXR_IO_STEP ((uint64_t)1 << 30)

typedef struct {
  int fd;
  int last_errno; /* errno of a failed system call, 0 if none */
  char msg[512];  /* first message from the library (read contexts only) */
} exr_stream;

static int64_t on_exr_read(exr_const_context_t ctx, void *user, void *buf, uint64_t sz,
                           uint64_t off, exr_stream_error_func_ptr_t error_cb) {
  (void)ctx;
  (void)error_cb;
  exr_stream *st = user;
  uint64_t done = 0;
  while (done < sz) {
    uint64_t want = sz - done < EXR_IO_STEP ? sz - done : EXR_IO_STEP;
    ssize_t n = pread(st->fd, (char *)buf + done, (size_t)want, (off_t)(off + done));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      st->last_errno = errno;
      return -1;
    }
    if (n == 0) break; /* end of file: the library reports the short read */
    done += (uint64_t)n;
  }
  return (int64_t)done;
}

static int64_t on_exr_size(exr_const_context_t ctx, void *user) {
  (void)ctx;
  struct stat st;
  if (fstat(((exr_stream *)user)->fd, &st) != 0 || !S_ISREG(st.st_mode)) return -1; /* unknown */
  return (int64_t)st.st_size;
}

/* Keeps the library's first message for our own report instead of stderr.
 * Only used for read contexts, which the library does not lock when we ask
 * for the user data. */
static void on_exr_read_error(exr_const_context_t ctx, exr_result_t code, const char *msg) {
  (void)code;
  void *user = NULL;
  if (!ctx || exr_get_user_data(ctx, &user) != EXR_ERR_SUCCESS || !user) return;
  exr_stream *st = user;
  if (!st->msg[0]) snprintf(st->msg, sizeof st->msg, "%s", msg ? msg : "unknown error");
}

/* Write contexts may report errors with their lock held: stay silent there and
 * build messages from the result codes. */
static void on_exr_quiet(exr_const_context_t ctx, exr_result_t code, const char *msg) {
  (void)ctx;
  (void)code;
  (void)msg;
}

/* ---- read ---- */

typedef struct {
  const char *path;
  exr_stream io;
  exr_context_t ctx;
  exr_attr_box2i_t dw;  /* data window */
  const char *names[3]; /* channel feeding output channel k; "Y" for grey files */
  int grey;
  wv_image img;
  wv_image_info meta;
  wv_error *err;
} exr_reader;

/* A short read is a truncated file (format); only a failed system call is I/O. */
static wv_status read_fail(exr_reader *r, exr_result_t rv, const char *what) {
  char eb[128];
  if (r->io.last_errno)
    return wv_fail(r->err, WV_ERR_IO, "%s: cannot read: %s", r->path,
                   wv_io_strerror(r->io.last_errno, eb, sizeof eb));
  return wv_fail(r->err, rv == EXR_ERR_OUT_OF_MEMORY ? WV_ERR_NOMEM : WV_ERR_FORMAT, "%s: %s: %s",
                 r->path, what, r->io.msg[0] ? r->io.msg : exr_get_default_error_message(rv));
}

static const exr_attr_chlist_entry_t *find_channel(const exr_attr_chlist_t *cl, const char *name) {
  for (int i = 0; i < cl->num_channels; i++)
    if (cl->entries[i].name.str && strcmp(cl->entries[i].name.str, name) == 0)
      return &cl->entries[i];
  return NULL;
}

/* Picks R,G,B (or Y) and checks they can be decoded to full-resolution floats. */
static wv_status pick_channels(exr_reader *r) {
  const exr_attr_chlist_t *cl = NULL;
  exr_result_t rv = exr_get_channels(r->ctx, 0, &cl);
  if (rv != EXR_ERR_SUCCESS || !cl) return read_fail(r, rv, "cannot read channel list");
  const exr_attr_chlist_entry_t *ch[3] = {find_channel(cl, "R"), find_channel(cl, "G"),
                                          find_channel(cl, "B")};
  r->grey = !(ch[0] && ch[1] && ch[2]);
  if (r->grey) ch[0] = ch[1] = ch[2] = find_channel(cl, "Y");
  if (!ch[0])
    return wv_fail(r->err, WV_ERR_FORMAT, "%s: EXR file has neither R, G, B nor Y channels",
                   r->path);
  int all_half = 1;
  for (int k = 0; k < 3; k++) {
    if (ch[k]->x_sampling != 1 || ch[k]->y_sampling != 1)
      return wv_fail(r->err, WV_ERR_FORMAT, "%s: subsampled EXR channels are not supported",
                     r->path);
    if (ch[k]->pixel_type != EXR_PIXEL_HALF && ch[k]->pixel_type != EXR_PIXEL_FLOAT)
      return wv_fail(r->err, WV_ERR_FORMAT, "%s: EXR channel %s is not half or float", r->path,
                     ch[k]->name.str);
    all_half &= ch[k]->pixel_type == EXR_PIXEL_HALF;
    r->names[k] = ch[k]->name.str;
  }
  r->meta =
      (wv_image_info){.bit_depth = all_half ? 16 : 32,
                      .is_float = 1,
                      .channels_in_file = (r->grey ? 1 : 3) + (find_channel(cl, "A") != NULL)};
  return WV_OK;
}

/* Reads the header facts we depend on: storage, size, channels. */
static wv_status read_layout(exr_reader *r) {
  exr_storage_t storage;
  exr_result_t rv = exr_get_storage(r->ctx, 0, &storage);
  if (rv != EXR_ERR_SUCCESS) return read_fail(r, rv, "cannot read EXR header");
  if (storage == EXR_STORAGE_TILED)
    return wv_fail(r->err, WV_ERR_FORMAT, "%s: tiled EXR files are not supported (use scanline)",
                   r->path);
  if (storage != EXR_STORAGE_SCANLINE)
    return wv_fail(r->err, WV_ERR_FORMAT, "%s: deep EXR files are not supported", r->path);
  rv = exr_get_data_window(r->ctx, 0, &r->dw);
  if (rv != EXR_ERR_SUCCESS) return read_fail(r, rv, "cannot read EXR data window");
  long long w = (long long)r->dw.max.x - r->dw.min.x + 1,
            h = (long long)r->dw.max.y - r->dw.min.y + 1;
  wv_status s = wv_io_check_size(r->path, w, h, r->err);
  if (s == WV_OK && w * 3 * (long long)sizeof(float) > INT32_MAX)
    s = wv_fail(r->err, WV_ERR_NOMEM, "%s: EXR image is too wide (%lld pixels)", r->path, w);
  return s == WV_OK ? pick_channels(r) : s;
}

/* Points the decoder's wanted channels at rows of the interleaved output. */
static void set_outputs(exr_reader *r, exr_decode_pipeline_t *dec, int row0) {
  float *base = wv_image_px(&r->img, 0, row0);
  for (int c = 0; c < dec->channel_count; c++) {
    exr_coding_channel_info_t *ch = &dec->channels[c];
    ch->decode_to_ptr = NULL; /* skipped unless wanted */
    for (int k = 0; k < (r->grey ? 1 : 3); k++)
      if (strcmp(ch->channel_name, r->names[k]) == 0) ch->decode_to_ptr = (uint8_t *)(base + k);
    ch->user_pixel_stride = 3 * (int32_t)sizeof(float);
    ch->user_line_stride = r->img.w * 3 * (int32_t)sizeof(float);
    ch->user_bytes_per_element = sizeof(float);
    ch->user_data_type = EXR_PIXEL_FLOAT;
  }
}

static wv_status decode_chunks(exr_reader *r, exr_decode_pipeline_t *dec) {
  int32_t lines = 0;
  exr_result_t rv = exr_get_scanlines_per_chunk(r->ctx, 0, &lines);
  if (rv != EXR_ERR_SUCCESS || lines <= 0) return read_fail(r, rv, "cannot read EXR chunk layout");
  int first = 1;
  for (int64_t y = r->dw.min.y; y <= r->dw.max.y; y += lines) {
    exr_chunk_info_t ci;
    r->io.msg[0] = '\0'; /* report this chunk's problem, not an earlier warning */
    rv = exr_read_scanline_chunk_info(r->ctx, 0, (int)y, &ci);
    if (rv != EXR_ERR_SUCCESS) return read_fail(r, rv, "corrupt or truncated EXR data");
    rv = first ? exr_decoding_initialize(r->ctx, 0, &ci, dec)
               : exr_decoding_update(r->ctx, 0, &ci, dec);
    if (rv != EXR_ERR_SUCCESS) return read_fail(r, rv, "cannot decode EXR data");
    if (ci.start_y < r->dw.min.y || (int64_t)ci.start_y + ci.height - 1 > r->dw.max.y)
      return wv_fail(r->err, WV_ERR_FORMAT, "%s: EXR chunk outside the data window", r->path);
    set_outputs(r, dec, ci.start_y - r->dw.min.y);
    if (first) rv = exr_decoding_choose_default_routines(r->ctx, 0, dec);
    if (rv == EXR_ERR_SUCCESS) rv = exr_decoding_run(r->ctx, 0, dec);
    if (rv != EXR_ERR_SUCCESS) return read_fail(r, rv, "corrupt or truncated EXR data");
    first = 0;
  }
  return WV_OK;
}

static void replicate_grey(wv_image *img) {
  size_t n = (size_t)img->w * img->h;
  for (size_t i = 0; i < n; i++) img->data[3 * i + 1] = img->data[3 * i + 2] = img->data[3 * i];
}

wv_status wv_io_read_exr(const char *path, int fd, wv_image *img, wv_image_info *info,
                         wv_error *err) {
  exr_reader r = {.path = path, .io = {.fd = fd}, .err = err};
  exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
  init.error_handler_fn = on_exr_read_error;
  init.user_data = &r.io;
  init.read_fn = on_exr_read;
  init.size_fn = on_exr_size;
  exr_result_t rv = exr_start_read(&r.ctx, path, &init);
  if (rv != EXR_ERR_SUCCESS) return read_fail(&r, rv, "invalid EXR header");
  r.io.msg[0] = '\0';
  wv_status s = read_layout(&r);
  if (s == WV_OK) {
    s = wv_image_alloc(&r.img, r.dw.max.x - r.dw.min.x + 1, r.dw.max.y - r.dw.min.y + 1, 3, err);
    if (s != WV_OK) wv_error_prefix(err, "%s", path);
  }
  if (s == WV_OK) {
    exr_decode_pipeline_t dec = EXR_DECODE_PIPELINE_INITIALIZER;
    s = decode_chunks(&r, &dec);
    exr_decoding_destroy(r.ctx, &dec);
  }
  exr_finish(&r.ctx);
  if (s != WV_OK) {
    wv_image_free(&r.img);
    return s;
  }
  if (r.grey) replicate_grey(&r.img);
  *img = r.img;
  if (info) *info = r.meta;
  return WV_OK;
}

/* ---- write ---- */

static int64_t on_exr_write(exr_const_context_t ctx, void *user, const void *buf, uint64_t sz,
                            uint64_t off, exr_stream_error_func_ptr_t error_cb) {
  (void)ctx;
  (void)error_cb;
  exr_stream *st = user;
  uint64_t done = 0;
  while (done < sz) {
    uint64_t want = sz - done < EXR_IO_STEP ? sz - done : EXR_IO_STEP;
    ssize_t n = pwrite(st->fd, (const char *)buf + done, (size_t)want, (off_t)(off + done));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      st->last_errno = n < 0 ? errno : EIO;
      return -1;
    }
    done += (uint64_t)n;
  }
  return (int64_t)done;
}

typedef struct {
  const char *path;
  const wv_image *src;
  exr_stream io;
  exr_context_t ctx;
  int part;
  wv_error *err;
} exr_writer;

static wv_status write_fail(exr_writer *w, exr_result_t rv, const char *what) {
  char eb[128];
  if (w->io.last_errno)
    return wv_fail(w->err, WV_ERR_IO, "%s: cannot write: %s", w->path,
                   wv_io_strerror(w->io.last_errno, eb, sizeof eb));
  wv_status code = rv == EXR_ERR_OUT_OF_MEMORY ? WV_ERR_NOMEM
                   : rv == EXR_ERR_WRITE_IO    ? WV_ERR_IO
                                               : WV_ERR_INTERNAL;
  return wv_fail(w->err, code, "%s: %s: %s", w->path, what, exr_get_default_error_message(rv));
}

/* Declares a single scanline part: float R, G, B, ZIP (lossless, 16-line chunks). */
static wv_status define_header(exr_writer *w) {
  exr_result_t rv = exr_add_part(w->ctx, NULL, EXR_STORAGE_SCANLINE, &w->part);
  if (rv == EXR_ERR_SUCCESS)
    rv = exr_initialize_required_attr_simple(w->ctx, w->part, w->src->w, w->src->h,
                                             EXR_COMPRESSION_ZIP);
  static const char *const names[3] = {"R", "G", "B"};
  for (int k = 0; k < 3 && rv == EXR_ERR_SUCCESS; k++)
    rv = exr_add_channel(w->ctx, w->part, names[k], EXR_PIXEL_FLOAT, EXR_PERCEPTUALLY_LOGARITHMIC,
                         1, 1);
  if (rv == EXR_ERR_SUCCESS) rv = exr_write_header(w->ctx);
  return rv == EXR_ERR_SUCCESS ? WV_OK : write_fail(w, rv, "cannot write EXR header");
}

/* Points each file channel at the matching samples of rows starting at row0
 * (a grey image feeds all three). */
static void set_inputs(exr_writer *w, exr_encode_pipeline_t *enc, int row0) {
  const wv_image *src = w->src;
  const float *base = wv_image_px(src, 0, row0);
  for (int c = 0; c < enc->channel_count; c++) {
    exr_coding_channel_info_t *ch = &enc->channels[c];
    int k = ch->channel_name[0] == 'R' ? 0 : ch->channel_name[0] == 'G' ? 1 : 2;
    ch->encode_from_ptr = (const uint8_t *)(base + (src->c == 1 ? 0 : k));
    ch->user_pixel_stride = src->c * (int32_t)sizeof(float);
    ch->user_line_stride = src->w * src->c * (int32_t)sizeof(float);
    ch->user_bytes_per_element = sizeof(float);
    ch->user_data_type = EXR_PIXEL_FLOAT;
  }
}

static wv_status encode_chunks(exr_writer *w, exr_encode_pipeline_t *enc) {
  int32_t lines = 0;
  exr_result_t rv = exr_get_scanlines_per_chunk(w->ctx, w->part, &lines);
  if (rv != EXR_ERR_SUCCESS || lines <= 0) return write_fail(w, rv, "cannot set up EXR chunks");
  for (int y = 0; y < w->src->h; y += lines) {
    exr_chunk_info_t ci;
    rv = exr_write_scanline_chunk_info(w->ctx, w->part, y, &ci);
    if (rv == EXR_ERR_SUCCESS)
      rv = y == 0 ? exr_encoding_initialize(w->ctx, w->part, &ci, enc)
                  : exr_encoding_update(w->ctx, w->part, &ci, enc);
    if (rv != EXR_ERR_SUCCESS) return write_fail(w, rv, "cannot encode EXR data");
    set_inputs(w, enc, ci.start_y);
    if (y == 0) rv = exr_encoding_choose_default_routines(w->ctx, w->part, enc);
    if (rv == EXR_ERR_SUCCESS) rv = exr_encoding_run(w->ctx, w->part, enc);
    if (rv != EXR_ERR_SUCCESS) return write_fail(w, rv, "cannot encode EXR data");
  }
  return WV_OK;
}

/* Encodes into an already opened temporary file descriptor. */
static wv_status exr_write_to(const char *path, int fd, const wv_image *src, wv_error *err) {
  exr_writer w = {.path = path, .src = src, .io = {.fd = fd}, .err = err};
  exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
  init.error_handler_fn = on_exr_quiet;
  init.user_data = &w.io;
  init.write_fn = on_exr_write;
  exr_result_t rv = exr_start_write(&w.ctx, path, EXR_WRITE_FILE_DIRECTLY, &init);
  if (rv != EXR_ERR_SUCCESS) return write_fail(&w, rv, "cannot start EXR output");
  wv_status s = define_header(&w);
  if (s == WV_OK) {
    exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
    s = encode_chunks(&w, &enc);
    exr_encoding_destroy(w.ctx, &enc);
  }
  rv = exr_finish(&w.ctx); /* writes the chunk offset table */
  if (s == WV_OK && rv != EXR_ERR_SUCCESS) s = write_fail(&w, rv, "cannot finish EXR output");
  return s;
}

wv_status wv_image_write_exr(const char *path, const wv_image *img, wv_error *err) {
  if (!path) return wv_fail(err, WV_ERR_INVALID, "missing output path");
  wv_status s = wv_io_check_image(path, img, err);
  if (s == WV_OK && (long long)img->w * img->c * (long long)sizeof(float) > INT32_MAX)
    s = wv_fail(err, WV_ERR_INVALID, "%s: image is too wide for EXR output", path);
  if (s != WV_OK) return s;
  wv_io_atomic out;
  s = wv_io_atomic_open(&out, path, err);
  if (s != WV_OK) return s;
  s = exr_write_to(path, out.fd, img, err);
  if (s != WV_OK) {
    wv_io_atomic_abort(&out);
    return s;
  }
  return wv_io_atomic_commit(&out, err);
}
