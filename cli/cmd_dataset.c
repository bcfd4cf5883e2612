/* woven dataset: FabricNet's synthetic training set (SPEC section 7), resumable. */
#include <errno.h>
#include <limits.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cli.h"
#include "woven/descriptor.h"
#include "woven/dist.h"
#include "woven/fabricnet.h"
#include "woven/io.h"
#include "woven/render.h"

typedef struct {
  const char *scene, *dir, *descriptor, *weights;
  int per, seed, spp, no_augment, jobs;
} dataset_args;

static const cli_opt OPTS[] = {
    CLI_O_STR("--scene", NULL, dataset_args, scene, "S", "a scene file, cylinder or flat45"),
    CLI_O_INT("--per-pattern", NULL, dataset_args, per, 1, WV_DATASET_MAX_PER_PATTERN, "N", "samples per pattern"),
    CLI_O_STR("--output", "-o", dataset_args, dir, "DIR", "the dataset's directory"),
    CLI_O_INT("--seed", NULL, dataset_args, seed, 0, INT_MAX, "N",
              "dataset seed (default 1); sample parameters are a function of\n(seed, pattern, i)"),
    CLI_O_INT("--spp", NULL, dataset_args, spp, 1, WV_SCENE_MAX_SPP, "N", "samples per pixel (default: the scene's)"),
    CLI_O_FLAG("--no-augment", dataset_args, no_augment, "store the renders as they are (8-bit), without the camera"),
    CLI_O_INT("--jobs", NULL, dataset_args, jobs, 1, 1024, "N", "samples rendered at once, one thread each (default: all cores)"),
    CLI_O_STR("--descriptor", NULL, dataset_args, descriptor, "default|vgg19", "the texture descriptor (default: default)"),
    CLI_O_STR("--vgg19-weights", NULL, dataset_args, weights, "FILE", "the VGG-19 weights (--descriptor vgg19)"),
    CLI_O_END};

static const cli_cmd CMD = {
    "dataset",
    "usage: woven dataset --scene S.json|cylinder|flat45 --per-pattern N -o DIR [--seed N] [--spp N]\n"
    "                     [--no-augment] [--jobs N] [--descriptor default|vgg19] [--vgg19-weights FILE]\n"
    "                     [--quiet] [--json]\n"
    "\n"
    "Renders N samples for each built-in weave pattern (plain, basket, the twills, the satins and\n"
    "their 90-degree variants), parameters drawn from the SPEC section 5 priors, passes each\n"
    "through a camera (glints, defocus, exposure and white balance, sensor noise, JPEG), and\n"
    "caches their descriptor features.\n",
    "Writes DIR/dataset.json and DIR/samples/<pattern>_<i>.{json,png,feat} (docs/fabricnet.md).\n"
    "Run the same command again to resume after an interruption: finished samples are kept,\n"
    "a larger --per-pattern extends the set; a DIR made with other settings is refused.\n"
    "Under 'mpirun -n N' the processes share the samples (docs/mpi.md); the directory is the same\n"
    "as one process makes. One job at a time per DIR (DIR/woven.lock).\n",
    {{OPTS, 0}}, 0, {0}};

