/* woven: directories of outputs written whole (wv_outdir): everything goes into a
 * temporary directory beside the target, which then takes the target's place. */
#define _GNU_SOURCE /* renameat2, RENAME_EXCHANGE, flock */
#include <errno.h>
#include <fcntl.h>
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include "io/io_internal.h"

/* path without trailing slashes (owned), or NULL when out of memory. */
static char *trimmed(const char *path) {
  char *p = strdup(path);
  if (!p) return NULL;
  size_t n = strlen(p);
  while (n > 1 && p[n - 1] == '/') p[--n] = '\0';
  return p;
}

/* Splits a trimmed path into its directory (owned) and last component (inside path). */
static char *parent_of(const char *path, const char **base) {
  const char *slash = strrchr(path, '/');
  *base = slash ? slash + 1 : path;
  if (!slash) return strdup(".");
  if (slash == path) return strdup("/");
  return strndup(path, (size_t)(slash - path));
}

static int listed(const char *name, const char *const *own) {
  for (int i = 0; own[i]; i++)
    if (!strcmp(name, own[i])) return 1;
  return 0;
}

wv_status wv_outdir_check(const char *path, const char *const *own, wv_error *err) {
  char eb[128];
  char *p = trimmed(path);
  if (!p) return wv_fail(err, WV_ERR_NOMEM, "%s: out of memory", path);
  const char *base;
  char *parent = parent_of(p, &base);
  wv_status st = WV_OK;
  struct stat sb;
  if (!parent) {
    st = wv_fail(err, WV_ERR_NOMEM, "%s: out of memory", path);
  } else if (!*base || !strcmp(base, ".") || !strcmp(base, "..") || !strcmp(p, "/")) {
    st = wv_fail(err, WV_ERR_INVALID, "%s: an output directory is replaced as a whole; name a directory of its own",
                 path);
  } else if (stat(p, &sb) != 0) {
    struct stat pb;
    if (errno != ENOENT)
      st = wv_fail(err, WV_ERR_IO, "%s: %s", path, wv_io_strerror(errno, eb, sizeof eb));
    else if (stat(parent, &pb) != 0 || !S_ISDIR(pb.st_mode) || access(parent, W_OK | X_OK) != 0)
      st = wv_fail(err, WV_ERR_IO, "%s: cannot create the directory: '%s' does not exist or is not writable", path,
                   parent);
  } else if (!S_ISDIR(sb.st_mode)) {
    st = wv_fail(err, WV_ERR_IO, "%s exists and is not a directory", path);
  } else if (own) {
    DIR *d = opendir(p);
    if (!d) {
      st = wv_fail(err, WV_ERR_IO, "%s: cannot read the directory: %s", path, wv_io_strerror(errno, eb, sizeof eb));
    } else {
      for (struct dirent *e; (e = readdir(d));) {
        const char *n = e->d_name;
        if (!strcmp(n, ".") || !strcmp(n, "..") || wv_is_temp_name(n) || listed(n, own)) continue;
        st = wv_fail(err, WV_ERR_IO,
                     "%s holds '%s', which is not part of this output; the directory is replaced as a whole, so "
                     "refusing (move that file away or choose another output directory)",
                     path, n);
        break;
      }
      closedir(d);
    }
  }
  free(parent);
  free(p);
  return st;
}

