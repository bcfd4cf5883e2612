/* woven fuzz: the helpers of fuzz_util.h. Setup failures (no memfd, no temporary
 * directory) abort: they are the machine's problem, and a harness that silently
 * skipped its work would report coverage it never had. */
#define _GNU_SOURCE
#include "fuzz_util.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

void fuzz_fail(const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  fputs("fuzz: ", stderr);
  vfprintf(stderr, fmt, ap);
  fputc('\n', stderr);
  va_end(ap);
  abort();
}

char *fuzz_cstr(const uint8_t *data, size_t size) {
  char *s = malloc(size + 1);
  if (!s) fuzz_fail("out of memory");
  if (size) memcpy(s, data, size);
  s[size] = '\0';
  return s;
}

static void write_all(int fd, const uint8_t *data, size_t size) {
  while (size > 0) {
    ssize_t n = write(fd, data, size);
    if (n <= 0) fuzz_fail("cannot write the input file");
    data += n;
    size -= (size_t)n;
  }
}

void fuzz_file_open(fuzz_file *f, const uint8_t *data, size_t size) {
  f->fd = memfd_create("fuzz-input", MFD_CLOEXEC);
  if (f->fd < 0) fuzz_fail("memfd_create failed");
  write_all(f->fd, data, size);
  snprintf(f->path, sizeof f->path, "/proc/self/fd/%d", f->fd);
}

void fuzz_file_close(fuzz_file *f) {
  if (f->fd >= 0) close(f->fd);
  f->fd = -1;
}

void fuzz_dir_open(fuzz_dir *d, const char *name, const uint8_t *data, size_t size) {
  const char *tmp = getenv("TMPDIR");
  snprintf(d->dir, sizeof d->dir, "%s/woven-fuzz.XXXXXX", tmp && *tmp ? tmp : "/tmp");
  if (!mkdtemp(d->dir)) fuzz_fail("cannot create a temporary directory in %s", d->dir);
  snprintf(d->file, sizeof d->file, "%s/%s", d->dir, name);
  FILE *fp = fopen(d->file, "wb");
  if (!fp || (size && fwrite(data, 1, size, fp) != size) || fclose(fp) != 0)
    fuzz_fail("cannot write %s", d->file);
}

void fuzz_dir_remove(fuzz_dir *d) {
  unlink(d->file);
  rmdir(d->dir);
}

void fuzz_check_refusal(wv_status st, const wv_error *err, const char *source) {
  if (st == WV_OK) return;
  if (err->code != st) fuzz_fail("status %d but the error records %d (%s)", (int)st, (int)err->code, err->msg);
  if (!err->msg[0]) fuzz_fail("status %d with an empty message", (int)st);
  if (source && !strstr(err->msg, source)) fuzz_fail("message does not name %s: %s", source, err->msg);
}
