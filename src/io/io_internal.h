/* woven: helpers shared by the image and file I/O sources (not public API). */
#ifndef WOVEN_IO_INTERNAL_H
#define WOVEN_IO_INTERNAL_H

#include <stddef.h>
#include <stdio.h>
#include "woven/io.h"

/* Thread-safe strerror: formats errnum into buf and returns buf. */
const char *wv_io_strerror(int errnum, char *buf, size_t len);

/* The process's umask, read without changing it. */
#include <sys/types.h>
mode_t wv_io_umask(void);

/* Deletes a file or a directory tree (symbolic links are removed, never followed);
 * best effort. */
void wv_io_remove_tree(const char *path);

/* Rejects a decoded header whose size is invalid or over the read limits
 * (WV_IMAGE_READ_MAX_SIDE, WV_IMAGE_READ_MAX_PIXELS), before any pixel memory
 * is allocated. */
wv_status wv_io_check_size(const char *path, long long w, long long h, wv_error *err);

/* Rejects images a writer cannot store (NULL data, bad shape). */
wv_status wv_io_check_image(const char *path, const wv_image *img, wv_error *err);

/* Replaces a file atomically: data goes to a temporary file next to the target
 * ("<path>.tmp.XXXXXX", locked while open), which is renamed over the target on
 * commit and removed on abort, so readers never see a partial file. */
typedef struct {
  const char *path; /* final name (borrowed) */
  char *tmp;        /* temporary name (owned) */
  int fd;           /* open temporary file, -1 when closed */
} wv_io_atomic;

wv_status wv_io_atomic_open(wv_io_atomic *af, const char *path, wv_error *err);
/* Appends len bytes at the current position. */
wv_status wv_io_atomic_write(wv_io_atomic *af, const void *data, size_t len, wv_error *err);
/* Closes and renames into place; on failure the temporary file is removed. */
wv_status wv_io_atomic_commit(wv_io_atomic *af, wv_error *err);
/* Closes and removes the temporary file; safe to call after a failed commit. */
void wv_io_atomic_abort(wv_io_atomic *af);

/* Decoders. fp (or fd) is open at the start of the file and stays owned by the caller;
 * path is only used in messages. */
wv_status wv_io_read_png(const char *path, FILE *fp, wv_image *img, wv_image_info *info,
                         wv_error *err);
wv_status wv_io_read_jpeg(const char *path, FILE *fp, wv_image *img, wv_image_info *info,
                          wv_error *err);
wv_status wv_io_read_exr(const char *path, int fd, wv_image *img, wv_image_info *info,
                         wv_error *err);

/* Converts a value to an unsigned integer sample in [0, maxval]: clamped, rounded,
 * NaN mapped to 0. */
static inline unsigned wv_io_quantise(float v, unsigned maxval) {
  if (!(v > 0.0f)) return 0; /* also catches NaN */
  if (v >= 1.0f) return maxval;
  return (unsigned)(v * (float)maxval + 0.5f);
}

#endif
