/* Recovery study of the photo-pair capture on synthetic targets with known parameters.
 *   recover_pair [--per-family N] [--first I] [--family NAME] [--seed S] [--iters N]
 *                [--threads N] [--model M] [--pair-model M|none] [--save DIR]
 * Targets: for each family (plain, basket, twill, satin; --family: that one) draws I ..
 * I+N-1 (default 0 .. 1). Draw i of a family takes its built-in 3 i mod n (n built-ins in
 * wv_weave_builtin_name order), a prior draw of it (wv_params_sample_prior, transmission
 * colours included) and open gaps: a yarn width drawn uniformly in 0.7 .. 1 (open area
 * (1 - width)^2, 0 .. 9%; the prior has no gaps). Rendered in flat45 (front-lit) and
 * flat45-back (back-lit) and quantised to 8 bits, as a photo pair.
 * Each pair is captured as `woven capture R --transmission T --scene flat45` captures it: the
 * one-photo network's estimate and pattern choice on R, the transmission colours from the
 * pair model (default models/fabricnet-flat45+flat45-back.bin when it exists; none: the
 * prior's) when they score the lower pair loss (wv_capture_pair_start), the back-lit scene with the choice's lattice orientation, the joint fit.
 * Measured per target: the open area and the transmission colours against the truth (the
 * colour error of a yarn type is |fit - truth| / |truth| over its RGB vector, for k_t and k_st; the larger of
 * the two types is reported), the transmitted colour (the mean linear radiance of the back-lit
 * re-render against the ceiling's, RGB, as above: the colour the back-lit photo shows, which
 * it determines where it does not tell k_t and k_st apart), and for each photo the SSIM (per RGB channel) of the re-render
 * against the target over the ceiling, the truth rendered with the fit's noise seed; and the
 * same for the back-lit ceiling with the fit's transmission colours in place of the truth's
 * (ratio_t_fit_colours: near 1 where the photo does not tell the two sets of colours apart) and,
 * for scale, with the truth's k_t 10% brighter (ratio_t_kt_10pct). Prints
 * a line per target, then one JSON object on the last line: per target, per family, overall.
 * --save DIR (an existing directory) writes each pair and its re-renders as PNGs, and the true
 * and fitted parameters (<family>_<draw>_truth.json, _fit.json). */
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "bench_common.h"
#include "util/hash.h"
#include "woven/capture.h"
#include "woven/estimate.h"
#include "woven/fit.h"
#include "woven/imgops.h"
#include "woven/io.h"
#include "woven/metrics.h"
#include "woven/pattern.h"
#include "woven/render.h"
#include "woven/weave.h"

static void die(const wv_error *e) {
  fprintf(stderr, "recover_pair: %s\n", e->msg);
  exit(1);
}

#define NFAM 4
static const char *const FAMILIES[NFAM] = {"plain", "basket", "twill", "satin"};
#define WIDTH_LO 0.7 /* the targets' yarn width, uniform in WIDTH_LO .. 1 */

static double open_area(const wv_params *p) { return (1 - p->yarn_width) * (1 - p->yarn_width); }

/* The larger relative error of the two yarn types' transmission colours: from parameter id
 * first (WV_P_KT_WARP_R: k_t; WV_P_KST_WARP_R: k_st), six in a row. */
static double kt_error(const wv_params *fit, const wv_params *truth, int first) {
  double worst = 0;
  for (int y = 0; y < 2; y++) {
    double d = 0, n = 0;
    for (int c = 0; c < 3; c++) {
      double f = wv_param_get(fit, first + 3 * y + c), t = wv_param_get(truth, first + 3 * y + c);
      d += (f - t) * (f - t), n += t * t;
    }
    double e = n > 0 ? sqrt(d / n) : sqrt(d);
    worst = e > worst ? e : worst;
  }
  return worst;
}

/* A render at the scene's spp; photo: quantised to 8 bits as a photo arrives; mean (may be
 * NULL): the mean linear radiance of each channel, before the camera's response. */
