/* Recovery study of the capture (the network's estimate, the pattern choice over the
 * built-in library, then the fit), on synthetic targets or on real photos.
 *   recover [--scene S] [--model M] [--per-pattern N] [--patterns a,b,...] [--seed S]
 *           [--start network|prior] [--iters N] [--iter-spp N] [--iter-scale N] [--threads N]
 *           [--w-struct X] [--w-colour X] [--lr X] [--[no-]colour-split]
 *           [--camera-blur auto|measured|S] [--no-orient] [--no-refine]
 *           (the fit's options, as woven fit's; --no-orient: candidates and fit on square cloth
 *           without the lattice's rotation and skew; --no-refine: the chosen lattice as the
 *           analysis's centre window measured it, not refined over the whole image)
 *     Synthetic: N prior draws of every canonical built-in (or of the listed patterns; the
 *     earlier names twill, satin, twill90, satin90 are built-ins too); every second draw is
 *     a two-colour cloth (a dark blue warp and a near-white weft, as denim), rendered in the
 *     scene (default flat45) at its spp and quantised to 8 bits. --start network (default):
 *     the capture as `woven capture` runs it without --pattern; --start prior: the fit from
 *     the true pattern's prior mean (the choice is not tested). Per target: the chosen
 *     pattern and whether its family is right, SSIM (per RGB channel, averaged) of start and
 *     fit, the ceiling (the true parameters rendered with the fit's noise seed instead of the
 *     target's), the fit's share of the ceiling, and WSC of the fit and of the ceiling.
 *   recover --real DIR [--model M] [--iters N] ...
 *     Every DIR/<pattern><n>_*.png as a photo in the flat45 scene, captured as `woven
 *     capture` does: the chosen pattern, SSIM (RGB and luminance) and WSC of start and fit,
 *     the baseline SSIM of the photo's own copy blurred with a Gaussian of sigma 4 px, the
 *     WSC of the photo's four 256 x 256 quadrants against each other (the mean of the six
 *     pairs: what the same weave scores), and SSIM and WSC of the fit's render blurred by a
 *     Gaussian of sigma 2 px (the fit with its pixel-scale weave erased: where that scores
 *     the higher SSIM, SSIM rewards losing the weave).
 * SSIM and WSC are measured on full-quality renders at the scene's resolution and spp.
 * Prints one line per target, then one JSON object on the last line. */
#define RECOVER_NAME "recover"
#include "recover_common.h"
#include "woven/imgops.h"
#include "wsc_quadrants.h"

/* WSC (whitened: 1) of the photo's quadrants against each other (bench/wsc_quadrants.h). */
static double wsc_quadrants(const wv_image *img, int whitened) {
  wv_error err = {0};
  double v;
  if (bench_wsc_quadrants(img, whitened, &v, &err)) die(&err);
  return v;
}

static const char *family(const char *pattern) { return wv_weave_family(pattern); }

