/* woven: whole-file reads and atomic file replacement. */
#define _DEFAULT_SOURCE /* flock */
#include <errno.h>
#include <fcntl.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include "io/io_internal.h"

const char *wv_io_strerror(int errnum, char *buf, size_t len) {
  /* XSI strerror_r (we build with _POSIX_C_SOURCE): returns 0 on success. */
  if (strerror_r(errnum, buf, len) != 0) snprintf(buf, len, "error %d", errnum);
  return buf;
}

wv_status wv_io_check_size(const char *path, long long w, long long h, wv_error *err) {
  if (w <= 0 || h <= 0)
    return wv_fail(err, WV_ERR_FORMAT, "%s: invalid image size %lld x %lld", path, w, h);
  if (w > WV_IMAGE_READ_MAX_SIDE || h > WV_IMAGE_READ_MAX_SIDE || w * h > WV_IMAGE_READ_MAX_PIXELS)
    return wv_fail(err, WV_ERR_NOMEM,
                   "%s: image of %lld x %lld pixels is too large (limit %d pixels per side and %ld "
                   "pixels in all)",
                   path, w, h, WV_IMAGE_READ_MAX_SIDE, (long)WV_IMAGE_READ_MAX_PIXELS);
  return WV_OK;
}

wv_status wv_io_check_image(const char *path, const wv_image *img, wv_error *err) {
  if (!img || !img->data || img->w <= 0 || img->h <= 0 ||
      (img->c != 1 && img->c != 3 && img->c != 4) ||
      (long long)img->w * img->h > WV_IMAGE_MAX_PIXELS)
    return wv_fail(err, WV_ERR_INVALID, "%s: cannot write an invalid image (%d x %d x %d)", path,
                   img ? img->w : 0, img ? img->h : 0, img ? img->c : 0);
  return WV_OK;
}

/* ---- excerpts of files in messages ---- */

void wv_printable_excerpt(const char *s, char *out, size_t len) {
  if (!len) return;
  size_t n = 0, i = 0;
  for (; s && s[i] && n + 1 < len; i++) {
    unsigned char c = (unsigned char)s[i];
    out[n++] = c >= 0x20 && c < 0x7f ? (char)c : '?';
  }
  out[n] = 0;
  if (s && s[i] && len > 4) memcpy(out + len - 4, "...", 4);
}

void wv_error_excerpt(wv_error *err, size_t keep) {
  if (!err) return;
  char *near = strstr(err->msg, " near '");
  if (!near) return;
  char *text = near + 7, *end = strrchr(text, '\'');
  if (!end) return;
  *end = 0;
  char ex[WV_EXCERPT_CHARS + 4], tail[sizeof err->msg];
  snprintf(tail, sizeof tail, "%s", end + 1);
  if (keep > WV_EXCERPT_CHARS) keep = WV_EXCERPT_CHARS;
  wv_printable_excerpt(text, ex, keep + 1 < sizeof ex ? keep + 1 : sizeof ex);
  if (keep) snprintf(near, sizeof err->msg - (size_t)(near - err->msg), " near '%s'%s", ex, tail);
  else snprintf(near, sizeof err->msg - (size_t)(near - err->msg), "%s", tail);
}

/* ---- opening a file to read ---- */

wv_status wv_open_regular(const char *path, int *fd, struct stat *st, wv_error *err) {
  char eb[128];
  struct stat sb;
  *fd = -1;
  if (!path) return wv_fail(err, WV_ERR_INVALID, "missing path");
  int f = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
  if (f < 0) return wv_fail(err, WV_ERR_IO, "%s: cannot open: %s", path, wv_io_strerror(errno, eb, sizeof eb));
  if (fstat(f, &sb) != 0) {
    int e = errno;
    close(f);
    return wv_fail(err, WV_ERR_IO, "%s: cannot open: %s", path, wv_io_strerror(e, eb, sizeof eb));
  }
  if (!S_ISREG(sb.st_mode)) {
    close(f);
    if (S_ISDIR(sb.st_mode)) return wv_fail(err, WV_ERR_IO, "%s: is a directory", path);
    return wv_fail(err, WV_ERR_IO, "%s: not a regular file", path);
  }
  int fl = fcntl(f, F_GETFL);
  if (fl < 0 || fcntl(f, F_SETFL, fl & ~O_NONBLOCK) != 0) {
    int e = errno;
    close(f);
    return wv_fail(err, WV_ERR_IO, "%s: cannot open: %s", path, wv_io_strerror(e, eb, sizeof eb));
  }
  if (st) *st = sb;
  *fd = f;
  return WV_OK;
}

