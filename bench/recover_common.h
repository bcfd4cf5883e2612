/* What the recovery studies share (bench/recover.c, bench/recover_degraded.c): a capture
 * as woven capture runs it (the network's estimate, the pattern choice, the fit), its
 * measures against a target, and the two-colour draws. Define RECOVER_NAME (the program's
 * name, for messages) before including. */
#ifndef WOVEN_BENCH_RECOVER_COMMON_H
#define WOVEN_BENCH_RECOVER_COMMON_H
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_common.h"
#include "util/hash.h"
#include "woven/capture.h"
#include "woven/descriptor.h"
#include "woven/fit.h"
#include "woven/metrics.h"
#include "woven/pattern.h"
#include "woven/photo.h"
#include "woven/render.h"

static void die(const wv_error *e) {
  fprintf(stderr, "%s: %s\n", RECOVER_NAME, e->msg);
  exit(1);
}

typedef struct {
  const wv_scene *s;
  wv_descriptor *d;
  wv_fabricnet *net; /* NULL: --start prior */
  wv_fit_opts o;
  int orient, refine; /* wv_pattern_opts.orient, .refine */
} study;

/* What one capture gave. */
typedef struct {
  char chosen[16];
  char lattice_choice[16]; /* the family's best pattern by the lattice and render match alone */
  const char *method;
  wv_pattern_families families; /* how each family stood in the choice (kind "none": given) */
  wv_params start, fit;
  wv_scene fit_scene; /* the scene with the registration's offset */
  double blur_start;  /* the camera blur measured before the first iteration (px) */
  double seconds, choice_seconds;
} capture;

/* The capture of photo: the network's estimate and the pattern choice (or the given start),
 * then the fit. */
static void run_capture(const study *st, const wv_image *photo, const wv_params *given, capture *c) {
  wv_error err = {0};
  double t0 = bench_now();
  memset(c, 0, sizeof *c);
  wv_fit_opts o = st->o; /* as woven capture adapts them to the pattern choice */
  wv_scene scene = *st->s; /* and its scene, with the lattice's orientation */
  c->families.kind = "none";
  if (given) {
    c->start = *given;
    c->method = "given";
  } else {
    float y[WV_NET_OUT];
    wv_pattern_choice *pc = malloc(sizeof *pc);
    if (!pc) exit(1);
    wv_pattern_opts po;
    wv_pattern_opts_default(&po);
    po.orient = st->orient, po.refine = st->refine, po.threads = st->o.threads;
    if (wv_fabricnet_predict_pattern(st->net, st->d, st->s, photo, &po, y, pc, &err)) die(&err);
    wv_pattern_choice_scene(pc, st->s, pc->best, &scene);
    c->start = pc->params[pc->best];
    c->method = pc->method;
    /* no family tie and no pattern tie: the lattice and render match decide alone */
    int lb = pc->lattice.found ? wv_pattern_decide(pc, 0.0, -1.0, NULL) : pc->best;
    snprintf(c->lattice_choice, sizeof c->lattice_choice, "%s", wv_weave_builtin_name(lb >= 0 ? lb : pc->best));
    c->choice_seconds = pc->seconds;
    wv_pattern_family_scores(pc, &c->families);
    wv_capture_fit_opts(pc, 0, &o);
    free(pc);
  }
  snprintf(c->chosen, sizeof c->chosen, "%s", c->start.pattern);
  wv_fit_state fs;
  if (wv_fit_state_init(&fs, &c->start, &o, &err) || wv_fit_run(&fs, &scene, photo, st->d, &o, NULL, NULL, &err))
    die(&err);
  c->fit = fs.params;
  c->blur_start = fs.psf_start;
  wv_fit_scene(&fs, &scene, &c->fit_scene);
  wv_fit_state_free(&fs);
  c->seconds = bench_now() - t0;
}

/* SSIM (RGB and luminance, ssim_luma may be NULL), WSC and whitened WSC (wsc[0], wsc[1]) of
 * img against ref; with blur > 0 also SSIM and WSC of img blurred by that sigma (blurred[0]
 * SSIM, [1] WSC). */
static void measure_image(const wv_image *img, const wv_image *ref, double *ssim_rgb, double *ssim_luma, double wsc[2],
                          double blur, double blurred[2]) {
  wv_image b;
  wv_error err = {0};
  if (wv_ssim(ref, img, WV_SSIM_RGB, ssim_rgb, &err) || (ssim_luma && wv_ssim(ref, img, WV_SSIM_LUMA, ssim_luma, &err)) ||
      wv_wsc(ref, img, &wsc[0], &err) || wv_wsc_whitened(ref, img, &wsc[1], &err))
    die(&err);
  if (blur > 0) {
    if (wv_image_blur(img, blur, &b, &err) || wv_ssim(ref, &b, WV_SSIM_RGB, &blurred[0], &err) ||
        wv_wsc(ref, &b, &blurred[1], &err))
      die(&err);
    wv_image_free(&b);
  }
}

/* measure_image of a full-quality render of p in s. */
static void measure(const wv_scene *s, const wv_params *p, const wv_image *ref, int threads, double *ssim_rgb,
                    double *ssim_luma, double wsc[2], double blur, double blurred[2]) {
  wv_render_opts ro = {.threads = threads};
  wv_image img;
  wv_error err = {0};
  if (wv_render(s, p, &ro, &img, NULL, &err)) die(&err);
  measure_image(&img, ref, ssim_rgb, ssim_luma, wsc, blur, blurred);
  wv_image_free(&img);
}

/* A two-colour cloth as denim: a dark blue warp and a near-white weft, a little varied. */
static void two_colour(wv_params *p, uint64_t seed) {
  double j[4];
  for (int k = 0; k < 4; k++) j[k] = wv_u01d(wv_hash2(seed, (uint64_t)k, 99));
  double warp[3] = {0.03 + 0.04 * j[0], 0.07 + 0.06 * j[1], 0.25 + 0.2 * j[2]};
  double weft[3] = {0.75 + 0.15 * j[3], 0.74 + 0.15 * j[3], 0.68 + 0.15 * j[3]};
  for (int c = 0; c < 3; c++) {
    p->diffuse[WV_WARP][c] = warp[c], p->diffuse[WV_WEFT][c] = weft[c];
    p->specular[WV_WARP][c] = sqrt(warp[c]), p->specular[WV_WEFT][c] = sqrt(weft[c]);
  }
}
#endif