static int mkdir_p(const char *dir) {
  struct stat sb;
  if (stat(dir, &sb) == 0) return S_ISDIR(sb.st_mode) ? 0 : -1;
  return mkdir(dir, 0777);
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

int cmd_dataset(int argc, char **argv) {
  cli_ctx c = {0, 0, "dataset"};
  dataset_args da = {NULL, NULL, "default", NULL, 0, 1, 0, 0, 0};
  CLI_PARSE(&CMD, argc, argv, &da, &c);
  const char *scene_name = da.scene, *dir = da.dir, *desc_name = da.descriptor, *weights = da.weights;
  long per = da.per, seed = da.seed, spp = da.spp, jobs = da.jobs;
  int augment = !da.no_augment;
  if (!scene_name) return cli_usage_error(c.cmd, "--scene is required");
  if (!dir) return cli_usage_error(c.cmd, "-o DIR is required");
  if (!per) return cli_usage_error(c.cmd, "--per-pattern N is required");
  /* The dataset grows in place: no input may be one of its files. */
  char own[2][4096];
  snprintf(own[0], sizeof own[0], "%s/dataset.json", dir);
  snprintf(own[1], sizeof own[1], "%s/samples", dir);
  const char *inputs[2] = {scene_name, weights};
  int rc = cli_check_not_input(&c, own[0], 0, inputs, 2);
  if (!rc) rc = cli_check_not_input(&c, own[1], 1, inputs, 2);
  if (rc) return rc;
  wv_error err = {0};
  wv_dataset_info want;
  memset(&want, 0, sizeof want);
  if (wv_scene_load(scene_name, &want.scene, &err)) return cli_fail(&c, &err);
  char *sj = wv_scene_to_json(&want.scene);
  if (!sj || strlen(sj) >= sizeof want.scene_json) {
    free(sj);
    return cli_usage_error(c.cmd, "scene description too long");
  }
  snprintf(want.scene_json, sizeof want.scene_json, "%s", sj);
  free(sj);
  want.version = WV_DATASET_VERSION, want.renderer = WV_RENDER_VERSION, want.seed = (uint64_t)seed, want.per_pattern = (int)per;
  want.augment = augment;
  want.spp = spp ? (int)spp : want.scene.spp;
  if (jobs == 0) jobs = omp_get_max_threads();

  /* One descriptor per job: descriptors keep scratch and are not thread-safe. */
  wv_descriptor **desc = calloc((size_t)jobs, sizeof *desc);
  if (!desc) return cli_usage_error(c.cmd, "out of memory");
  for (long j = 0; j < jobs && !rc; j++)
    if (wv_descriptor_create(desc_name, weights, &desc[j], &err)) rc = cli_fail(&c, &err);
  if (!rc) {
    snprintf(want.descriptor, sizeof want.descriptor, "%s", wv_descriptor_name(desc[0]));
    want.n_feat = (int)wv_descriptor_size(desc[0]);
  }
  /* Under mpirun every rank runs this command: rank 0 owns the lock and dataset.json,
   * the others only render their share and stay quiet. */
  wv_dist dist;
  wv_dir_lock lock = {{0}, 0};
  if (wv_dist_begin(&dist, &err)) rc = cli_fail(&c, &err);
  if (dist.rank > 0) c.quiet = 1, c.json = 0;

  /* One job per directory: a second one would render the same samples. */
  if (!rc && dist.rank == 0) {
    char note[4400];
    if (mkdir_p(dir) != 0) {
      fprintf(stderr, "woven dataset: error: %s: cannot create directory: %s\n", dir, strerror(errno));
      rc = WV_ERR_IO;
    } else if (wv_dir_lock_acquire(dir, &lock, note, sizeof note, &err)) {
      rc = cli_fail(&c, &err);
    } else if (note[0]) {
      cli_info(&c, "%s\n", note);
    }
  }

  /* An existing dataset must have been made with the same settings. */
  struct stat sb;
  char path[4096];
  snprintf(path, sizeof path, "%s/dataset.json", dir);
  int existing = !rc && dist.rank == 0 && stat(path, &sb) == 0;
  if (existing) {
    wv_dataset_info have;
    if (wv_dataset_info_read(dir, &have, &err)) {
      rc = cli_fail(&c, &err);
    } else {
      wv_scene hs = have.scene;
      char *hj = wv_scene_to_json(&hs);
      char *wj = wv_scene_to_json(&want.scene);
      const char *why = have.version != want.version        ? "format version"
                        : have.seed != want.seed            ? "seed"
                        : have.augment != want.augment      ? "camera augmentation setting"
                        : strcmp(have.descriptor, want.descriptor) || have.n_feat != want.n_feat ? "descriptor"
                        : have.spp != want.spp               ? "spp"
                        : have.renderer != want.renderer     ? "renderer version"
                        : !hj || !wj || strcmp(hj, wj)       ? "scene"
                                                             : NULL;
      free(hj), free(wj);
      if (why) {
        fprintf(stderr,
                "woven dataset: error: %s holds a dataset made with another %s (seed %llu, spp %d, descriptor "
                "'%s', scene '%s'); refusing to mix samples: use another directory\n",
                dir, why, (unsigned long long)have.seed, have.spp, have.descriptor, have.scene.name);
        rc = WV_ERR_INVALID;
      } else if (have.per_pattern > want.per_pattern) {
        want.per_pattern = have.per_pattern; /* never shrink the recorded size */
        cli_info(&c, "%s records %d per pattern; completing all of them\n", dir, have.per_pattern);
      }
    }
  } else if (!rc && dist.rank == 0) {
    if (mkdir_p(dir) != 0) {
      fprintf(stderr, "woven dataset: error: %s: cannot create directory: %s\n", dir, strerror(errno));
      rc = WV_ERR_IO;
    }
  }
  snprintf(path, sizeof path, "%s/samples", dir);
  if (!rc && dist.rank == 0 && mkdir_p(path) != 0) {
    fprintf(stderr, "woven dataset: error: %s: cannot create directory: %s\n", path, strerror(errno));
    rc = WV_ERR_IO;
  }
  if (!rc && dist.rank == 0) wv_remove_stale_temps(path, NULL);
  if (!rc && dist.rank == 0) cli_clean_temps_beside(own[0]);
  /* dataset.json before any sample: a directory with samples always says what they are */
  if (!rc && dist.rank == 0 && wv_dataset_info_write(dir, &want, &err)) rc = cli_fail(&c, &err);
  /* the other ranks start once rank 0 is ready, with its size (it may have grown) */
  int shared[2] = {rc, want.per_pattern};
  wv_dist_bcast_ints(&dist, shared, 2);
  rc = wv_dist_max_int(&dist, rc ? rc : shared[0]);
  want.per_pattern = shared[1];

  int total = wv_dataset_pattern_count(&want) * want.per_pattern, ntodo = 0, nbefore = 0, nleft = 0;
  int *todo = NULL;
  if (!rc && wv_dist_share(&dist, total, sample_done, &(sample_check){dir, &want}, &todo, &ntodo, &nleft, &err))
    rc = cli_fail(&c, &err);
  if (!rc) {
    nbefore = total - nleft;
    cli_info(&c, "%s: %d samples (%d per pattern), %d done, %d to render at %d x %d, %d spp, %ld job(s)%s\n", dir,
             total, want.per_pattern, nbefore, nleft, want.scene.width, want.scene.height, want.spp, jobs,
             dist.size > 1 ? " per process" : "");
    if (dist.size > 1) cli_info(&c, "%d processes share them (MPI)\n", dist.size);
  }
  double t0 = cli_now();
  int done = 0, failed = 0, last_report = 0;
  wv_error first_err = {0};
  cli_progress bar;
  cli_progress_start(&bar, &c, "dataset");
  int tty = bar.enabled;
  /* Every sample shares the scene: its per-pixel camera geometry is made once. */
  wv_footprints *fp = NULL;
  if (!rc && ntodo > 0 && wv_footprints_create(&want.scene, (int)jobs, &fp, &err)) rc = cli_fail(&c, &err);
  if (!rc && ntodo > 0) {
    int nj = (int)(jobs < ntodo ? jobs : ntodo);
    /* Samples in parallel with one render thread each beat one sample at a time with
     * all threads (less synchronisation, the descriptor overlaps with rendering). */
    int render_threads = nj > 1 ? 1 : 0;
#pragma omp parallel num_threads(nj)
    {
      int tid = omp_get_thread_num();
      float *feat = malloc(sizeof(float) * (size_t)want.n_feat);
#pragma omp for schedule(dynamic, 1)
      for (int t = 0; t < ntodo; t++) {
        int stop;
#pragma omp atomic read
        stop = failed;
        if (stop) continue;
        wv_error e = {0};
        wv_status st = feat ? wv_dataset_make_sample(dir, &want, todo[t], render_threads, fp, desc[tid], feat, &e)
                            : wv_fail(&e, WV_ERR_NOMEM, "out of memory for features");
#pragma omp critical(dataset_progress)
        {
          if (st) {
            if (!failed) first_err = e;
            failed = 1;
          } else {
            done++;
            double f = (double)done / ntodo;
            cli_progress_update(&bar, f);
            /* without a terminal (logs, nohup): a line every 5% */
            if (!tty && !c.quiet && !c.json && (int)(f * 20) > last_report) {
              last_report = (int)(f * 20);
              double el = cli_now() - t0;
              fprintf(stderr, "dataset %d/%d  %.2f samples/s  %.0fs, %.0fs left\n", done, ntodo, done / el, el,
                      el * (1 - f) / f);
            }
          }
        }
      }
      free(feat);
    }
  }
  wv_footprints_free(fp);
  cli_progress_end(&bar);
  double el = cli_now() - t0;
  if (!rc && failed) rc = cli_fail(&c, &first_err);
  done = wv_dist_sum_int(&dist, done);
  el = wv_dist_max_double(&dist, el);
  rc = wv_dist_max_int(&dist, rc);
  if (!rc) {
    cli_info(&c, "%d samples rendered in %.1f s (%.3f samples/s); %s has %d of %d\n", done, el,
             el > 0 ? done / el : 0.0, dir, nbefore + done, total);
    if (c.json)
      cli_print_json(json_pack("{s:o,s:i,s:i,s:i,s:o,s:o,s:i,s:i,s:i,s:I,s:i}", "dir", cli_str(dir), "samples", total,
                               "done_before", nbefore, "rendered", done, "seconds", cli_real(el, 3), "samples_per_s",
                               cli_real(el > 0 ? done / el : 0.0, 4), "spp", want.spp, "width", want.scene.width,
                               "height", want.scene.height, "jobs", (json_int_t)jobs, "processes", dist.size));
  }
  for (long j = 0; j < jobs; j++) wv_descriptor_free(desc[j]);
  free(desc);
  free(todo);
  wv_dir_lock_release(&lock);
  wv_dist_end(&dist);
  return rc;
}
