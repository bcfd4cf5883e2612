/* How many camera rays per pixel the mesh renderer needs: SPEC section 6's rule
 * (doubling the spp changes the image by less than 1%, mean absolute difference
 * of the capture image) on a scene file, by default the bundled draped cloth under
 * the studio environment at its full 1024 x 768. Renders the ladder 4, 8, ..., 128
 * spp (the scene's yarn samples per ray unchanged) and prints MAD(spp, 2 spp) over
 * the whole image.
 * Usage: scene_convergence [scene.json] [threads]. Prints one JSON object last. */
#include <stdio.h>
#include <stdlib.h>

#include "bench_common.h"
#include "woven/scene3d.h"

#define LADDER 6

int main(int argc, char **argv) {
  const char *path = argc > 1 ? argv[1] : WOVEN_SOURCE_DIR "/scenes/drape-studio.json";
  int threads = argc > 2 ? atoi(argv[2]) : 2;
  wv_error e = {0};
  wv_scene3d s;
  wv_world *w;
  if (wv_scene3d_read(path, &s, &e) || wv_world_load(&s, NULL, threads, &w, &e)) {
    fprintf(stderr, "scene_convergence: %s\n", e.msg);
    return 1;
  }
  const int ladder[LADDER] = {4, 8, 16, 32, 64, 128};
  wv_image img[LADDER];
  double secs[LADDER];
  for (int k = 0; k < LADDER; k++) {
    wv_scene3d_opts o = {.spp = ladder[k], .threads = threads};
    double t0 = bench_now();
    if (wv_scene3d_render(&s, w, &o, &img[k], NULL, NULL, &e)) {
      fprintf(stderr, "scene_convergence: %s\n", e.msg);
      return 1;
    }
    secs[k] = bench_now() - t0;
    fprintf(stderr, "%d spp: %.1f s\n", ladder[k], secs[k]);
  }
  printf("{\"scene\": \"%s\", \"width\": %d, \"height\": %d, \"yarn_samples\": %d, \"ladder\": [", s.name, s.width,
         s.height, s.yarn_samples);
  for (int k = 0; k + 1 < LADDER; k++) {
    double mad = wv_image_mad(&img[k], &img[k + 1]);
    fprintf(stderr, "spp %3d vs %3d: MAD %.5f%s\n", ladder[k], ladder[k + 1], mad,
            ladder[k] == s.spp ? "  (scene default)" : "");
    printf("%s{\"spp\": %d, \"mad\": %.6f, \"seconds\": %.2f}", k ? ", " : "", ladder[k], mad, secs[k]);
  }
  printf("]}\n");
  for (int k = 0; k < LADDER; k++) wv_image_free(&img[k]);
  wv_world_free(w);
  wv_scene3d_free(&s);
  return 0;
}