#define MAXP 32
static int synthetic(const study *st, int per, const char **pats, int np, uint64_t seed, int prior_start) {
  wv_error err = {0};
  const wv_scene *s = st->s;
  double sum_fit = 0, sum_start = 0, sum_ceil = 0, sum_ratio = 0, sum_wsc = 0, sum_wsc_ceil = 0, sum_t = 0;
  double sum_wscw = 0, sum_wscw_ceil = 0;
  double pat_fit[MAXP] = {0}, pat_ceil[MAXP] = {0}, pat_wsc[MAXP] = {0};
  int pat_fam[MAXP] = {0}, fam_right = 0, lat_right = 0, n = 0, two = 0;
  double two_fit = 0, two_ceil = 0;
  for (int k = 0; k < np; k++)
    for (int i = 0; i < per; i++) {
      wv_params target, prior;
      uint64_t ts = wv_hash4(seed, (uint64_t)k, (uint64_t)i, 1);
      if (wv_params_sample_prior(pats[k], ts, &target, &err)) die(&err);
      int denim = i % 2 == 1;
      if (denim) two_colour(&target, ts);
      wv_render_opts ro = {.threads = st->o.threads};
      wv_image photo;
      if (wv_render(s, &target, &ro, &photo, NULL, &err)) die(&err);
      wv_image_quantise8(&photo);
      capture c;
      if (prior_start && wv_params_default(pats[k], &prior, &err)) die(&err);
      run_capture(st, &photo, prior_start ? &prior : NULL, &c);
      double s0, s1, sc, w0[2], w1[2], wc[2];
      measure(s, &c.start, &photo, st->o.threads, &s0, NULL, w0, 0, NULL);
      measure(&c.fit_scene, &c.fit, &photo, st->o.threads, &s1, NULL, w1, 0, NULL);
      /* the ceiling: the truth with the fit's noise seed */
      wv_params oracle = target;
      oracle.seed = c.fit.seed;
      measure(s, &oracle, &photo, st->o.threads, &sc, NULL, wc, 0, NULL);
      int fam_ok = !strcmp(family(c.chosen), family(pats[k]));
      int lat_ok = !prior_start && !strcmp(family(c.lattice_choice), family(pats[k]));
      fam_right += fam_ok, pat_fam[k] += fam_ok, lat_right += lat_ok;
      sum_fit += s1, sum_start += s0, sum_ceil += sc, sum_ratio += s1 / sc, sum_wsc += w1[0], sum_wsc_ceil += wc[0];
      sum_wscw += w1[1], sum_wscw_ceil += wc[1];
      sum_t += c.seconds;
      pat_fit[k] += s1, pat_ceil[k] += sc, pat_wsc[k] += w1[0];
      if (denim) two++, two_fit += s1, two_ceil += sc;
      n++;
      printf("%-12s %d%s -> %-12s %-5s (lattice alone %-12s %-5s) SSIM start %.4f fit %.4f ceiling %.4f (%.3f)  WSC fit %.3f ceiling %.3f  whitened %.3f / %.3f  "
             "density %.1f/%.1f (truth %.0f/%.0f)  %.1f s\n",
             pats[k], i, denim ? " two-colour" : "", c.chosen, fam_ok ? "ok" : "WRONG", c.lattice_choice,
             lat_ok ? "ok" : "WRONG", s0, s1, sc, s1 / sc, w1[0], wc[0], w1[1], wc[1],
             c.fit.density[0], c.fit.density[1], target.density[0], target.density[1], c.seconds);
      fflush(stdout);
      wv_image_free(&photo);
    }
  printf("{\"mode\": \"synthetic\", \"scene\": \"%s\", \"start\": \"%s\", \"targets\": %d, \"per_pattern\": %d, "
         "\"iters\": %d, \"iter_spp\": %d, \"iter_scale\": %d, \"ssim\": \"rgb\", \"ssim_start_mean\": %.4f, "
         "\"ssim_fit_mean\": %.4f, \"ssim_ceiling_mean\": %.4f, \"fit_over_ceiling\": %.4f, "
         "\"mean_fit_over_ceiling\": %.4f, \"two_colour_fit_over_ceiling\": %.4f, \"wsc_fit_mean\": %.4f, "
         "\"wsc_ceiling_mean\": %.4f, \"wsc_whitened_fit_mean\": %.4f, \"wsc_whitened_ceiling_mean\": %.4f, "
         "\"family_right\": %.4f, \"family_right_lattice_alone\": %.4f, \"capture_s_mean\": %.1f, "
         "\"per_pattern_results\": {",
         s->name, prior_start ? "prior" : "network", n, per, st->o.iters, st->o.iter_spp, st->o.iter_scale,
         sum_start / n, sum_fit / n, sum_ceil / n, sum_fit / sum_ceil, sum_ratio / n, two ? two_fit / two_ceil : 0.0,
         sum_wsc / n, sum_wsc_ceil / n, sum_wscw / n, sum_wscw_ceil / n, (double)fam_right / n, (double)lat_right / n, sum_t / n);
  for (int k = 0; k < np; k++)
    printf("%s\"%s\": {\"ssim_fit\": %.4f, \"ceiling\": %.4f, \"wsc_fit\": %.4f, \"family_right\": %d}", k ? ", " : "",
           pats[k], pat_fit[k] / per, pat_ceil[k] / per, pat_wsc[k] / per, pat_fam[k]);
  printf("}}\n");
  return 0;
}

