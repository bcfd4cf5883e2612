/* woven: a batch of captures, one per photo, shared over the processes of an MPI job
 * (or run by one process), resumable, with a summary of every photo. The capture of
 * one photo is the caller's function (woven capture-batch passes woven capture's). */
#ifndef WOVEN_BATCH_H
#define WOVEN_BATCH_H

#include "woven/dist.h"
#include "woven/error.h"

#ifdef __cplusplus
extern "C" {
#endif

/* One photo of a batch: its path and its name (the file name without its extension),
 * which names its output directory. */
typedef struct {
  char photo[4096];
  char name[256];
} wv_batch_item;

/* The photos of LIST: a directory (its .png, .jpg, .jpeg and .exr files, by name) or
 * a text file of paths, one a line (blank lines and lines starting with # skipped;
 * a relative path is relative to the list file's directory). Two photos with the same
 * name are refused. *items is the caller's to free. */
wv_status wv_batch_list(const char *list, wv_batch_item **items, int *n, wv_error *err);

/* What one capture reports. */
typedef struct {
  int status;       /* 0 captured, else the wv_status / exit code of the failure */
  char error[1024]; /* why it failed */
  char pattern[32];
  double ssim_start, ssim_fit; /* SSIM of the start (network) and of the fit against the photo */
  double wsc;                  /* weave-spectrum correlation of the fit; NaN when the capture does not report it */
  int iterations;
} wv_batch_result;

/* Captures photo into dir (a directory that does not exist or holds an unfinished
 * capture to replace); fills res and returns res->status. */
typedef int (*wv_batch_capture_fn)(void *user, const char *photo, const char *dir, wv_batch_result *res);

/* list, dir and capture are required; on_photo and user may be zero (NULL). */
typedef struct {
  const char *list; /* as wv_batch_list takes it */
  const char *dir;  /* the output directory */
  wv_batch_capture_fn capture;
  void *user;
  /* A line about each photo as it finishes (may be NULL); called on the rank that
   * captured it. */
  void (*on_photo)(void *user, const wv_batch_item *item, const wv_batch_result *res, double seconds, int done,
                   int todo);
} wv_batch_opts;

typedef struct {
  int photos;      /* in the list */
  int done_before; /* finished by an earlier run, not redone */
  int captured;    /* by this run, over all ranks */
  int failed;      /* by this run, over all ranks */
  double seconds;  /* wall time of the captures (the slowest rank) */
} wv_batch_summary;

/* Runs the batch (collective over d's ranks). DIR/<name>/ holds each finished capture
 * and appears whole: it is written in DIR/.batch/work/<name>/ and renamed into place;
 * a photo whose DIR/<name>/params.json exists is not captured again. Each attempt's
 * result is kept in DIR/.batch/<name>.json. Rank 0 locks DIR (wv_dir_lock) and at the
 * end writes DIR/summary.json and DIR/summary.html over every photo of the list. A
 * photo that fails is recorded and the others go on: the run returns WV_OK and
 * counts it in sum->failed. The error of a failure on rank 0 during set-up reaches
 * every rank as its status; err's message is set only where it happened. */
wv_status wv_batch_run(const wv_dist *d, const wv_batch_opts *o, wv_batch_summary *sum, char *note, size_t note_cap,
                       wv_error *err);

#ifdef __cplusplus
}
#endif
#endif
