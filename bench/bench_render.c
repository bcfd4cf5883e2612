/* Forward renderer speed: the 800 x 300 cylinder preset at its default spp.
 * Prints progress lines, then one JSON object on the last line: medians of the
 * runs' wall times (2 threads and 1), and of the CPU time of a 2-thread render
 * (samples per CPU second: the figure to compare on a busy machine). */
#include <stdio.h>

#include "bench_common.h"
#include "woven/render.h"

static double time_render(const wv_scene *s, const wv_params *p, int threads, double *cpu) {
  wv_render_opts o = {.threads = threads};
  wv_image img;
  wv_error err = {0};
  double t0 = bench_now(), c0 = bench_cpu_now();
  if (wv_render(s, p, &o, &img, NULL, &err)) {
    fprintf(stderr, "bench_render: %s\n", err.msg);
    exit(1);
  }
  double t = bench_now() - t0;
  if (cpu) *cpu = bench_cpu_now() - c0;
  wv_image_free(&img);
  return t;
}

int main(int argc, char **argv) {
  int runs = argc > 1 ? atoi(argv[1]) : 5;
  if (runs < 1) runs = 1;
  wv_scene s;
  wv_params p;
  wv_scene_preset("cylinder", &s, NULL);
  wv_params_default("twill", &p, NULL);
  double samples = (double)s.width * s.height * s.spp;
  double t2[32], t1[32], c2[32];
  if (runs > 32) runs = 32;
  time_render(&s, &p, 2, NULL); /* warm-up */
  for (int i = 0; i < runs; i++) {
    t2[i] = time_render(&s, &p, 2, &c2[i]);
    t1[i] = time_render(&s, &p, 1, NULL);
    printf("run %d: 2 threads %.1f ms (CPU %.1f ms), 1 thread %.1f ms\n", i + 1, t2[i] * 1e3, c2[i] * 1e3,
           t1[i] * 1e3);
  }
  double m2 = bench_median(t2, runs), m1 = bench_median(t1, runs), mc = bench_median(c2, runs);
  printf("{\"scene\": \"cylinder\", \"width\": %d, \"height\": %d, \"spp\": %d, \"runs\": %d, "
         "\"ms_per_image\": %.1f, \"samples_per_s\": %.0f, \"samples_per_s_1thread\": %.0f, "
         "\"thread_scaling\": %.2f, \"cpu_ms_per_image\": %.1f, \"samples_per_cpu_s\": %.0f}\n",
         s.width, s.height, s.spp, runs, m2 * 1e3, samples / m2, samples / m1, m1 / m2, mc * 1e3, samples / mc);
  return 0;
}