static int real(const study *st, const char *dir) {
  char names[64][256];
  int n = bench_list_png(dir, names);
  if (n < 0) {
    fprintf(stderr, "recover: cannot open %s\n", dir);
    return 1;
  }
  char json[16384] = "";
  size_t jl = 0;
  double sum[7] = {0};
  int fam_right = 0, counted = 0;
  for (int i = 0; i < n; i++) {
    char named[32] = ""; /* the weave the file name gives: its family is the truth */
    for (int k = 0; k < 31 && names[i][k] && !(names[i][k] >= '0' && names[i][k] <= '9') && names[i][k] != '_'; k++)
      named[k] = names[i][k], named[k + 1] = 0;
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, names[i]);
    wv_image photo;
    wv_error err = {0};
    if (wv_photo_load(path, st->s, NULL, &photo, NULL, &err)) die(&err);
    double base; /* the baseline woven capture reports as ssim_rgb_blurred_photo */
    if (wv_blurred_copy_ssim(&photo, WV_BLURRED_COPY_SIGMA, &base, &err)) die(&err);
    capture c;
    run_capture(st, &photo, NULL, &c);
    double s0, s1, l0, l1, w0[2], w1[2], bl[2], quads = wsc_quadrants(&photo, 0), quadsw = wsc_quadrants(&photo, 1);
    measure(st->s, &c.start, &photo, st->o.threads, &s0, &l0, w0, 0, NULL);
    measure(&c.fit_scene, &c.fit, &photo, st->o.threads, &s1, &l1, w1, 2.0, bl);
    int known = wv_weave_is_builtin(named), ok = known && !strcmp(family(named), family(c.chosen));
    fam_right += ok, counted += known;
    sum[0] += base, sum[1] += s0, sum[2] += s1, sum[3] += w0[0], sum[4] += w1[0], sum[5] += w0[1], sum[6] += w1[1];
    printf("%-14s -> %-12s (%s, family %s; lattice alone %s)  blurred copy SSIM %.4f, quadrants WSC %.3f "
           "(whitened %.3f) | SSIM start %.4f fit %.4f (luminance %.4f -> %.4f) | WSC start %.3f fit %.3f | "
           "whitened WSC start %.3f fit %.3f | fit blurred 2 px: SSIM %.4f WSC %.3f | %.1f s\n",
           names[i], c.chosen, c.method, !known ? "?" : ok ? "right" : "WRONG", c.lattice_choice, base, quads, quadsw,
           s0, s1, l0, l1, w0[0], w1[0], w0[1], w1[1], bl[0], bl[1], c.seconds);
    fflush(stdout);
    jl += (size_t)snprintf(json + jl, sizeof json - jl,
                           "%s{\"file\": \"%s\", \"chosen\": \"%s\", \"family_right\": %s, \"method\": \"%s\", "
                           "\"lattice_alone\": \"%s\", \"blurred_copy_ssim\": %.4f, \"wsc_quadrants\": %.4f, "
                           "\"wsc_whitened_quadrants\": %.4f, \"ssim_start\": %.4f, \"ssim_fit\": %.4f, "
                           "\"fit_blurred_2px\": {\"ssim\": %.4f, \"wsc\": %.4f}, \"ssim_luma_start\": %.4f, "
                           "\"ssim_luma_fit\": %.4f, \"wsc_start\": %.4f, \"wsc_fit\": %.4f, \"wsc_whitened_start\": %.4f, "
                           "\"wsc_whitened_fit\": %.4f, \"density\": [%.1f, %.1f], \"capture_s\": %.1f, \"choice_s\": %.1f}",
                           i ? ", " : "", names[i], c.chosen, !known ? "null" : ok ? "true" : "false", c.method,
                           c.lattice_choice, base, quads, quadsw, s0, s1, bl[0], bl[1], l0, l1, w0[0], w1[0], w0[1], w1[1],
                           c.fit.density[0], c.fit.density[1], c.seconds, c.choice_seconds);
    if (jl >= sizeof json) jl = sizeof json - 1;
    wv_image_free(&photo);
  }
  printf("{\"mode\": \"real\", \"scene\": \"%s\", \"iters\": %d, \"ssim\": \"rgb\", \"photos\": [%s], "
         "\"blurred_copy_ssim_mean\": %.4f, \"ssim_start_mean\": %.4f, \"ssim_fit_mean\": %.4f, \"wsc_start_mean\": %.4f, "
         "\"wsc_fit_mean\": %.4f, \"wsc_whitened_start_mean\": %.4f, \"wsc_whitened_fit_mean\": %.4f, "
         "\"family_right\": %d, \"count\": %d}\n",
         st->s->name, st->o.iters, json, sum[0] / n, sum[1] / n, sum[2] / n, sum[3] / n, sum[4] / n, sum[5] / n,
         sum[6] / n, fam_right, counted);
  return 0;
}