static void render(const wv_scene *s, const wv_params *p, int threads, int photo, wv_image *out, double mean[3]) {
  wv_render_opts ro = {.threads = threads};
  wv_error err = {0};
  wv_image rad = {0}, one = {0};
  if (wv_render(s, p, &ro, out, mean ? &rad : NULL, &err)) die(&err);
  if (photo) wv_image_quantise8(out);
  if (!mean) return;
  if (wv_image_downsample(&rad, 1, 1, &one, &err)) die(&err); /* the area average: each channel's mean */
  for (int c = 0; c < 3; c++) mean[c] = one.data[c];
  wv_image_free(&rad), wv_image_free(&one);
}

/* |fit - truth| / |truth| of two RGB vectors. */
static double colour_error(const double fit[3], const double truth[3]) {
  double d = 0, n = 0;
  for (int c = 0; c < 3; c++) d += (fit[c] - truth[c]) * (fit[c] - truth[c]), n += truth[c] * truth[c];
  return n > 0 ? sqrt(d / n) : sqrt(d);
}

static double ssim_of(const wv_image *a, const wv_image *b) {
  double v;
  wv_error err = {0};
  if (wv_ssim(a, b, WV_SSIM_RGB, &v, &err)) die(&err);
  return v;
}

int main(int argc, char **argv) {
  int per = 2, first = 0, threads = 0, iters = -1;
  uint64_t seed = 1;
  const char *family = NULL, *model = NULL, *pair_model = NULL, *save = NULL;
  for (int i = 1; i < argc; i++) {
    if (!strcmp(argv[i], "--per-family") && i + 1 < argc) per = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--first") && i + 1 < argc) first = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--family") && i + 1 < argc) family = argv[++i];
    else if (!strcmp(argv[i], "--seed") && i + 1 < argc) seed = strtoull(argv[++i], NULL, 10);
    else if (!strcmp(argv[i], "--iters") && i + 1 < argc) iters = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--threads") && i + 1 < argc) threads = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--model") && i + 1 < argc) model = argv[++i];
    else if (!strcmp(argv[i], "--pair-model") && i + 1 < argc) pair_model = argv[++i];
    else if (!strcmp(argv[i], "--save") && i + 1 < argc) save = argv[++i];
    else {
      fprintf(stderr, "usage: recover_pair [--per-family N] [--first I] [--family NAME] [--seed S] [--iters N]\n"
                      "                    [--threads N] [--model M] [--pair-model M|none] [--save DIR]\n");
      return 2;
    }
  }
  wv_error err = {0};
  wv_scene s, st;
  if (wv_scene_preset("flat45", &s, &err) || wv_scene_preset("flat45-back", &st, &err)) die(&err);
  char mpath[4096], ppath[4096];
  if (model)
    snprintf(mpath, sizeof mpath, "%s", model);
  else
    snprintf(mpath, sizeof mpath, "%s/models/fabricnet-flat45.bin", WOVEN_SOURCE_DIR);
  if (pair_model)
    snprintf(ppath, sizeof ppath, "%s", pair_model);
  else
    snprintf(ppath, sizeof ppath, "%s/models/fabricnet-flat45+flat45-back.bin", WOVEN_SOURCE_DIR);
  struct stat sb;
  int use_pair = strcmp(ppath, "none") && (pair_model || stat(ppath, &sb) == 0);
  int found = 0;
  char given[4096];
  snprintf(given, sizeof given, "%s", ppath);
  if (use_pair && wv_estimate_pair_model(&s, &st, given, ppath, sizeof ppath, &found, &err)) die(&err);
  wv_fabricnet net;
  wv_descriptor *d;
  if (wv_fabricnet_load(mpath, &net, &err) || wv_descriptor_create_default(&d, &err) ||
      wv_fabricnet_check(&net, mpath, wv_descriptor_name(d), wv_descriptor_size(d), &s, &err))
    die(&err);
  wv_fit_opts fo;
  wv_fit_opts_default(&fo);
  fo.threads = threads;
  if (iters > 0) fo.iters = iters;
  json_t *targets = json_array();
  double fam_sum[NFAM][6] = {{0}}; /* ratio R, ratio T, open-area error, k_t error, k_st error, transmitted colour error */
  int fam_n[NFAM] = {0}, fam_ok[NFAM] = {0};
  double t_all = bench_now();
  for (int f = 0; f < NFAM; f++) {
    if (family && strcmp(family, FAMILIES[f])) continue;
    int members[WV_NET_CLASSES], nm = 0;
    for (int b = 0; b < wv_weave_builtin_count(); b++)
      if (!strcmp(wv_weave_family(wv_weave_builtin_name(b)), FAMILIES[f])) members[nm++] = b;
    for (int i = first; i < first + per; i++) {
      const char *pattern = wv_weave_builtin_name(members[(3 * i) % nm]);
      wv_params truth, ceil_p;
      if (wv_params_sample_prior(pattern, wv_hash4(seed, (uint64_t)f, (uint64_t)i, 0x70616972ULL), &truth, &err))
        die(&err);
      truth.yarn_width = WIDTH_LO + (1 - WIDTH_LO) * wv_u01d(wv_hash4(seed, (uint64_t)f, (uint64_t)i, 0x77696474ULL));
      wv_image photo, photo_t, ceil_r, ceil_t;
      render(&s, &truth, threads, 1, &photo, NULL);
      render(&st, &truth, threads, 1, &photo_t, NULL);
      /* the capture: the network and the pattern choice on the reflection photo */
      double t0 = bench_now();
      wv_pattern_choice *pc = malloc(sizeof *pc);
      float y[WV_NET_OUT_MAX];
      wv_pattern_opts po;
      wv_pattern_opts_default(&po);
      po.threads = threads;
      if (!pc || wv_fabricnet_predict_pattern(&net, d, &s, &photo, &po, y, pc, &err)) die(&err);
      wv_estimate e = {0};
      e.params = pc->params[pc->best], e.desc = d, e.photo = photo;
      wv_pattern_choice_scene(pc, &s, pc->best, &e.scene);
      wv_scene scene_t;
      wv_pattern_choice_scene(pc, &st, pc->best, &scene_t);
      wv_fit_opts o = fo;
      wv_capture_fit_opts(pc, 0, &o);
      int kt_model = found;
      if (found && (wv_estimate_transmission(&e, &scene_t, &photo_t, ppath, &err) ||
                    wv_capture_pair_start(&e, &scene_t, &photo_t, &o, &kt_model, &err)))
        die(&err);
      wv_params start = e.params;
      wv_fit_state fs;
      if (wv_fit_state_init(&fs, &start, &o, &err) ||
          wv_fit_run_pair(&fs, &e.scene, &photo, &scene_t, &photo_t, d, &o, NULL, NULL, &err))
        die(&err);
      double secs = bench_now() - t0;
      wv_scene fr, ft;
      wv_params pt; /* the back-lit photo's own view (woven capture's render_t.png) */
      wv_fit_scene(&fs, &e.scene, &fr);
      wv_fit_scene_t(&fs, &scene_t, &ft);
      wv_fit_params_t(&fs, &fs.params, &pt);
      wv_image rr, rt;
      double mean_fit[3], mean_truth[3];
      render(&fr, &fs.params, threads, 0, &rr, NULL);
      render(&ft, &pt, threads, 0, &rt, mean_fit);
      /* the ceiling: the truth with the fit's noise seed */
      ceil_p = truth;
      ceil_p.seed = fs.params.seed != truth.seed ? fs.params.seed : truth.seed + 1;
      render(&s, &ceil_p, threads, 0, &ceil_r, NULL);
      render(&st, &ceil_p, threads, 0, &ceil_t, mean_truth);
      /* the truth with the fit's transmission colours: how far the back-lit photo tells them
       * from the truth's (near the ceiling: it does not) */
      wv_params cf = ceil_p;
      for (int k = WV_P_REFLECT_COUNT; k < WV_P_COUNT; k++) wv_param_set(&cf, k, wv_param_get(&fs.params, k));
      cf.forward_width = fs.params.forward_width;
      wv_image colours_t, kt10_t;
      render(&st, &cf, threads, 0, &colours_t, NULL);
      /* for scale: the truth with its k_t 10% brighter, every yarn type and channel */
      cf = ceil_p;
      for (int k = WV_P_KT_WARP_R; k < WV_P_KT_WARP_R + 6; k++) wv_param_set(&cf, k, 1.1 * wv_param_get(&cf, k));
      render(&st, &cf, threads, 0, &kt10_t, NULL);
      if (save) { /* the pair and its re-renders, for a look */
        const wv_image *im[4] = {&photo, &photo_t, &rr, &rt};
        static const char *const tag[4] = {"R", "T", "fit_R", "fit_T"};
        for (int k = 0; k < 4; k++) {
          char path[4096];
          snprintf(path, sizeof path, "%s/%s_%d_%s.png", save, FAMILIES[f], i, tag[k]);
          if (wv_image_write_png(path, im[k], 8, &err)) die(&err);
        }
        const wv_params *pp[2] = {&truth, &fs.params};
        static const char *const ptag[2] = {"truth", "fit"};
        for (int k = 0; k < 2; k++) {
          char path[4096];
          snprintf(path, sizeof path, "%s/%s_%d_%s.json", save, FAMILIES[f], i, ptag[k]);
          if (wv_params_write(path, pp[k], &err)) die(&err);
        }
      }
      double sr = ssim_of(&photo, &rr), st_ = ssim_of(&photo_t, &rt), sc = ssim_of(&photo_t, &colours_t);
      double s10 = ssim_of(&photo_t, &kt10_t);
      double cr = ssim_of(&photo, &ceil_r), ct = ssim_of(&photo_t, &ceil_t);
      double oa_t = open_area(&truth), oa_f = open_area(&fs.params);
      double oa_err = oa_t > 0 ? fabs(oa_f - oa_t) / oa_t : fabs(oa_f - oa_t);
      double kt_e = kt_error(&fs.params, &truth, WV_P_KT_WARP_R), kt_s = kt_error(&start, &truth, WV_P_KT_WARP_R);
      double kst_e = kt_error(&fs.params, &truth, WV_P_KST_WARP_R), kst_s = kt_error(&start, &truth, WV_P_KST_WARP_R);
      double tc_e = colour_error(mean_fit, mean_truth);
      double kf_e = kt_error(&fs.params, &truth, WV_P_KF_WARP_R);
      int fam_right = !strcmp(wv_weave_family(fs.params.pattern), FAMILIES[f]);
      printf("%s %d %s -> %s: density %.1f/%.1f -> %.1f/%.1f, R %.3f/%.3f = %.3f, T %.3f/%.3f = %.3f, open area %.4f -> "
             "%.4f (%.2f), k_t error "
             "%.3f (start %.3f, %s), k_st error %.3f (start %.3f), k_f error %.3f (width %.3f -> %.3f), transmitted colour "
             "error %.3f, the truth with the fit's colours T %.3f (with k_t 10%% up %.3f), back-lit view %s %.4f %+.2f "
             "deg, %d it, %.0f s\n",
             FAMILIES[f], i, pattern, fs.params.pattern, truth.density[0], truth.density[1], fs.params.density[0],
             fs.params.density[1], sr, cr, sr / cr, st_, ct, st_ / ct, oa_t, oa_f, oa_err, kt_e,
             kt_s, kt_model == 1 ? "pair model" : "prior", kst_e, kst_s, kf_e, truth.forward_width,
             fs.params.forward_width, tc_e, sc / ct, s10 / ct, fs.t_found ? "related" : "not related",
             fs.t_scale, fs.t_rotation_deg, fs.iter, secs);
      fflush(stdout);
      json_t *tj = json_pack("{s:f,s:f,s:f,s:f,s:f}", "kf_error", kf_e, "forward_width", truth.forward_width,
                             "forward_width_fit", fs.params.forward_width, "ratio_t_fit_colours", sc / ct,
                             "ratio_t_kt_10pct", s10 / ct);
      json_t *rest = json_pack("{s:s,s:i,s:s,s:s,s:b,s:f,s:f,s:f,s:f,s:f,s:f,s:f,s:f,s:f,s:f,s:f,s:f,s:f,s:f,s:b,s:f,s:f,s:i,s:f}",
                             "family", FAMILIES[f], "draw", i, "pattern", pattern, "chosen", fs.params.pattern, "family_right",
                             fam_right, "ssim_r", sr, "ceiling_r", cr, "ratio_r", sr / cr, "ssim_t", st_, "ceiling_t",
                             ct, "ratio_t", st_ / ct, "open_area", oa_t, "open_area_fit", oa_f, "open_area_error",
                             oa_err, "kt_error", kt_e, "kt_error_start", kt_s, "kst_error", kst_e, "kst_error_start",
                             kst_s, "transmitted_colour_error", tc_e, "view_t_related", fs.t_found, "view_t_scale",
                             fs.t_scale, "view_t_rotation_deg", fs.t_rotation_deg, "iterations", fs.iter, "seconds",
                             secs);
      json_object_update(tj, rest);
      json_decref(rest);
      json_array_append_new(targets, tj);
      fam_sum[f][0] += sr / cr, fam_sum[f][1] += st_ / ct, fam_sum[f][2] += oa_err;
      fam_sum[f][3] += kt_e, fam_sum[f][4] += kst_e, fam_sum[f][5] += tc_e;
      fam_n[f]++, fam_ok[f] += fam_right;
      wv_fit_state_free(&fs);
      free(pc);
      wv_image_free(&photo), wv_image_free(&photo_t), wv_image_free(&rr), wv_image_free(&rt);
      wv_image_free(&ceil_r), wv_image_free(&ceil_t), wv_image_free(&colours_t), wv_image_free(&kt10_t);
    }
  }
  json_t *fams = json_object();
  double all[6] = {0};
  int n = 0, ok = 0;
  for (int f = 0; f < NFAM; f++) {
    if (!fam_n[f]) continue;
    json_object_set_new(fams, FAMILIES[f],
                        json_pack("{s:i,s:i,s:f,s:f,s:f,s:f,s:f,s:f}", "targets", fam_n[f], "family_right", fam_ok[f],
                                  "mean_ratio_r", fam_sum[f][0] / fam_n[f], "mean_ratio_t", fam_sum[f][1] / fam_n[f],
                                  "mean_open_area_error", fam_sum[f][2] / fam_n[f], "mean_kt_error",
                                  fam_sum[f][3] / fam_n[f], "mean_kst_error", fam_sum[f][4] / fam_n[f],
                                  "mean_transmitted_colour_error", fam_sum[f][5] / fam_n[f]));
    for (int k = 0; k < 6; k++) all[k] += fam_sum[f][k];
    n += fam_n[f], ok += fam_ok[f];
  }
  json_t *out = json_pack("{s:s,s:s,s:o,s:o,s:{s:i,s:i,s:f,s:f,s:f,s:f,s:f,s:f},s:f}", "model", mpath, "pair_model",
                          found ? ppath : "none (the prior's k_t)", "targets", targets, "families", fams, "all",
                          "targets", n, "family_right", ok, "mean_ratio_r", n ? all[0] / n : 0, "mean_ratio_t",
                          n ? all[1] / n : 0, "mean_open_area_error", n ? all[2] / n : 0, "mean_kt_error",
                          n ? all[3] / n : 0, "mean_kst_error", n ? all[4] / n : 0, "mean_transmitted_colour_error",
                          n ? all[5] / n : 0, "seconds", bench_now() - t_all);
  char *text = json_dumps(out, JSON_COMPACT | JSON_REAL_PRECISION(6));
  printf("%s\n", text);
  free(text);
  json_decref(out);
  wv_fabricnet_free(&net);
  wv_descriptor_free(d);
  return 0;
}
