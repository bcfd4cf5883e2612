/* How fast renders converge with spp: SPEC section 6 asks that the default spp be
 * high enough that doubling it changes the image by less than 1% (mean absolute
 * difference). For prior draws of every pattern (SPEC section 5), renders each
 * preset scene at spp and 2 spp and prints MAD(spp, 2 spp), mean and worst over the
 * draws, for a ladder of spp: over the whole image and over its centre 200 x 100
 * window (all fabric, the stricter figure). 2 render threads.
 * Usage: spp_convergence [draws per pattern, default 2] [scene, default both]
 * Prints one JSON object on the last line. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_common.h"
#include "woven/dataset.h"
#include "woven/metrics.h"
#include "woven/render.h"

#define LADDER 5

int main(int argc, char **argv) {
  int per = argc > 1 ? atoi(argv[1]) : 2;
  const char *only = argc > 2 ? argv[2] : NULL;
  if (per < 1) {
    fprintf(stderr, "usage: spp_convergence [draws per pattern >= 1] [cylinder|flat45]\n");
    return 2;
  }
  const char *scenes[] = {"cylinder", "flat45"};
  const int ladder[LADDER] = {16, 32, 64, 128, 256};
  printf("{\"draws\": %d, \"scenes\": {", per * WV_NET_PATTERNS);
  int first_scene = 1;
  for (int si = 0; si < 2; si++) {
    if (only && strcmp(only, scenes[si])) continue;
    wv_scene s;
    wv_error e;
    if (wv_scene_preset(scenes[si], &s, &e)) return 1;
    double sum[LADDER] = {0}, worst[LADDER] = {0}, csum[LADDER] = {0}, cworst[LADDER] = {0};
    int n = 0;
    for (int pi = 0; pi < WV_NET_PATTERNS; pi++)
      for (int d = 0; d < per; d++, n++) {
        wv_params p;
        if (wv_params_sample_prior(wv_net_pattern(pi), (uint64_t)(5000 + 17 * d + pi), &p, &e)) {
          fprintf(stderr, "%s\n", e.msg);
          return 1;
        }
        wv_image prev = {0};
        for (int k = 0; k <= LADDER; k++) {
          int spp = k < LADDER ? ladder[k] : 2 * ladder[LADDER - 1];
          wv_render_opts ro = {.spp = spp, .threads = 2};
          wv_image img = {0};
          if (wv_render(&s, &p, &ro, &img, NULL, &e)) {
            fprintf(stderr, "%s\n", e.msg);
            return 1;
          }
          if (k > 0) {
            double mad = wv_image_mad(&prev, &img);
            sum[k - 1] += mad;
            if (mad > worst[k - 1]) worst[k - 1] = mad;
            wv_image ca = {0}, cb = {0};
            if (wv_image_centre_crop(&prev, 200, 100, &ca, &e) || wv_image_centre_crop(&img, 200, 100, &cb, &e)) {
              fprintf(stderr, "%s\n", e.msg);
              return 1;
            }
            mad = wv_image_mad(&ca, &cb);
            csum[k - 1] += mad;
            if (mad > cworst[k - 1]) cworst[k - 1] = mad;
            wv_image_free(&ca), wv_image_free(&cb);
          }
          wv_image_free(&prev);
          prev = img;
        }
        wv_image_free(&prev);
        fprintf(stderr, "%s %s draw %d done\n", scenes[si], wv_net_pattern(pi), d);
      }
    printf("%s\"%s\": [", first_scene ? "" : ", ", scenes[si]);
    first_scene = 0;
    for (int k = 0; k < LADDER; k++) {
      fprintf(stderr, "%-8s spp %4d vs %4d: MAD image mean %.5f worst %.5f; centre mean %.5f worst %.5f%s\n",
              scenes[si], ladder[k], 2 * ladder[k], sum[k] / n, worst[k], csum[k] / n, cworst[k],
              ladder[k] == s.spp ? "  (scene default)" : "");
      printf("%s{\"spp\": %d, \"mad_mean\": %.6f, \"mad_worst\": %.6f, \"centre_mad_mean\": %.6f, "
             "\"centre_mad_worst\": %.6f}",
             k ? ", " : "", ladder[k], sum[k] / n, worst[k], csum[k] / n, cworst[k]);
    }
    printf("]");
  }
  printf("}}\n");
  return 0;
}