wv_status wv_outdir_begin(wv_outdir *od, const char *path, const char *const *own, wv_error *err) {
  char eb[128];
  od->path = od->tmp = NULL;
  od->fd = -1;
  wv_status st = wv_outdir_check(path, own, err);
  if (st) return st;
  struct stat sb, lb;
  int exists = stat(path, &sb) == 0;
  /* A link to a directory: replace the directory it names, not the link. */
  od->path = exists && lstat(path, &lb) == 0 && S_ISLNK(lb.st_mode) ? realpath(path, NULL) : trimmed(path);
  const char *base;
  char *parent = od->path ? parent_of(od->path, &base) : NULL;
  size_t n = od->path ? strlen(od->path) : 0;
  od->tmp = od->path ? malloc(n + 12) : NULL;
  if (!parent || !od->tmp) {
    free(parent);
    wv_outdir_abort(od, NULL);
    return wv_fail(err, WV_ERR_NOMEM, "%s: out of memory", path);
  }
  wv_remove_stale_temps(parent, base);
  free(parent);
  memcpy(od->tmp, od->path, n);
  memcpy(od->tmp + n, ".tmp.XXXXXX", 12);
  if (!mkdtemp(od->tmp)) {
    int e = errno;
    free(od->tmp);
    od->tmp = NULL;
    wv_outdir_abort(od, NULL);
    return wv_fail(err, WV_ERR_IO, "%s: cannot create a temporary directory beside it: %s", path,
                   wv_io_strerror(e, eb, sizeof eb));
  }
  /* mkdtemp makes 0700: give what mkdir would, or keep the replaced directory's mode. */
  (void)chmod(od->tmp, exists ? (sb.st_mode & 07777) : (0777 & ~wv_io_umask()));
  od->fd = open(od->tmp, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (od->fd < 0 || flock(od->fd, LOCK_EX | LOCK_NB) != 0) {
    int e = errno;
    wv_outdir_abort(od, NULL);
    return wv_fail(err, WV_ERR_IO, "%s: cannot lock the temporary directory: %s", path,
                   wv_io_strerror(e, eb, sizeof eb));
  }
  return WV_OK;
}

static void release(wv_outdir *od) {
  if (od->fd >= 0) close(od->fd);
  od->fd = -1;
  free(od->path);
  free(od->tmp);
  od->path = od->tmp = NULL;
}

/* Every occurrence of from in msg becomes to (truncated to the message's size). */
static void replace_in(char *msg, size_t cap, const char *from, const char *to) {
  char out[sizeof ((wv_error *)0)->msg];
  size_t n = 0, fl = strlen(from), tl = strlen(to);
  for (const char *p = msg; *p && n + 1 < sizeof out && n + 1 < cap;) {
    if (fl && !strncmp(p, from, fl)) {
      for (size_t i = 0; i < tl && n + 1 < sizeof out; i++) out[n++] = to[i];
      p += fl;
    } else {
      out[n++] = *p++;
    }
  }
  out[n] = '\0';
  memcpy(msg, out, n + 1);
}

void wv_outdir_abort(wv_outdir *od, wv_error *err) {
  if (!od) return;
  if (err && od->tmp && od->path) replace_in(err->msg, sizeof err->msg, od->tmp, od->path);
  if (od->tmp) wv_io_remove_tree(od->tmp);
  release(od);
}

/* Without RENAME_EXCHANGE: the old directory goes aside under a name the stale-file
 * cleaner leaves alone (it may be the only copy if the process dies between the two
 * renames), the new one takes its place, and the old one is deleted. */
static int replace_by_two_renames(wv_outdir *od) {
  size_t n = strlen(od->path);
  char *old = malloc(n + 12);
  if (!old) return ENOMEM;
  memcpy(old, od->path, n);
  memcpy(old + n, ".old.XXXXXX", 12);
  int e = 0;
  if (!mkdtemp(old)) {
    e = errno;
  } else if (rename(od->path, old) != 0) { /* replaces the empty placeholder */
    e = errno;
    rmdir(old);
  } else if (rename(od->tmp, od->path) != 0) {
    e = errno;
    (void)rename(old, od->path); /* put the old one back */
  } else {
    wv_io_remove_tree(old);
  }
  free(old);
  return e;
}

wv_status wv_outdir_commit(wv_outdir *od, wv_error *err) {
  char eb[128];
  if (!od || !od->tmp) return wv_fail(err, WV_ERR_INTERNAL, "wv_outdir_commit: nothing to commit");
  struct stat sb;
  int e = 0;
  if (lstat(od->path, &sb) != 0) {
    if (rename(od->tmp, od->path) != 0) e = errno;
  } else if (!S_ISDIR(sb.st_mode)) {
    e = ENOTDIR;
  } else if (renameat2(AT_FDCWD, od->tmp, AT_FDCWD, od->path, RENAME_EXCHANGE) == 0) {
    wv_io_remove_tree(od->tmp); /* the old directory now has the temporary name */
  } else if (errno == EINVAL || errno == ENOSYS || errno == ENOTSUP) {
    e = replace_by_two_renames(od);
  } else {
    e = errno;
  }
  if (e) {
    wv_status st = wv_fail(err, WV_ERR_IO, "%s: cannot put the new directory in place: %s", od->path,
                           wv_io_strerror(e, eb, sizeof eb));
    wv_outdir_abort(od, NULL);
    return st;
  }
  release(od);
  return WV_OK;
}
