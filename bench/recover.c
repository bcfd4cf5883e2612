/* Recovery study for the fit (issue: woven fit).
 *   recover [--per-pattern N] [--iters N] [--iter-spp N] [--iter-scale N] [--threads N]
 *     Synthetic: N random parameter sets per pattern from the SPEC priors, rendered
 *     in the cylinder scene with one noise seed, fitted from the pattern's prior
 *     mean with another seed. Prints SSIM(target, fit) and normalised errors.
 *   recover --real DIR [--iters N]
 *     Real photos DIR/<pattern><n>_*.png in the flat45 scene: SSIM start and fit. The
 *     orientation (pattern or pattern90) is the one whose prior mean has the lower
 *     fit loss; both losses are printed.
 * SSIM is always measured on full-quality renders at the scene's resolution and spp.
 * Prints one line per fit, then one JSON object on the last line. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_common.h"
#include "woven/descriptor.h"
#include "woven/fit.h"
#include "woven/metrics.h"
#include "woven/photo.h"
#include "woven/render.h"

static const char *PATTERNS[5] = {"plain", "twill", "satin", "twill90", "satin90"};

static void die(const wv_error *e) {
  fprintf(stderr, "recover: %s\n", e->msg);
  exit(1);
}

/* Fit p0 to photo; returns the fitted parameters, the scene they are registered
 * to (s with the registration's offset) and the fit time. */
static double run_fit(const wv_scene *s, const wv_image *photo, wv_descriptor *d, const wv_params *p0,
                      const wv_fit_opts *o, wv_params *out, wv_scene *out_scene, wv_fit_timing *timing) {
  wv_fit_state st;
  wv_error err = {0};
  if (wv_fit_state_init(&st, p0, o, &err)) die(&err);
  double t0 = bench_now();
  if (wv_fit_run(&st, s, photo, d, o, NULL, NULL, &err)) die(&err);
  double t = bench_now() - t0;
  *out = st.params;
  wv_fit_scene(&st, s, out_scene);
  if (timing) *timing = st.timing;
  wv_fit_state_free(&st);
  return t;
}

static double ssim_of(const wv_scene *s, const wv_params *p, const wv_image *ref, int threads) {
  wv_render_opts ro = {0, threads, NULL, NULL, NULL};
  wv_image img;
  wv_error err = {0};
  if (wv_render(s, p, &ro, &img, NULL, &err)) die(&err);
  double v;
  if (wv_ssim(ref, &img, WV_SSIM_LUMA, &v, &err)) die(&err);
  wv_image_free(&img);
  return v;
}

static int synthetic(int per, const wv_fit_opts *o, wv_descriptor *d) {
  wv_scene s;
  wv_error err = {0};
  wv_scene_preset("cylinder", &s, NULL);
  double err_sum[WV_P_COUNT + 3] = {0}, start_err_sum[WV_P_COUNT + 3] = {0};
  double ssim_sum = 0, ssim_start_sum = 0, ssim_oracle_sum = 0, time_sum = 0;
  wv_fit_timing tsum = {0};
  int n = 0;
  for (int k = 0; k < 5; k++)
    for (int i = 0; i < per; i++) {
      wv_params target, start, fit;
      wv_scene fs;
      if (wv_params_sample_prior(PATTERNS[k], 1000u * k + i, &target, &err)) die(&err);
      wv_render_opts ro = {0, o->threads, NULL, NULL, NULL};
      wv_image photo;
      if (wv_render(&s, &target, &ro, &photo, NULL, &err)) die(&err);
      wv_params_default(PATTERNS[k], &start, NULL);
      start.seed = target.seed + 7919; /* another noise seed than the target's */
      wv_fit_timing t;
      time_sum += run_fit(&s, &photo, d, &start, o, &fit, &fs, &t);
      tsum.render += t.render, tsum.gradient += t.gradient, tsum.descriptor += t.descriptor;
      tsum.discrete += t.discrete;
      tsum.registration += t.registration;
      double s0 = ssim_of(&s, &start, &photo, o->threads), s1 = ssim_of(&fs, &fit, &photo, o->threads);
      /* the ceiling: the true parameters rendered with the fit's noise seed */
      wv_params oracle = target;
      oracle.seed = start.seed;
      double so = ssim_of(&s, &oracle, &photo, o->threads);
      ssim_sum += s1, ssim_start_sum += s0, ssim_oracle_sum += so;
      for (int j = 0; j < WV_P_COUNT; j++) {
        double lo, hi;
        wv_param_range(j, &lo, &hi);
        err_sum[j] += fabs(wv_param_get(&fit, j) - wv_param_get(&target, j)) / (hi - lo);
        start_err_sum[j] += fabs(wv_param_get(&start, j) - wv_param_get(&target, j)) / (hi - lo);
      }
      for (int y = 0; y < 2; y++) {
        err_sum[WV_P_COUNT + y] += fabs(fit.density[y] - target.density[y]) / 230.0;
        start_err_sum[WV_P_COUNT + y] += fabs(start.density[y] - target.density[y]) / 230.0;
      }
      err_sum[WV_P_COUNT + 2] += abs(fit.noise_level - target.noise_level) / 10.0;
      start_err_sum[WV_P_COUNT + 2] += abs(start.noise_level - target.noise_level) / 10.0;
      n++;
      printf("%-8s %2d: SSIM start %.4f fit %.4f truth-with-fit-seed %.4f  (%.1f s)\n", PATTERNS[k], i, s0, s1, so,
             t.total);
      fflush(stdout);
      wv_image_free(&photo);
    }
  printf("{\"mode\": \"synthetic\", \"scene\": \"cylinder\", \"fits\": %d, \"iters\": %d, \"iter_spp\": %d, "
         "\"iter_scale\": %d, \"ssim_start_mean\": %.4f, \"ssim_fit_mean\": %.4f, \"ssim_truth_other_seed_mean\": %.4f, "
         "\"fit_s_mean\": %.2f, "
         "\"fit_breakdown_s_mean\": {\"render\": %.2f, \"gradient\": %.2f, \"descriptor\": %.2f, \"discrete\": %.2f, \"registration\": %.2f}, "
         "\"normalised_error_fit\": {",
         n, o->iters, o->iter_spp, o->iter_scale, ssim_start_sum / n, ssim_sum / n, ssim_oracle_sum / n, time_sum / n, tsum.render / n,
         tsum.gradient / n, tsum.descriptor / n, tsum.discrete / n, tsum.registration / n);
  for (int j = 0; j < WV_P_COUNT + 3; j++)
    printf("%s\"%s\": %.4f", j ? ", " : "",
           j < WV_P_COUNT ? wv_param_name(j) : j == WV_P_COUNT ? "density.warp" : j == WV_P_COUNT + 1 ? "density.weft" : "noise_level",
           err_sum[j] / n);
  printf("}, \"normalised_error_start\": {");
  for (int j = 0; j < WV_P_COUNT + 3; j++)
    printf("%s\"%s\": %.4f", j ? ", " : "",
           j < WV_P_COUNT ? wv_param_name(j) : j == WV_P_COUNT ? "density.warp" : j == WV_P_COUNT + 1 ? "density.weft" : "noise_level",
           start_err_sum[j] / n);
  printf("}}\n");
  return 0;
}

