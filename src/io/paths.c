/* woven: path checks that keep outputs off inputs, and removal of the temporary
 * files and directories an interrupted run left behind. */
#define _GNU_SOURCE /* flock, nftw, fstatat */
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <ftw.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "io/io_internal.h"

int wv_same_file(const char *a, const char *b) {
  struct stat sa, sb;
  if (!a || !b || stat(a, &sa) != 0 || stat(b, &sb) != 0) return 0;
  return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}

int wv_path_within(const char *path, const char *dir) {
  struct stat sd, s;
  if (!path || !dir || stat(dir, &sd) != 0) return 0;
  /* A path that does not exist yet lies where its nearest existing ancestor does. */
  char *r = realpath(path, NULL), *cut = r ? NULL : strdup(path);
  while (!r && cut) {
    char *slash = strrchr(cut, '/');
    if (!slash) {
      r = realpath(".", NULL);
      break;
    }
    if (slash == cut) slash[1] = '\0';
    else *slash = '\0';
    r = realpath(cut, NULL);
    if (!r && !strcmp(cut, "/")) break;
  }
  free(cut);
  if (!r) return 0;
  int in = 0;
  /* The path and each of its ancestors, compared by identity rather than by name
   * (bind mounts and links give one directory several names). */
  for (;;) {
    if (stat(r, &s) == 0 && s.st_dev == sd.st_dev && s.st_ino == sd.st_ino) {
      in = 1;
      break;
    }
    char *slash = strrchr(r, '/');
    if (!slash || !strcmp(r, "/")) break;
    if (slash == r)
      r[1] = '\0';
    else
      *slash = '\0';
  }
  free(r);
  return in;
}

wv_status wv_check_not_input(const char *output, int output_is_dir, const char *const *inputs, int n_inputs,
                             wv_error *err) {
  for (int i = 0; i < n_inputs; i++) {
    const char *in = inputs[i];
    if (!in) continue;
    if (wv_same_file(output, in))
      return wv_fail(err, WV_ERR_INVALID, "%s: the output is the input %s; refusing to write over an input", output,
                     in);
    if (output_is_dir && wv_path_within(in, output))
      return wv_fail(err, WV_ERR_INVALID,
                     "%s: the input %s lies inside this output directory, which is replaced as a whole; "
                     "write the output to another directory",
                     output, in);
  }
  return WV_OK;
}

int wv_is_temp_name(const char *name) {
  size_t n = strlen(name);
  if (n < 12 || memcmp(name + n - 11, ".tmp.", 5) != 0) return 0;
  for (size_t i = n - 6; i < n; i++) {
    char c = name[i];
    if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9'))) return 0;
  }
  return 1;
}

static int remove_entry(const char *path, const struct stat *st, int flag, struct FTW *ftw) {
  (void)st, (void)flag, (void)ftw;
  (void)remove(path); /* best effort: what cannot be removed stays for the next run */
  return 0;
}

void wv_io_remove_tree(const char *path) {
  (void)nftw(path, remove_entry, 16, FTW_DEPTH | FTW_PHYS);
}

int wv_remove_stale_temps(const char *dir, const char *prefix) {
  DIR *d = opendir(dir);
  if (!d) return 0;
  int dfd = dirfd(d), removed = 0;
  size_t plen = prefix ? strlen(prefix) : 0;
  time_t now = time(NULL);
  for (struct dirent *e; (e = readdir(d));) {
    const char *name = e->d_name;
    if (!wv_is_temp_name(name)) continue;
    if (prefix && (strlen(name) != plen + 11 || strncmp(name, prefix, plen) != 0)) continue;
    struct stat st, st2;
    if (fstatat(dfd, name, &st, AT_SYMLINK_NOFOLLOW) != 0) continue;
    if (st.st_uid != geteuid() || !(S_ISREG(st.st_mode) || S_ISDIR(st.st_mode))) continue;
    if (now - st.st_mtime < WV_TMP_STALE_SECONDS) continue; /* may be a writer between create and lock */
    int fd = openat(dfd, name, O_RDONLY | O_NOFOLLOW | O_CLOEXEC | O_NONBLOCK | (S_ISDIR(st.st_mode) ? O_DIRECTORY : 0));
    if (fd < 0) continue;
    /* A live writer holds the lock; a killed one released it. */
    if (flock(fd, LOCK_EX | LOCK_NB) == 0 && fstat(fd, &st2) == 0 && st2.st_ino == st.st_ino &&
        st2.st_dev == st.st_dev) {
      char path[4096];
      if (snprintf(path, sizeof path, "%s/%s", dir, name) < (int)sizeof path) {
        if (S_ISDIR(st.st_mode))
          wv_io_remove_tree(path);
        else
          (void)unlinkat(dfd, name, 0);
        removed++;
      }
    }
    close(fd);
  }
  closedir(d);
  return removed;
}

int wv_remove_stale_temps_beside(const char *path) {
  const char *slash = strrchr(path, '/');
  char dir[4096];
  if (!slash)
    snprintf(dir, sizeof dir, ".");
  else
    snprintf(dir, sizeof dir, "%.*s", slash == path ? 1 : (int)(slash - path), path);
  return wv_remove_stale_temps(dir, slash ? slash + 1 : path);
}
