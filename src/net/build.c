/* woven: building FabricNet's dataset (woven dataset): the directory's lock and record,
 * the check that an existing dataset was made with the same settings, and the samples
 * not yet done rendered in parallel and shared over the ranks of an MPI job. Notes and
 * progress come from rank 0 only. */
#include <errno.h>
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "sampler/sampler.h"
#include "util/note.h"
#include "woven/dataset.h"
#include "woven/descriptor.h"
#include "woven/io.h"
#include "woven/render.h"

void wv_dataset_build_opts_default(wv_dataset_build_opts *o) {
  memset(o, 0, sizeof *o);
  o->seed = 1, o->augment = 1, o->descriptor = "default";
}

static wv_status mkdir_p(const char *dir, wv_error *err) {
  struct stat sb;
  if (stat(dir, &sb) == 0 ? S_ISDIR(sb.st_mode) : mkdir(dir, 0777) == 0) return WV_OK;
  return wv_fail(err, WV_ERR_IO, "%s: cannot create directory: %s", dir, strerror(errno));
}

/* A sample is done when its files are whole (wv_dataset_sample_done). */
typedef struct {
  const char *dir;
  const wv_dataset_info *info;
} sample_check;
static int sample_done(void *user, int k) {
  const sample_check *sc = user;
  return wv_dataset_sample_done(sc->dir, sc->info, k);
}

/* Whether samples of renderer version a and b at spp are the same images: versions 2 and 3
 * differ only in the pixel's sample grid, and only where version 2's (ceil(sqrt(spp))
 * columns, as many rows as they need) held more cells than samples (WV_RENDER_VERSION). */
static int same_renderer(int a, int b, int spp) {
  if (a == b) return 1;
  if (a < 2 || a > 3 || b < 2 || b > 3 || spp < 1) return 0;
  int ox = (int)ceil(sqrt((double)spp)), oy = (spp + ox - 1) / ox, nx, ny;
  wv_pixel_grid(spp, &nx, &ny);
  return ox == nx && oy == ny;
}

/* The settings of want, checked against those recorded in dir (rank 0). */
static wv_status check_existing(const wv_dataset_build_opts *o, const wv_dist *dist, wv_dataset_info *want,
                                wv_error *err) {
  wv_dataset_info have;
  wv_status st = wv_dataset_info_read(o->dir, &have, err);
  if (st) return st;
  wv_scene hs = have.scene;
  char *hj = wv_scene_to_json(&hs);
  char *wj = wv_scene_to_json(&want->scene);
  char *htj = have.pair ? wv_scene_to_json(&have.tscene) : NULL, *wtj = want->pair ? wv_scene_to_json(&want->tscene) : NULL;
  int tdiff = have.pair != want->pair || (have.pair && (!htj || !wtj || strcmp(htj, wtj)));
  free(htj), free(wtj);
  const char *why = tdiff                           ? "transmission scene (or none)"
                    : have.version != want->version ? "format version"
                    : have.seed != want->seed       ? "seed"
                    : have.augment != want->augment ? "camera augmentation setting"
                    : have.draws != want->draws     ? "way of drawing the cloths (--photo-draws)"
                    : strcmp(have.descriptor, want->descriptor) || have.n_feat != want->n_feat ? "descriptor"
                    : have.spp != want->spp                                                    ? "spp"
                    : !same_renderer(have.renderer, want->renderer, have.spp)                  ? "renderer version"
                    : !hj || !wj || strcmp(hj, wj)                                             ? "scene"
                                                                                               : NULL;
  free(hj), free(wj);
  if (why)
    return wv_fail(err, WV_ERR_INVALID,
                   "%s holds a dataset made with another %s (seed %llu, spp %d, descriptor '%s', scene '%s'); "
                   "refusing to mix samples: use another directory",
                   o->dir, why, (unsigned long long)have.seed, have.spp, have.descriptor, have.scene.name);
  if (have.per_pattern > want->per_pattern) {
    want->per_pattern = have.per_pattern; /* never shrink the recorded size */
    wv_note(dist->rank ? NULL : o->on_note, o->user, "%s records %d per pattern; completing all of them", o->dir,
            have.per_pattern);
  }
  return WV_OK;
}

/* Rank 0's preparation: the inputs are not the dataset's files, the lock, an existing
 * dataset's settings, samples/ and dataset.json. */
