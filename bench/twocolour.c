/* Two-colour twills (denim: blue warp, near-white weft): does the fit keep the warp and
 * weft colours apart?
 *   twocolour [--n N] [--iters N] [--scene flat45|cylinder] [--side S] [--w-struct X]
 *             [--w-colour X] [--[no-]split] [--full] [--threads N]
 *   N targets (default 4): a built-in twill (cycling through the S and Z twills), the
 *   rest of the parameters from its prior, then a blue warp and a near-white weft with a
 *   little jitter. Rendered in the scene's centre S x S window (default 256; 0 = the
 *   whole image) with one noise seed and fitted from the pattern's prior mean with
 *   another, given the true densities (the colours are the question here, so the density
 *   alignment, the registration and the discrete steps are off; --full turns them on and
 *   starts from the prior's densities). Prints per target: SSIM (RGB) of the fit and the ceiling (the true
 *   parameters rendered with the fit's noise seed), the fit's warp and weft diffuse
 *   colours against the truth, and the colour separation |kd_warp - kd_weft|.
 * Prints one line per fit, then one JSON object on the last line. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_common.h"
#include "woven/descriptor.h"
#include "woven/fit.h"
#include "woven/metrics.h"
#include "woven/nn.h"
#include "woven/render.h"

static const char *TWILLS[4] = {"twill21z", "twill31s", "twill22z", "twill21s_90"};

static void die(const wv_error *e) {
  fprintf(stderr, "twocolour: %s\n", e->msg);
  exit(1);
}

static double ssim_of(const wv_scene *s, const wv_params *p, const wv_image *ref, int threads) {
  wv_render_opts ro = {.threads = threads};
  wv_image img;
  wv_error err = {0};
  if (wv_render(s, p, &ro, &img, NULL, &err)) die(&err);
  double v;
  if (wv_ssim(ref, &img, WV_SSIM_RGB, &v, &err)) die(&err);
  wv_image_free(&img);
  return v;
}

static double dist3(const double *a, const double *b) {
  return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

int main(int argc, char **argv) {
  int n = 4, side = 256, full = 0;
  const char *scene = "flat45";
  wv_fit_opts o;
  wv_fit_opts_default(&o);
  for (int i = 1; i < argc; i++) {
    if (!strcmp(argv[i], "--n") && i + 1 < argc) n = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--iters") && i + 1 < argc) o.iters = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--scene") && i + 1 < argc) scene = argv[++i];
    else if (!strcmp(argv[i], "--side") && i + 1 < argc) side = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--w-struct") && i + 1 < argc) o.w_struct = atof(argv[++i]);
    else if (!strcmp(argv[i], "--w-colour") && i + 1 < argc) o.w_colour = atof(argv[++i]);
    else if (!strcmp(argv[i], "--no-split")) o.colour_split = 0;
    else if (!strcmp(argv[i], "--split")) o.colour_split = 1;
    else if (!strcmp(argv[i], "--full")) full = 1;
    else if (!strcmp(argv[i], "--threads") && i + 1 < argc) o.threads = atoi(argv[++i]);
    else {
      fprintf(stderr, "usage: twocolour [--n N] [--iters N] [--scene flat45|cylinder] [--side S] [--w-struct X] "
                      "[--w-colour X] [--[no-]split] [--full] [--threads N]\n");
      return 2;
    }
  }
  if (n < 1 || o.iters < 0) return 2;
  if (!full) o.align_radius = 0, o.register_radius = 0, o.discrete_every = 0; /* densities stay exact */
  wv_error err = {0};
  wv_scene s;
  if (wv_scene_preset(scene, &s, &err)) die(&err);
  if (side > 0) {
    wv_scene full = s;
    wv_scene_centre_window(&full, side < full.width ? side : full.width, side < full.height ? side : full.height, &s);
  }
  wv_descriptor *d;
  if (wv_descriptor_create_default(&d, &err)) die(&err);
  double sf = 0, sc = 0, ecol = 0, sep_fit = 0, sep_true = 0, secs = 0;
  for (int k = 0; k < n; k++) {
    const char *pat = TWILLS[k % 4];
    wv_params target, start;
    if (wv_params_sample_prior(pat, 4000u + k, &target, &err)) die(&err);
    wv_rng r;
    wv_rng_seed(&r, 77 + k);
    const double blue[3] = {0.04, 0.08, 0.30}, white[3] = {0.80, 0.80, 0.74};
    for (int c = 0; c < 3; c++) {
      target.diffuse[WV_WARP][c] = blue[c] * (0.8 + 0.4 * wv_rng_uniform(&r));
      target.diffuse[WV_WEFT][c] = white[c] * (0.9 + 0.2 * wv_rng_uniform(&r));
      target.specular[WV_WARP][c] = pow(target.diffuse[WV_WARP][c], 0.5);
      target.specular[WV_WEFT][c] = pow(target.diffuse[WV_WEFT][c], 0.5);
    }
    if (wv_params_validate(&target, &err)) die(&err);
    wv_render_opts ro = {.threads = o.threads};
    wv_image photo;
    if (wv_render(&s, &target, &ro, &photo, NULL, &err)) die(&err);
    wv_params_default(pat, &start, NULL);
    start.seed = target.seed + 7919; /* another noise seed than the target's */
    if (!full) start.density[0] = target.density[0], start.density[1] = target.density[1];
    wv_fit_state st;
    if (wv_fit_state_init(&st, &start, &o, &err)) die(&err);
    double t0 = bench_now();
    if (wv_fit_run(&st, &s, &photo, d, &o, NULL, NULL, &err)) die(&err);
    double t = bench_now() - t0;
    wv_scene fs;
    wv_fit_scene(&st, &s, &fs);
    wv_params oracle = target;
    oracle.seed = start.seed;
    double s1 = ssim_of(&fs, &st.params, &photo, o.threads), so = ssim_of(&s, &oracle, &photo, o.threads);
    double e = 0.5 * (dist3(st.params.diffuse[0], target.diffuse[0]) + dist3(st.params.diffuse[1], target.diffuse[1]));
    double spf = dist3(st.params.diffuse[0], st.params.diffuse[1]), spt = dist3(target.diffuse[0], target.diffuse[1]);
    printf("%-12s %d: SSIM fit %.4f ceiling %.4f (%.3f)  kd warp %.2f %.2f %.2f (true %.2f %.2f %.2f)  weft %.2f %.2f "
           "%.2f (true %.2f %.2f %.2f)  separation %.3f of %.3f  (%.0f s)\n",
           pat, k, s1, so, s1 / so, st.params.diffuse[0][0], st.params.diffuse[0][1], st.params.diffuse[0][2],
           target.diffuse[0][0], target.diffuse[0][1], target.diffuse[0][2], st.params.diffuse[1][0],
           st.params.diffuse[1][1], st.params.diffuse[1][2], target.diffuse[1][0], target.diffuse[1][1],
           target.diffuse[1][2], spf, spt, t);
    fflush(stdout);
    sf += s1, sc += so, ecol += e, sep_fit += spf, sep_true += spt, secs += t;
    wv_fit_state_free(&st);
    wv_image_free(&photo);
  }
  printf("{\"targets\": %d, \"scene\": \"%s\", \"side\": %d, \"full\": %d, \"iters\": %d, \"w_struct\": %g, \"colour_split\": %d, "
         "\"ssim_fit_mean\": %.4f, \"ssim_ceiling_mean\": %.4f, \"fit_over_ceiling\": %.4f, \"diffuse_error_mean\": %.4f, "
         "\"separation_fit_mean\": %.4f, \"separation_true_mean\": %.4f, \"fit_s_mean\": %.1f}\n",
         n, scene, side, full, o.iters, o.w_struct, o.colour_split, sf / n, sc / n, sf / sc, ecol / n, sep_fit / n,
         sep_true / n, secs / n);
  wv_descriptor_free(d);
  return 0;
}
