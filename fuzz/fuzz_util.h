/* woven fuzz: helpers shared by the libFuzzer harnesses in fuzz/: the input as a
 * NUL-terminated string or as a file for the entry points that take a path, and the
 * checks every harness makes on a refusal (a status, a message naming the input). */
#ifndef WOVEN_FUZZ_UTIL_H
#define WOVEN_FUZZ_UTIL_H

#include <stddef.h>
#include <stdint.h>

#include "woven/error.h"

/* The input as a malloc'ed NUL-terminated string (an embedded NUL ends it early). */
char *fuzz_cstr(const uint8_t *data, size_t size);

/* The input as an anonymous in-memory file, readable by path ("/proc/self/fd/N");
 * nothing touches the disk. */
typedef struct {
  int fd;
  char path[64];
} fuzz_file;
void fuzz_file_open(fuzz_file *f, const uint8_t *data, size_t size);
void fuzz_file_close(fuzz_file *f);

/* A fresh directory (under TMPDIR or /tmp) holding one file `name` with the input,
 * for readers that take a directory; fuzz_dir_remove deletes both. */
typedef struct {
  char dir[256], file[512];
} fuzz_dir;
void fuzz_dir_open(fuzz_dir *d, const char *name, const uint8_t *data, size_t size);
void fuzz_dir_remove(fuzz_dir *d);

/* Aborts (a finding) with a message on stderr. */
void fuzz_fail(const char *fmt, ...) __attribute__((format(printf, 1, 2), noreturn));

/* A refusal must carry its status in err and a message that names `source`. */
void fuzz_check_refusal(wv_status st, const wv_error *err, const char *source);

#endif