static wv_status prepare(const wv_dataset_build_opts *o, const wv_dist *dist, wv_dataset_info *want, wv_dir_lock *lock,
                         wv_error *err) {
  const char *dir = o->dir;
  char own[2][4096], path[4096];
  snprintf(own[0], sizeof own[0], "%s/dataset.json", dir);
  snprintf(own[1], sizeof own[1], "%s/samples", dir);
  const char *inputs[3] = {o->scene, o->weights, o->transmission_scene};
  wv_status st = wv_check_not_input(own[0], 0, inputs, 3, err);
  if (!st) st = wv_check_not_input(own[1], 1, inputs, 3, err);
  if (!st) st = mkdir_p(dir, err);
  char lnote[4400];
  if (!st && !(st = wv_dir_lock_acquire(dir, lock, lnote, sizeof lnote, err)) && lnote[0])
    wv_note(dist->rank ? NULL : o->on_note, o->user, "%s", lnote);
  struct stat sb;
  if (!st && stat(own[0], &sb) == 0) st = check_existing(o, dist, want, err);
  snprintf(path, sizeof path, "%s/samples", dir);
  if (!st) st = mkdir_p(path, err);
  if (!st) {
    wv_remove_stale_temps(path, NULL);
    wv_remove_stale_temps(dir, "dataset.json");
  }
  /* dataset.json before any sample: a directory with samples always says what they are */
  if (!st) st = wv_dataset_info_write(dir, want, err);
  return st;
}

/* The samples in todo, jobs at a time with one descriptor each (descriptors keep scratch
 * and are not thread-safe). Returns the number done, or -1 - done after a failure
 * (*first_err the first); *stopped when on_progress asked to stop. */
static int render_samples(const wv_dataset_build_opts *o, const wv_dist *dist, const wv_dataset_info *want, int *stopped,
                          const int *todo, int ntodo, int jobs, wv_descriptor **desc, const struct wv_footprints *fp,
                          const struct wv_footprints *fp_t, double t0, wv_error *first_err) {
  int done = 0, failed = 0; /* failed: 1 a sample failed, 2 on_progress asked to stop */
  int nj = jobs < ntodo ? jobs : ntodo;
  /* Samples in parallel with one render thread each beat one sample at a time with
   * all threads (less synchronisation, the descriptor overlaps with rendering). */
  int render_threads = nj > 1 ? 1 : 0;
#pragma omp parallel num_threads(nj)
  {
    int tid = omp_get_thread_num();
    float *feat = malloc(sizeof(float) * (size_t)want->n_feat);
#pragma omp for schedule(dynamic, 1)
    for (int t = 0; t < ntodo; t++) {
      int stop;
#pragma omp atomic read
      stop = failed;
      if (stop) continue;
      wv_error e = {0};
      wv_status st = feat ? wv_dataset_make_sample(o->dir, want, todo[t], render_threads, fp, fp_t, desc[tid], feat, &e)
                          : wv_fail(&e, WV_ERR_NOMEM, "out of memory for features");
#pragma omp critical(dataset_progress)
      {
        if (st) {
          if (failed != 1) *first_err = e;
          failed = 1;
        } else {
          done++;
          /* a stop leaves the samples in flight to finish: the directory stays resumable */
          if (o->on_progress && dist->rank == 0 && o->on_progress(o->user, done, ntodo, omp_get_wtime() - t0))
            failed = failed ? failed : 2;
        }
      }
    }
    free(feat);
  }
  *stopped = failed == 2;
  return failed == 1 ? -1 - done : done;
}

