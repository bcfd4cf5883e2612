/* How much of the gaps between yarns a render shows at a given spp. The back-lit rig
 * (flat45-back) adds its gap glow wherever a pixel's samples cross a gap, so the glow a
 * render carries, weighted by the glow's Gaussian (the glow's own least-squares amplitude),
 * is the open area its samples saw. For a plain and a twill drawn from the prior (seeds 7
 * and 8, as tests/test_analysis.c's test_open_area) at 120 / 100 yarns per inch, yarn
 * width 0.85 and 0.75, in the centre 256 x 256 pixels of flat45-back, it renders each spp
 * with and without the glow (the same samples) and prints, per cloth and spp, the open
 * area (1 - width)^2, the open area the glow shows, and wv_open_area_measure's reading of
 * the render with the glow, as one JSON object.
 * Usage: gap_coverage [spp ...] (default 8 16 24 32 48 64 128 256) */
#include <stdio.h>
#include <stdlib.h>

#include "sensor/sensor.h"
#include "woven/analysis.h"
#include "woven/metrics.h"
#include "woven/render.h"

#define SIDE 256

static void die(const wv_error *e) {
  fprintf(stderr, "gap_coverage: %s\n", e->msg);
  exit(1);
}

int main(int argc, char **argv) {
  int def[] = {8, 16, 24, 32, 48, 64, 128, 256}, n = argc > 1 ? argc - 1 : (int)(sizeof def / sizeof def[0]);
  int *spps = malloc(sizeof(int) * (size_t)n);
  if (!spps) return 1;
  for (int i = 0; i < n; i++) {
    spps[i] = argc > 1 ? atoi(argv[i + 1]) : def[i];
    if (spps[i] < 1 || spps[i] > WV_SCENE_MAX_SPP) {
      fprintf(stderr, "usage: gap_coverage [spp 1..%d ...]\n", WV_SCENE_MAX_SPP);
      return 2;
    }
  }
  const char *pats[2] = {"plain", "twill"};
  const double widths[2] = {0.85, 0.75};
  wv_error e = {0};
  printf("{\"cloths\": [");
  for (int k = 0; k < 2; k++)
    for (int w = 0; w < 2; w++) {
      wv_params p;
      if (wv_params_sample_prior(pats[k], 7 + k, &p, &e)) die(&e);
      p.density[WV_WARP] = 120, p.density[WV_WEFT] = 100, p.yarn_width = widths[w];
      double open = (1 - widths[w]) * (1 - widths[w]);
      printf("%s{\"pattern\": \"%s\", \"width\": %.2f, \"open_area\": %.5f, \"spp\": [", k || w ? ", " : "", pats[k],
             widths[w], open);
      for (int i = 0; i < n; i++) {
        wv_scene full, s;
        if (wv_scene_preset("flat45-back", &full, &e)) die(&e);
        wv_scene_centre_window(&full, SIDE, SIDE, &s); /* the same pixels as the full image there */
        s.spp = spps[i];
        wv_scene dark = s;
        dark.glow_radiance = 0;
        wv_render_opts ro = {0};
        wv_image cap, cap0, rad, rad0;
        if (wv_render(&s, &p, &ro, &cap, &rad, &e) || wv_render(&dark, &p, &ro, &cap0, &rad0, &e)) die(&e);
        double num = 0, den = 0;
        for (int y = 0; y < SIDE; y++)
          for (int x = 0; x < SIDE; x++) {
            double g = wv_pixel_gaussian(SIDE, SIDE, x, y, s.glow_sigma), d = 0;
            for (int c = 0; c < 3; c++) d += wv_image_px(&rad, x, y)[c] - wv_image_px(&rad0, x, y)[c];
            num += g * d / 3, den += g * g;
          }
        wv_open_area oa;
        if (wv_open_area_measure(&s, &cap, &oa, &e)) die(&e);
        double shown = num / den / s.glow_radiance;
        printf("%s{\"spp\": %d, \"shown\": %.5f, \"shown_error\": %.4f, \"measured\": %.5f, \"measured_error\": %.4f}",
               i ? ", " : "", spps[i], shown, shown / open - 1, oa.open_area, oa.open_area / open - 1);
        fflush(stdout);
        wv_image_free(&cap), wv_image_free(&cap0), wv_image_free(&rad), wv_image_free(&rad0);
      }
      printf("]}");
    }
  printf("]}\n");
  free(spps);
  return 0;
}