static int real(const char *dir, const wv_fit_opts *o, wv_descriptor *d) {
  wv_scene s;
  wv_error err = {0};
  wv_scene_preset("flat45", &s, NULL);
  char names[64][256];
  int n = bench_list_png(dir, names);
  if (n < 0) {
    fprintf(stderr, "recover: cannot open %s\n", dir);
    return 1;
  }
  printf("{\"mode\": \"real\", \"scene\": \"flat45\", \"iters\": %d, \"photos\": [", o->iters);
  char json[8192] = "";
  size_t jl = 0;
  int raised = 0;
  for (int i = 0; i < n; i++) {
    char pattern[32] = "";
    for (int k = 0; k < 32 && names[i][k] && !(names[i][k] >= '0' && names[i][k] <= '9') && names[i][k] != '_'; k++)
      pattern[k] = names[i][k], pattern[k + 1] = 0;
    wv_params start, fit;
    wv_scene fs;
    if (wv_params_default(pattern, &start, &err)) {
      fprintf(stderr, "recover: %s: no pattern in the file name (%s)\n", names[i], err.msg);
      continue;
    }
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, names[i]);
    wv_image photo;
    if (wv_photo_load(path, &s, NULL, &photo, NULL, &err)) die(&err);
    /* The file names the weave, not its orientation ("as seen in the photo"): the
     * pattern or its 90-degree variant, whichever prior mean the fit's own loss
     * prefers (decided before fitting, without SSIM). */
    double loss[2] = {0, 0};
    char rotated[40];
    snprintf(rotated, sizeof rotated, "%s90", pattern);
    wv_params alt;
    if (!wv_params_default(rotated, &alt, NULL)) {
      wv_fit_record rec;
      if (wv_fit_loss(&s, &photo, d, &start, o, &rec, &err)) die(&err);
      loss[0] = rec.loss;
      if (wv_fit_loss(&s, &photo, d, &alt, o, &rec, &err)) die(&err);
      loss[1] = rec.loss;
      if (loss[1] < loss[0]) start = alt, snprintf(pattern, sizeof pattern, "%s", rotated);
    }
    double t = run_fit(&s, &photo, d, &start, o, &fit, &fs, NULL);
    double s0 = ssim_of(&s, &start, &photo, o->threads), s1 = ssim_of(&fs, &fit, &photo, o->threads);
    raised += s1 > s0;
    fprintf(stderr, "%s (%s): SSIM start %.4f fit %.4f (%.1f s)\n", names[i], pattern, s0, s1, t);
    jl += (size_t)snprintf(json + jl, sizeof json - jl,
                           "%s{\"file\": \"%s\", \"pattern\": \"%s\", \"prior_loss\": [%.6f, %.6f], "
                           "\"ssim_start\": %.4f, \"ssim_fit\": %.4f, \"fit_s\": %.1f}",
                           i ? ", " : "", names[i], pattern, loss[0], loss[1], s0, s1, t);
    if (jl >= sizeof json) jl = sizeof json - 1;
    wv_image_free(&photo);
  }
  printf("%s], \"raised\": %d, \"count\": %d}\n", json, raised, n);
  return 0;
}

int main(int argc, char **argv) {
  wv_fit_opts o;
  wv_fit_opts_default(&o);
  int per = 10;
  const char *real_dir = NULL;
  for (int i = 1; i < argc; i++) {
    if (!strcmp(argv[i], "--per-pattern") && i + 1 < argc) per = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--iters") && i + 1 < argc) o.iters = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--iter-spp") && i + 1 < argc) o.iter_spp = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--iter-scale") && i + 1 < argc) o.iter_scale = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--threads") && i + 1 < argc) o.threads = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--real") && i + 1 < argc) real_dir = argv[++i];
    else {
      fprintf(stderr, "usage: recover [--per-pattern N] [--iters N] [--iter-spp N] [--iter-scale N] [--real DIR]\n");
      return 1;
    }
  }
  wv_descriptor *d;
  wv_error err = {0};
  if (wv_descriptor_create_default(&d, &err)) die(&err);
  int rc = real_dir ? real(real_dir, &o, d) : synthetic(per, &o, d);
  wv_descriptor_free(d);
  return rc;
}