wv_status wv_dataset_build(const wv_dist *dist, const wv_dataset_build_opts *o, wv_dataset_build_result *res,
                           wv_error *err) {
  memset(res, 0, sizeof *res);
  wv_dataset_info want;
  memset(&want, 0, sizeof want);
  wv_status st = wv_scene_load(o->scene, &want.scene, err);
  if (st) return st;
  char *sj = wv_scene_to_json(&want.scene);
  if (!sj || strlen(sj) >= sizeof want.scene_json) {
    free(sj);
    return wv_fail(err, WV_ERR_INVALID, "%s: scene description too long", o->scene);
  }
  snprintf(want.scene_json, sizeof want.scene_json, "%s", sj);
  free(sj);
  if (o->transmission_scene) { /* a pair set: each sample also rendered lit from behind */
    if ((st = wv_scene_load(o->transmission_scene, &want.tscene, err))) return st;
    if (!wv_scene_transmits(&want.tscene))
      return wv_fail(err, WV_ERR_INVALID,
                     "%s is not a back-lit scene (a plane with its light below the cloth): it cannot render the "
                     "transmission images",
                     o->transmission_scene);
    if (want.tscene.width != want.scene.width || want.tscene.height != want.scene.height)
      return wv_fail(err, WV_ERR_INVALID, "the back-lit scene %s renders %d x %d, not the %d x %d of %s",
                     o->transmission_scene, want.tscene.width, want.tscene.height, want.scene.width,
                     want.scene.height, o->scene);
    char *tj = wv_scene_to_json(&want.tscene);
    if (!tj || strlen(tj) >= sizeof want.tscene_json) {
      free(tj);
      return wv_fail(err, WV_ERR_INVALID, "%s: scene description too long", o->transmission_scene);
    }
    snprintf(want.tscene_json, sizeof want.tscene_json, "%s", tj);
    free(tj);
    want.pair = 1;
  }
  want.version = want.pair ? 3 : 2, want.renderer = WV_RENDER_VERSION, want.seed = o->seed;
  want.per_pattern = o->per_pattern, want.augment = o->augment, want.draws = o->draws;
  want.spp = o->spp ? o->spp : want.scene.spp;
  double jt[2][2], mm_per_px;
  if (want.draws == WV_DRAWS_PHOTO && !wv_render_centre_scale(&want.scene, jt, &mm_per_px))
    return wv_fail(err, WV_ERR_INVALID,
                   "%s does not see the sample at its image centre: --photo-draws sets the yarns' spacing there",
                   o->scene);
  int jobs = o->jobs ? o->jobs : omp_get_max_threads();

  wv_descriptor **desc = calloc((size_t)jobs, sizeof *desc);
  if (!desc) return wv_fail(err, WV_ERR_NOMEM, "out of memory");
  for (int j = 0; j < jobs && !st; j++) st = wv_descriptor_create(o->descriptor, o->weights, &desc[j], err);
  if (!st) {
    snprintf(want.descriptor, sizeof want.descriptor, "%s", wv_descriptor_name(desc[0]));
    want.n_feat = (int)wv_descriptor_size(desc[0]) * (want.pair ? 2 : 1);
  }
  /* Under mpirun every rank runs this: rank 0 owns the lock and dataset.json, the
   * others only render their share. */
  wv_dir_lock lock = {{0}, 0};
  if (!st && dist->rank == 0) st = prepare(o, dist, &want, &lock, err);
  /* the other ranks start once rank 0 is ready, with its size (it may have grown) */
  int shared[2] = {(int)st, want.per_pattern};
  wv_dist_bcast_ints(dist, shared, 2);
  int rc = wv_dist_max_int(dist, st ? (int)st : shared[0]);
  want.per_pattern = shared[1];

  int total = wv_dataset_pattern_count(&want) * want.per_pattern, ntodo = 0, nleft = 0;
  int *todo = NULL;
  if (!rc && (st = wv_dist_share(dist, total, sample_done, &(sample_check){o->dir, &want}, &todo, &ntodo, &nleft, err)))
    rc = (int)st;
  if (!rc) {
    res->done_before = total - nleft;
    wv_note(dist->rank ? NULL : o->on_note, o->user,
            "%s: %d samples (%d per pattern), %d done, %d to render at %d x %d, %d spp, %d job(s)%s", o->dir, total,
            want.per_pattern, res->done_before, nleft, want.scene.width, want.scene.height, want.spp, jobs,
            dist->size > 1 ? " per process" : "");
    if (dist->size > 1) wv_note(dist->rank ? NULL : o->on_note, o->user, "%d processes share them (MPI)", dist->size);
  }
  double t0 = omp_get_wtime();
  int done = 0;
  /* Every sample shares the scene: its per-pixel camera geometry is made once. */
  wv_footprints *fp = NULL, *fp_t = NULL;
  if (!rc && ntodo > 0 && (st = wv_footprints_create(&want.scene, jobs, &fp, err))) rc = (int)st;
  if (!rc && ntodo > 0 && want.pair && (st = wv_footprints_create(&want.tscene, jobs, &fp_t, err))) rc = (int)st;
  if (!rc && ntodo > 0) {
    wv_error first = {0};
    done = render_samples(o, dist, &want, &res->stopped, todo, ntodo, jobs, desc, fp, fp_t, t0, &first);
    if (done < 0) {
      done = -1 - done;
      *err = first;
      rc = first.code ? (int)first.code : WV_ERR_INVALID;
    }
  }
  wv_footprints_free(fp);
  wv_footprints_free(fp_t);
  double el = omp_get_wtime() - t0;
  int local = rc;
  done = wv_dist_sum_int(dist, done);
  el = wv_dist_max_double(dist, el);
  rc = wv_dist_max_int(dist, rc);
  if (rc && !local) err->msg[0] = '\0', err->code = (wv_status)rc; /* another rank's failure */
  res->samples = total, res->rendered = done, res->seconds = el, res->spp = want.spp;
  res->width = want.scene.width, res->height = want.scene.height, res->jobs = jobs, res->per_pattern = want.per_pattern;
  for (int j = 0; j < jobs; j++) wv_descriptor_free(desc[j]);
  free(desc);
  free(todo);
  wv_dir_lock_release(&lock);
  return (wv_status)rc;
}
