/* Dataset throughput as `woven dataset` makes it: prior draws rendered in the cylinder
 * scene (800 x 300), samples in parallel with one render thread each, descriptor
 * features per sample, at the scene's default spp and at a lower spp; and the
 * extrapolated time for the paper's 10,000 images. Files are not written (PNG encoding
 * and writes add about 2% in `woven dataset`).
 * Usage: dataset_speed [samples per setting, default 10] [low spp, default 16]
 * Prints one JSON object on the last line. */
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>

#include "bench_common.h"
#include "woven/descriptor.h"
#include "woven/fabricnet.h"
#include "woven/render.h"

static double run(const wv_scene *s, int spp, int n) {
  wv_footprints *fp = NULL;
  wv_error fe;
  if (wv_footprints_create(s, omp_get_max_threads(), &fp, &fe)) {
    fprintf(stderr, "%s\n", fe.msg);
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
  double t0 = bench_now();
#pragma omp parallel num_threads(jobs)
  {
    float *feat = malloc(sizeof(float) * wv_descriptor_size(d[0]));
#pragma omp for schedule(dynamic, 1)
    for (int k = 0; k < n; k++) {
      wv_error e2;
      wv_params p;
      wv_image img = {0};
      wv_render_opts ro = {spp, 1, NULL, NULL, fp}; /* made once per scene, as woven dataset does */
      if (wv_params_sample_prior(wv_net_pattern(k % WV_NET_PATTERNS), (uint64_t)k + 1000, &p, &e2) ||
          wv_render(s, &p, &ro, &img, NULL, &e2) || wv_descriptor_forward(d[omp_get_thread_num()], &img, feat, &e2))
        fprintf(stderr, "%s\n", e2.msg);
      wv_image_free(&img);
    }
    free(feat);
  }
  double el = bench_now() - t0;
  for (int j = 0; j < jobs; j++) wv_descriptor_free(d[j]);
  wv_footprints_free(fp);
  free(d);
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