wv_status wv_fopen_regular(const char *path, FILE **fp, wv_error *err) {
  char eb[128];
  int fd;
  *fp = NULL;
  wv_status s = wv_open_regular(path, &fd, NULL, err);
  if (s != WV_OK) return s;
  if (!(*fp = fdopen(fd, "rb"))) {
    int e = errno;
    close(fd);
    return wv_fail(err, WV_ERR_IO, "%s: cannot open: %s", path, wv_io_strerror(e, eb, sizeof eb));
  }
  return WV_OK;
}

/* ---- whole-file read ---- */

wv_status wv_read_file(const char *path, char **data, size_t *len, wv_error *err) {
  return wv_read_file_max(path, WV_READ_MAX_BYTES, data, len, err);
}

wv_status wv_read_file_max(const char *path, size_t max, char **data, size_t *len, wv_error *err) {
  char eb[128];
  if (!path || !data) return wv_fail(err, WV_ERR_INVALID, "wv_read_file: missing path or output");
  *data = NULL;
  if (len) *len = 0;
  int fd;
  struct stat st;
  wv_status os = wv_open_regular(path, &fd, &st, err);
  if (os != WV_OK) return os;
  int have_st = 1;
  if (have_st && S_ISREG(st.st_mode) && (unsigned long long)st.st_size > max) {
    close(fd);
    return wv_fail(err, WV_ERR_NOMEM, "%s: file of %lld bytes is over the limit of %zu bytes for this kind of file",
                   path, (long long)st.st_size, max);
  }
  /* The size is only a hint: pipes and devices report 0 and files may grow while
   * read, so the limit is enforced on what is read. Room for one byte more than
   * expected lets the final read see end of file without growing. */
  size_t cap = (have_st && S_ISREG(st.st_mode) && st.st_size > 0) ? (size_t)st.st_size + 2 : 4096;
  size_t n = 0;
  char *buf = malloc(cap);
  wv_status s = buf ? WV_OK : wv_fail(err, WV_ERR_NOMEM, "%s: out of memory", path);
  while (s == WV_OK) {
    if (n > max) {
      s = wv_fail(err, WV_ERR_NOMEM, "%s: more than %zu bytes, the limit for this kind of file", path, max);
      break;
    }
    if (n + 1 >= cap) {
      size_t ncap = cap < max / 2 + 2 ? cap * 2 : max + 2; /* never more than max + 2 bytes */
      char *nb = ncap > cap ? realloc(buf, ncap) : NULL;
      if (!nb) {
        s = wv_fail(err, WV_ERR_NOMEM, "%s: file too large to read into memory", path);
        break;
      }
      buf = nb;
      cap = ncap;
    }
    ssize_t r = read(fd, buf + n, cap - 1 - n);
    if (r < 0 && errno == EINTR) continue;
    if (r < 0)
      s = wv_fail(err, WV_ERR_IO, "%s: cannot read: %s", path,
                  wv_io_strerror(errno, eb, sizeof eb));
    if (r <= 0) break;
    n += (size_t)r;
  }
  close(fd);
  if (s != WV_OK) {
    free(buf);
    return s;
  }
  buf[n] = '\0';
  *data = buf;
  if (len) *len = n;
  return WV_OK;
}

/* ---- atomic replacement ---- */

/* The umask cannot be read without setting it (racy in threads), so ask the kernel. */
mode_t wv_io_umask(void) {
  mode_t mask = 022;
  int fd = open("/proc/self/status", O_RDONLY | O_CLOEXEC);
  FILE *f = fd >= 0 ? fdopen(fd, "r") : NULL;
  if (!f) {
    if (fd >= 0) close(fd);
    return mask;
  }
  char line[128];
  unsigned m;
  while (fgets(line, sizeof line, f))
    if (sscanf(line, "Umask: %o", &m) == 1) {
      mask = (mode_t)m;
      break;
    }
  fclose(f);
  return mask;
}

