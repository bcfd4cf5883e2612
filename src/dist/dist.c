/* woven: the MPI layer (which items each rank takes, collectives on a few numbers)
 * and the output directory lock. Everything MPI is behind WOVEN_HAVE_MPI; without it
 * the calls act for a single process. */
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "woven/dist.h"
#include "woven/io.h"

#ifdef WOVEN_HAVE_MPI
#include <mpi.h>
#endif

int wv_dist_built_with_mpi(void) {
#ifdef WOVEN_HAVE_MPI
  return 1;
#else
  return 0;
#endif
}

/* Launchers announce themselves in the environment: OpenMPI's mpirun, PMIx (srun
 * --mpi=pmix, OpenMPI 4 and later), PMI-1/2 (srun, MPICH). A plain process skips
 * MPI_Init, so the command starts as fast as before and needs no MPI runtime. */
static int launched_by_mpi(void) {
  static const char *const VARS[] = {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE"};
  for (size_t i = 0; i < sizeof VARS / sizeof VARS[0]; i++) {
    const char *v = getenv(VARS[i]);
    if (v && *v) return 1;
  }
  return 0;
}

wv_status wv_dist_begin(wv_dist *d, wv_error *err) {
  d->rank = 0, d->size = 1, d->mpi = 0;
#ifdef WOVEN_HAVE_MPI
  if (!launched_by_mpi()) return WV_OK;
  int provided = 0;
  /* Only the main thread calls MPI; OpenMP threads render in between. */
  if (MPI_Init_thread(NULL, NULL, MPI_THREAD_FUNNELED, &provided) != MPI_SUCCESS)
    return wv_fail(err, WV_ERR_INTERNAL, "MPI_Init failed");
  d->mpi = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &d->rank);
  MPI_Comm_size(MPI_COMM_WORLD, &d->size);
#else
  (void)err;
  (void)launched_by_mpi;
#endif
  return WV_OK;
}

void wv_dist_end(wv_dist *d) {
#ifdef WOVEN_HAVE_MPI
  if (d->mpi) MPI_Finalize();
#endif
  d->mpi = 0;
}

void wv_dist_barrier(const wv_dist *d) {
#ifdef WOVEN_HAVE_MPI
  if (d->mpi) MPI_Barrier(MPI_COMM_WORLD);
#else
  (void)d;
#endif
}

void wv_dist_bcast_ints(const wv_dist *d, int *v, int n) {
#ifdef WOVEN_HAVE_MPI
  if (d->mpi) MPI_Bcast(v, n, MPI_INT, 0, MPI_COMM_WORLD);
#else
  (void)d, (void)v, (void)n;
#endif
}

