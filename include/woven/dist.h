/* woven: running one job over many processes (MPI) and guarding an output directory
 * against a second job. A job shares a range of work items over the ranks of an MPI
 * job; without MPI (a build without it, or a process not started by mpirun/srun) the
 * same calls describe one process, rank 0 of 1, so every command runs unchanged. */
#ifndef WOVEN_DIST_H
#define WOVEN_DIST_H

#include <stddef.h>
#include "woven/error.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
  int rank, size; /* this process, and how many share the job */
  int mpi;        /* 1 when this process joined an MPI job (wv_dist_end must follow) */
} wv_dist;

/* 1 when woven was built with MPI. */
int wv_dist_built_with_mpi(void);
/* Joins the MPI job when the process was started by an MPI launcher (mpirun, srun)
 * and woven was built with MPI; otherwise d is rank 0 of 1. */
wv_status wv_dist_begin(wv_dist *d, wv_error *err);
/* Leaves the MPI job (collective: every rank calls it). */
void wv_dist_end(wv_dist *d);
void wv_dist_barrier(const wv_dist *d);
/* Rank 0's n integers to every rank (collective). */
void wv_dist_bcast_ints(const wv_dist *d, int *v, int n);
/* The largest / the sum of v over the ranks, on every rank (collective). */
int wv_dist_max_int(const wv_dist *d, int v);
int wv_dist_sum_int(const wv_dist *d, int v);
double wv_dist_max_double(const wv_dist *d, double v);

/* This rank's share of the items k in [0, n) that are not done. Each rank asks
 * done(user, k) for k = rank, rank + size, ... (the check is shared too); the items
 * still to do, in increasing order, go round the ranks: the t-th belongs to rank
 * t mod size. *mine (caller frees) gets this rank's items, *ntodo how many remain
 * over all ranks. Collective. */
wv_status wv_dist_share(const wv_dist *d, int n, int (*done)(void *user, int k), void *user, int **mine, int *nmine,
                        int *ntodo, wv_error *err);

/* ---- output directory lock ----
 * DIR/woven.lock, created exclusively, holds "host pid" of the job that owns DIR.
 * A second job finds it and is refused; a lock whose process is gone (same host) is
 * stale and taken over, and *note says so (empty otherwise). A lock from another
 * host cannot be checked: the message says how to remove it by hand. */
typedef struct {
  char path[4096];
  int held;
} wv_dir_lock;
wv_status wv_dir_lock_acquire(const char *dir, wv_dir_lock *lk, char *note, size_t note_cap, wv_error *err);
void wv_dir_lock_release(wv_dir_lock *lk);

#ifdef __cplusplus
}
#endif
#endif