/* mkstemp creates 0600 files; give the result the mode a plain fopen would, or keep
 * the mode of the file being replaced. */
static void set_final_mode(int fd, const char *path) {
  struct stat st;
  mode_t mode = (stat(path, &st) == 0 && S_ISREG(st.st_mode)) ? (st.st_mode & 07777)
                                                              : (0666 & ~wv_io_umask());
  (void)fchmod(fd, mode); /* best effort: the data matters more than the mode */
}

/* Directory part of path for messages ("." when there is none). */
static void dir_of(const char *path, char *out, size_t len) {
  const char *slash = strrchr(path, '/');
  if (!slash) {
    snprintf(out, len, ".");
  } else if (slash == path) {
    snprintf(out, len, "/");
  } else {
    snprintf(out, len, "%.*s", (int)(slash - path), path);
  }
}

wv_status wv_io_atomic_open(wv_io_atomic *af, const char *path, wv_error *err) {
  static const char suffix[] = ".tmp.XXXXXX";
  char eb[128], dir[512];
  af->path = path;
  af->fd = -1;
  size_t n = strlen(path);
  af->tmp = malloc(n + sizeof suffix);
  if (!af->tmp) return wv_fail(err, WV_ERR_NOMEM, "%s: out of memory", path);
  memcpy(af->tmp, path, n);
  memcpy(af->tmp + n, suffix, sizeof suffix);
  af->fd = mkstemp(af->tmp);
  if (af->fd < 0) {
    int e = errno;
    free(af->tmp);
    af->tmp = NULL;
    dir_of(path, dir, sizeof dir);
    return wv_fail(err, WV_ERR_IO, "%s: cannot create temporary file in '%s': %s", path, dir,
                   wv_io_strerror(e, eb, sizeof eb));
  }
  set_final_mode(af->fd, path);
  /* Marks the file as in use: wv_remove_stale_temps leaves locked files alone. */
  (void)flock(af->fd, LOCK_EX | LOCK_NB);
  return WV_OK;
}

wv_status wv_io_atomic_write(wv_io_atomic *af, const void *data, size_t len, wv_error *err) {
  const char *p = data;
  char eb[128];
  while (len > 0) {
    ssize_t w = write(af->fd, p, len);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0)
      return wv_fail(err, WV_ERR_IO, "%s: cannot write: %s", af->path,
                     wv_io_strerror(w < 0 ? errno : EIO, eb, sizeof eb));
    p += w;
    len -= (size_t)w;
  }
  return WV_OK;
}

wv_status wv_io_atomic_commit(wv_io_atomic *af, wv_error *err) {
  char eb[128];
  int fd = af->fd;
  af->fd = -1;
  /* close() can report delayed write errors (e.g. NFS, quota). */
  if (close(fd) != 0) {
    int e = errno;
    wv_io_atomic_abort(af);
    return wv_fail(err, WV_ERR_IO, "%s: cannot write: %s", af->path,
                   wv_io_strerror(e, eb, sizeof eb));
  }
  if (rename(af->tmp, af->path) != 0) {
    int e = errno;
    wv_io_atomic_abort(af);
    return wv_fail(err, WV_ERR_IO, "%s: cannot replace file: %s", af->path,
                   wv_io_strerror(e, eb, sizeof eb));
  }
  free(af->tmp);
  af->tmp = NULL;
  return WV_OK;
}

void wv_io_atomic_abort(wv_io_atomic *af) {
  if (af->fd >= 0) close(af->fd);
  af->fd = -1;
  if (af->tmp) unlink(af->tmp);
  free(af->tmp);
  af->tmp = NULL;
}

wv_status wv_write_file_atomic(const char *path, const void *data, size_t len, wv_error *err) {
  if (!path || (!data && len > 0))
    return wv_fail(err, WV_ERR_INVALID, "%s: invalid arguments to write", path ? path : "(null)");
  wv_io_atomic af;
  wv_status s = wv_io_atomic_open(&af, path, err);
  if (s != WV_OK) return s;
  s = wv_io_atomic_write(&af, data, len, err);
  if (s != WV_OK) {
    wv_io_atomic_abort(&af);
    return s;
  }
  return wv_io_atomic_commit(&af, err);
}
