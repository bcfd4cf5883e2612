/* Dataset throughput as `woven dataset` makes it (wv_dataset_make_sample, the same
 * function): prior draws rendered in the cylinder scene (800 x 300), samples in
 * parallel with one render thread each, the scene's footprints made once, each
 * sample's parameter file, PNG and descriptor features written into a temporary
 * dataset directory (removed at the end), at the scene's default spp and at a lower
 * spp; and the extrapolated time for the paper's 10,000 images.
 * Usage: dataset_speed [samples per setting, default 10] [low spp, default 16]
 * Prints one JSON object on the last line. */
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "bench_common.h"
#include "woven/dataset.h"
#include "woven/descriptor.h"
#include "woven/render.h"

static void remove_dir(const char *dir) {
  char cmd[4200];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", dir);
}

static double run(const wv_scene *s, int spp, int n) {
  char dir[] = "/tmp/woven-dataset-speed-XXXXXX", sub[64];
  if (!mkdtemp(dir)) {
    perror("mkdtemp");
    exit(1);
  }
  snprintf(sub, sizeof sub, "%s/samples", dir);
  if (mkdir(sub, 0777) != 0) {
    perror(sub);
    exit(1);
  }
  int jobs = omp_get_max_threads();
  wv_descriptor **d = calloc((size_t)jobs, sizeof *d);
  wv_error e;
  for (int j = 0; j < jobs; j++)
    if (wv_descriptor_create_default(&d[j], &e)) {
      fprintf(stderr, "%s\n", e.msg);
      exit(1);
    }
  wv_dataset_info info;
  memset(&info, 0, sizeof info);
  info.version = WV_DATASET_VERSION, info.renderer = WV_RENDER_VERSION, info.seed = 1000, info.per_pattern = n;
  info.augment = 1;
  info.spp = spp, info.scene = *s, info.n_feat = (int)wv_descriptor_size(d[0]);
  double t0 = bench_now();
  wv_footprints *fp = NULL; /* made once per scene, as woven dataset does (inside the timing) */
  if (wv_footprints_create(s, jobs, &fp, &e)) {
    fprintf(stderr, "%s\n", e.msg);
    exit(1);
  }
#pragma omp parallel num_threads(jobs)
  {
    float *feat = malloc(sizeof(float) * (size_t)info.n_feat);
#pragma omp for schedule(dynamic, 1)
    for (int k = 0; k < n; k++) {
      wv_error e2;
      if (wv_dataset_make_sample(dir, &info, k, 1, fp, NULL, d[omp_get_thread_num()], feat, &e2))
        fprintf(stderr, "%s\n", e2.msg);
    }
    free(feat);
  }
  double el = bench_now() - t0;
  wv_footprints_free(fp);
  for (int j = 0; j < jobs; j++) wv_descriptor_free(d[j]);
  free(d);
  remove_dir(dir);
  return n / el;
}

int main(int argc, char **argv) {
  int n = argc > 1 ? atoi(argv[1]) : 10, low = argc > 2 ? atoi(argv[2]) : 16;
  if (n < 1 || low < 1) {
    fprintf(stderr, "usage: dataset_speed [samples per setting >= 1, default 10] [low spp >= 1, default 16]\n");
    return 2;
  }
  wv_scene s;
  wv_error e;
  if (wv_scene_preset("cylinder", &s, &e)) return 1;
  double r_def = run(&s, s.spp, n), r_low = run(&s, low, n * 4);
  fprintf(stderr, "%d spp: %.3f samples/s (10,000 in %.1f min); %d spp: %.3f samples/s (10,000 in %.1f min)\n", s.spp,
          r_def, 10000 / r_def / 60, low, r_low, 10000 / r_low / 60);
  printf("{\"width\": %d, \"height\": %d, \"threads\": %d, \"default_spp\": %d, \"samples_per_s_default\": %.4f, "
         "\"minutes_10000_default\": %.1f, \"low_spp\": %d, \"samples_per_s_low\": %.4f, \"minutes_10000_low\": %.1f}\n",
         s.width, s.height, omp_get_max_threads(), s.spp, r_def, 10000 / r_def / 60, low, r_low, 10000 / r_low / 60);
  return 0;
}