int wv_dist_max_int(const wv_dist *d, int v) {
#ifdef WOVEN_HAVE_MPI
  if (d->mpi) MPI_Allreduce(MPI_IN_PLACE, &v, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
#else
  (void)d;
#endif
  return v;
}

int wv_dist_sum_int(const wv_dist *d, int v) {
#ifdef WOVEN_HAVE_MPI
  if (d->mpi) MPI_Allreduce(MPI_IN_PLACE, &v, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
#else
  (void)d;
#endif
  return v;
}

double wv_dist_max_double(const wv_dist *d, double v) {
#ifdef WOVEN_HAVE_MPI
  if (d->mpi) MPI_Allreduce(MPI_IN_PLACE, &v, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
#else
  (void)d;
#endif
  return v;
}

wv_status wv_dist_share(const wv_dist *d, int n, int (*done)(void *user, int k), void *user, int **mine, int *nmine,
                        int *ntodo, wv_error *err) {
  *mine = NULL, *nmine = 0, *ntodo = 0;
  if (n < 0) return wv_fail(err, WV_ERR_INVALID, "negative item count");
  unsigned char *todo = calloc((size_t)n + 1, 1);
  int *out = malloc(sizeof(int) * ((size_t)n / (size_t)d->size + 1));
  int failed = !todo || !out;
  for (int k = d->rank; k < n && !failed; k += d->size) todo[k] = !done(user, k);
#ifdef WOVEN_HAVE_MPI
  /* a failed allocation on any rank stops all of them before the exchange */
  failed = wv_dist_max_int(d, failed);
  if (!failed && d->mpi && n > 0) MPI_Allreduce(MPI_IN_PLACE, todo, n, MPI_UNSIGNED_CHAR, MPI_MAX, MPI_COMM_WORLD);
#endif
  if (failed) {
    free(todo), free(out);
    return wv_fail(err, WV_ERR_NOMEM, "out of memory for the list of %d items", n);
  }
  int t = 0;
  for (int k = 0; k < n; k++)
    if (todo[k]) {
      if (t % d->size == d->rank) out[(*nmine)++] = k;
      t++;
    }
  free(todo);
  *ntodo = t, *mine = out;
  return WV_OK;
}

/* ---- directory lock ---- */

/* "host pid" from a lock file; 0 when it cannot be read or parsed. */
static int read_lock(const char *path, char *text, size_t cap, char *host, size_t hcap, long *pid) {
  FILE *f;
  wv_error e;
  if (wv_fopen_regular(path, &f, &e)) return 0; /* a FIFO or device is no lock of ours */
  size_t len = fread(text, 1, cap - 1, f);
  fclose(f);
  text[len] = 0;
  char h[256];
  if (sscanf(text, "%255s %ld", h, pid) != 2 || *pid <= 0) return 0;
  snprintf(host, hcap, "%s", h);
  return 1;
}

/* Is process pid running on this host? A zombie (exited, not yet reaped: its parent
 * may be gone and init may not reap) counts as gone. */
static int process_alive(long pid) {
  if (kill((pid_t)pid, 0) != 0 && errno == ESRCH) return 0;
  char path[64], buf[512];
  snprintf(path, sizeof path, "/proc/%ld/stat", pid);
  FILE *f = fopen(path, "r");
  if (!f) return 1; /* no /proc: trust kill */
  size_t n = fread(buf, 1, sizeof buf - 1, f);
  fclose(f);
  buf[n] = 0;
  const char *close = strrchr(buf, ')'); /* the state follows the command name */
  return !(close && close[1] == ' ' && (close[2] == 'Z' || close[2] == 'X'));
}

wv_status wv_dir_lock_acquire(const char *dir, wv_dir_lock *lk, char *note, size_t note_cap, wv_error *err) {
  lk->held = 0;
  if (note_cap) note[0] = 0;
  if ((size_t)snprintf(lk->path, sizeof lk->path, "%s/woven.lock", dir) >= sizeof lk->path)
    return wv_fail(err, WV_ERR_INVALID, "%s: path too long", dir);
  char host[256] = "localhost", mine[320], tmp[4160];
  if (gethostname(host, sizeof host) != 0) snprintf(host, sizeof host, "localhost");
  host[sizeof host - 1] = 0;
  snprintf(mine, sizeof mine, "%s %ld\n", host, (long)getpid());
  /* The lock appears whole: written beside it, then hard-linked into place (link
   * fails when the lock exists, atomically, also on NFS). */
  snprintf(tmp, sizeof tmp, "%s.%ld.tmp", lk->path, (long)getpid());
  for (int attempt = 0; attempt < 4; attempt++) {
    /* a new file of ours: never through a link, never over an existing file (one left
     * by an earlier process of this pid is removed; unlink removes a link itself) */
    int fd = open(tmp, O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
    if (fd < 0 && errno == EEXIST && unlink(tmp) == 0) fd = open(tmp, O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
    if (fd < 0) return wv_fail(err, WV_ERR_IO, "%s: cannot create the lock file: %s", tmp, strerror(errno));
    ssize_t w = write(fd, mine, strlen(mine));
    close(fd);
    int linked = w == (ssize_t)strlen(mine) && link(tmp, lk->path) == 0;
    int why = errno;
    unlink(tmp);
    if (linked) {
      lk->held = 1;
      return WV_OK;
    }
    if (w != (ssize_t)strlen(mine) || why != EEXIST)
      return wv_fail(err, WV_ERR_IO, "%s: cannot create the lock file: %s", lk->path, strerror(why));
    char text[512], ohost[256];
    long opid = 0;
    if (!read_lock(lk->path, text, sizeof text, ohost, sizeof ohost, &opid)) {
      struct stat sb;
      if (stat(lk->path, &sb) != 0) continue; /* released meanwhile */
      return wv_fail(err, WV_ERR_IO, "%s is locked by another woven job (%s is unreadable); if no job runs on it, "
                     "remove the lock file", dir, lk->path);
    }
    int same_host = !strcmp(ohost, host);
    if (!same_host || process_alive(opid)) {
      if (same_host)
        return wv_fail(err, WV_ERR_IO, "%s is in use by another woven job (process %ld on this host, %s); wait for "
                       "it to finish or use another directory", dir, opid, lk->path);
      return wv_fail(err, WV_ERR_IO, "%s is in use by another woven job (process %ld on host %s, %s); if that job "
                     "is not running any more, remove the lock file", dir, opid, ohost, lk->path);
    }
    /* Stale: its process is gone. Moved aside first, so two jobs taking it over at
     * once cannot both succeed; the moved file must still be the stale lock. */
    char aside[4160], again[512], h2[256];
    long p2 = 0;
    snprintf(aside, sizeof aside, "%s.stale.%ld", lk->path, (long)getpid());
    if (rename(lk->path, aside) != 0) continue; /* someone else moved it */
    if (!read_lock(aside, again, sizeof again, h2, sizeof h2, &p2) || strcmp(again, text)) {
      /* a fresh lock replaced the stale one in between: put it back */
      int relinked = link(aside, lk->path); /* fails only if yet another lock exists */
      (void)relinked;
      unlink(aside);
      return wv_fail(err, WV_ERR_IO, "%s is in use by another woven job (%s)", dir, lk->path);
    }
    unlink(aside);
    if (note_cap)
      snprintf(note, note_cap, "took over the stale lock %s of process %ld on this host, which is no longer running",
               lk->path, opid);
  }
  return wv_fail(err, WV_ERR_IO, "%s: cannot take the lock %s (other jobs keep taking it)", dir, lk->path);
}

void wv_dir_lock_release(wv_dir_lock *lk) {
  if (lk->held) unlink(lk->path);
  lk->held = 0;
}