int main(int argc, char **argv) {
  study st;
  wv_fit_opts_default(&st.o);
  st.orient = 1, st.refine = 1;
  int per = 4, prior_start = 0;
  uint64_t seed = 1;
  const char *real_dir = NULL, *scene_name = "flat45", *model = NULL, *patlist = NULL;
  for (int i = 1; i < argc; i++) {
    if (!strcmp(argv[i], "--per-pattern") && i + 1 < argc) per = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--iters") && i + 1 < argc) st.o.iters = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--iter-spp") && i + 1 < argc) st.o.iter_spp = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--iter-scale") && i + 1 < argc) st.o.iter_scale = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--threads") && i + 1 < argc) st.o.threads = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--w-struct") && i + 1 < argc) st.o.w_struct = atof(argv[++i]);
    else if (!strcmp(argv[i], "--w-colour") && i + 1 < argc) st.o.w_colour = atof(argv[++i]);
    else if (!strcmp(argv[i], "--lr") && i + 1 < argc) st.o.lr = atof(argv[++i]);
    else if (!strcmp(argv[i], "--camera-blur") && i + 1 < argc) {
      const char *v = argv[++i]; /* auto, measured (not fitted) or a sigma */
      st.o.psf_fit = strcmp(v, "measured") != 0;
      st.o.psf_sigma = !strcmp(v, "auto") || !strcmp(v, "measured") ? WV_FIT_PSF_AUTO : atof(v);
    }
    else if (!strcmp(argv[i], "--no-colour-split")) st.o.colour_split = 0;
    else if (!strcmp(argv[i], "--colour-split")) st.o.colour_split = 1;
    else if (!strcmp(argv[i], "--no-orient")) st.orient = 0;
    else if (!strcmp(argv[i], "--no-refine")) st.refine = 0;
    else if (!strcmp(argv[i], "--seed") && i + 1 < argc) seed = strtoull(argv[++i], NULL, 10);
    else if (!strcmp(argv[i], "--scene") && i + 1 < argc) scene_name = argv[++i];
    else if (!strcmp(argv[i], "--model") && i + 1 < argc) model = argv[++i];
    else if (!strcmp(argv[i], "--patterns") && i + 1 < argc) patlist = argv[++i];
    else if (!strcmp(argv[i], "--start") && i + 1 < argc) {
      const char *v = argv[++i];
      if (strcmp(v, "network") && strcmp(v, "prior")) {
        fprintf(stderr, "recover: --start is network or prior\n");
        return 1;
      }
      prior_start = !strcmp(v, "prior");
    } else if (!strcmp(argv[i], "--real") && i + 1 < argc) real_dir = argv[++i];
    else {
      fprintf(stderr, "usage: recover [--scene S] [--model M] [--per-pattern N] [--patterns a,b] [--seed S]\n"
                      "               [--start network|prior] [--iters N] [--iter-spp N] [--iter-scale N] [--threads N]\n"
                      "               [--w-struct X] [--w-colour X] [--lr X] [--[no-]colour-split]\n"
                      "               [--camera-blur auto|measured|S] [--no-orient] [--no-refine]\n"
                      "       recover --real DIR [--model M] [--iters N] ...\n");
      return 1;
    }
  }
  if (per < 1 || st.o.iters < 0) {
    fprintf(stderr, "recover: --per-pattern must be at least 1 and --iters not negative\n");
    return 1;
  }
  wv_error err = {0};
  if (wv_fit_opts_validate(&st.o, &err)) die(&err);
  wv_scene s;
  if (wv_scene_load(real_dir ? "flat45" : scene_name, &s, &err)) die(&err);
  st.s = &s;
  if (wv_descriptor_create_default(&st.d, &err)) die(&err);
  wv_fabricnet net;
  st.net = NULL;
  if (!prior_start || real_dir) {
    char mpath[4096];
    if (model) snprintf(mpath, sizeof mpath, "%s", model);
    else snprintf(mpath, sizeof mpath, "%s/models/fabricnet-%s.bin", WOVEN_SOURCE_DIR, s.name);
    if (wv_fabricnet_load(mpath, &net, &err) ||
        wv_fabricnet_check(&net, mpath, wv_descriptor_name(st.d), wv_descriptor_size(st.d), &s, &err))
      die(&err);
    st.net = &net;
  }
  int rc;
  if (real_dir) {
    rc = real(&st, real_dir);
  } else {
    const char *pats[MAXP];
    char buf[1024];
    int np = 0;
    if (patlist) {
      snprintf(buf, sizeof buf, "%s", patlist);
      for (char *t = strtok(buf, ","); t && np < MAXP; t = strtok(NULL, ",")) {
        if (!wv_weave_is_builtin(t)) {
          fprintf(stderr, "recover: '%s' is not a built-in pattern\n", t);
          return 1;
        }
        pats[np++] = t;
      }
    } else {
      for (int i = 0; i < wv_weave_builtin_count(); i++) pats[np++] = wv_weave_builtin_name(i);
    }
    rc = synthetic(&st, per, pats, np, seed, prior_start);
  }
  if (st.net) wv_fabricnet_free(st.net);
  wv_descriptor_free(st.d);
  return rc;
}
