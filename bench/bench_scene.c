/* Mesh renderer speed: the bundled draped cloth under the studio environment
 * (scenes/drape-studio.json) at its 1024 x 768 and default spp, and the same view
 * as a 256 x 192 preview. Per size: median wall time of the runs for loading
 * (mesh, environment, ray tracer) and rendering with 2 threads, CPU time of the
 * render (steadier on a busy machine) and rays per second. With a reference
 * (an EXR of the same view, e.g. woven scene --spp 1024 --seed 99 -o ref.exr),
 * also the mean absolute difference of the full render's radiance from it: the
 * render's noise, to hold a faster estimator to the same.
 * Usage: bench_scene [runs, default 3] [scene.json] [reference.exr]. Prints one
 * JSON object last. */
#include <stdio.h>
#include <stdlib.h>

#include "bench_common.h"
#include "woven/io.h"
#include "woven/scene3d.h"

typedef struct {
  double load, render, cpu, rays, mad;
} timing;

/* One load and render; mad: of the radiance from ref (when not NULL), else -1. */
static timing run(const char *path, int w, int h, const wv_image *ref) {
  wv_error e = {0};
  wv_scene3d s;
  wv_world *world;
  timing t;
  double t0 = bench_now();
  if (wv_scene3d_read(path, &s, &e) || wv_world_load(&s, NULL, 2, &world, &e)) {
    fprintf(stderr, "bench_scene: %s\n", e.msg);
    exit(1);
  }
  t.load = bench_now() - t0;
  if (w) s.width = s.response.width = w, s.height = s.response.height = h;
  wv_scene3d_opts o = {.threads = 2};
  wv_scene3d_stats st;
  wv_image img, rad;
  double t1 = bench_now(), c1 = bench_cpu_now();
  if (wv_scene3d_render(&s, world, &o, &img, &rad, &st, &e)) {
    fprintf(stderr, "bench_scene: %s\n", e.msg);
    exit(1);
  }
  t.render = bench_now() - t1, t.cpu = bench_cpu_now() - c1, t.rays = st.rays, t.mad = -1;
  if (ref) {
    if (ref->w != rad.w || ref->h != rad.h || ref->c != rad.c) {
      fprintf(stderr, "bench_scene: the reference is %d x %d x %d, the render %d x %d x %d\n", ref->w, ref->h, ref->c,
              rad.w, rad.h, rad.c);
      exit(1);
    }
    t.mad = wv_image_mad(&rad, ref);
  }
  wv_image_free(&img);
  wv_image_free(&rad);
  wv_world_free(world);
  wv_scene3d_free(&s);
  return t;
}

int main(int argc, char **argv) {
  int runs = argc > 1 ? atoi(argv[1]) : 3;
  const char *path = argc > 2 ? argv[2] : WOVEN_SOURCE_DIR "/scenes/drape-studio.json";
  wv_image ref = {0};
  if (argc > 3) {
    wv_error e = {0};
    if (wv_image_read(argv[3], &ref, NULL, &e)) {
      fprintf(stderr, "bench_scene: %s\n", e.msg);
      return 1;
    }
  }
  if (runs < 1) runs = 1;
  if (runs > 16) runs = 16;
  const int sizes[2][2] = {{0, 0}, {256, 192}};
  printf("{\"scene\": \"%s\", \"runs\": %d, \"threads\": 2", path, runs);
  for (int k = 0; k < 2; k++) {
    double load[16], ren[16], cpu[16], rps[16], rpc[16], mad = -1;
    for (int i = 0; i < runs; i++) {
      timing t = run(path, sizes[k][0], sizes[k][1], k == 0 && argc > 3 ? &ref : NULL);
      mad = t.mad; /* the same every run: the render is deterministic */
      load[i] = t.load, ren[i] = t.render, cpu[i] = t.cpu, rps[i] = t.rays / t.render, rpc[i] = t.rays / t.cpu;
      fprintf(stderr, "%s run %d: load %.2f s, render %.2f s (CPU %.2f s), %.2f Mrays/s\n", k ? "preview" : "full", i + 1,
              t.load, t.render, t.cpu, rps[i] * 1e-6);
    }
    printf(", \"%s\": {\"load_s\": %.3f, \"render_s\": %.3f, \"total_s\": %.3f, \"render_cpu_s\": %.3f, "
           "\"rays_per_s\": %.0f, \"rays_per_cpu_s\": %.0f",
           k ? "preview_256x192" : "full", bench_median(load, runs), bench_median(ren, runs),
           bench_median(load, runs) + bench_median(ren, runs), bench_median(cpu, runs), bench_median(rps, runs),
           bench_median(rpc, runs));
    if (mad >= 0) printf(", \"mad_vs_reference\": %.6f}", mad);
    else printf("}");
  }
  printf("}\n");
  wv_image_free(&ref);
  return 0;
}
