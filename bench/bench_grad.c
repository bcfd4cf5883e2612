/* Benchmark: forward render vs forward + gradient (wv_render_grad) on the
 * cylinder preset (800 x 300) at its default spp, twill prior mean; also the
 * two-step path (wv_render_record, then wv_record_grad). Runs are interleaved
 * and each figure is a median, as the machine is shared.
 *   bench_grad [--runs N] [--spp N] [--threads N]
 * Last line: {"forward_ms": ..., "forward_grad_ms": ..., "ratio": ..., ...}
 *   bench_grad --grad-check [--scene cylinder|flat45] [--spp N]
 * prints analytic vs central-difference gradients (double precision, a 48 x 32
 * window at the image centre) and, last, a JSON line with the largest relative error.
 *   bench_grad --blur [--sigma S] [--runs N] [--spp N] [--threads N]
 * times one fit iteration's gradient path with a camera blur: flat45 (512 x 512) at
 * 4 spp (--spp), blur sigma 0.64 px (--sigma), twill prior mean. Last line: JSON medians
 * of the forward render (forward_ms), wv_render_record with a fresh record (record_ms)
 * and into the record of the run before, as the fit does (record_reuse_ms),
 * wv_record_grad (record_grad_ms), wv_record_grad_psf (record_grad_psf_ms), and the
 * fit's path, record_reuse + record_grad + record_grad_psf (gradient_path_ms). */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "woven/grad.h"
#include "woven/render.h"

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return x < y ? -1 : x > y;
}

static double median(double *v, int n) {
  qsort(v, (size_t)n, sizeof *v, cmp_double);
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

static int grad_check(const char *scene_name, int spp) {
  wv_scene s;
  wv_params p;
  wv_error err = {0};
  if (wv_scene_preset(scene_name, &s, &err) || wv_params_default("twill", &p, &err)) {
    fprintf(stderr, "bench_grad: %s\n", err.msg);
    return 1;
  }
  wv_grad_opts g = {.x0 = s.width / 2 - 24, .y0 = s.height / 2 - 16, .width = 48, .height = 32, .double_precision = 1};
  wv_image dc;
  if (wv_image_alloc(&dc, g.width, g.height, 3, &err)) return 1;
  uint64_t st = 7;
  for (int i = 0; i < g.width * g.height * 3; i++) {
    st = st * 6364136223846793005ULL + 1442695040888963407ULL;
    dc.data[i] = (float)((st >> 40) * (2.0 / 16777216.0) - 1.0);
  }
  wv_render_opts o = {0};
  o.spp = spp > 0 ? spp : 16;
  wv_grad_check_entry e[WV_P_COUNT];
  if (wv_grad_check(&s, &p, &o, &g, &dc, 1e-5, e, &err)) {
    fprintf(stderr, "bench_grad: %s\n", err.msg);
    wv_image_free(&dc);
    return 1;
  }
  double worst = 0;
  printf("%-18s %14s %16s %16s %10s\n", "parameter", "value", "analytic", "finite diff", "rel err");
  for (int i = 0; i < WV_P_COUNT; i++) {
    printf("%-18s %14.6g %+16.9e %+16.9e %10.2e\n", wv_param_name(i), wv_param_get(&p, i), e[i].analytic,
           e[i].numeric, e[i].rel_err);
    if (e[i].rel_err > worst) worst = e[i].rel_err;
  }
  printf("{\"scene\": \"%s\", \"spp\": %d, \"max_rel_err\": %.3e}\n", scene_name, o.spp, worst);
  wv_image_free(&dc);
  return 0;
}

/* An adjoint like an L1 loss against a photo: +-1 per value. */
static void l1_adjoint(wv_image *dc) {
  uint64_t st = 1;
  for (int i = 0; i < dc->w * dc->h * dc->c; i++) {
    st = st * 6364136223846793005ULL + 1442695040888963407ULL;
    dc->data[i] = (st >> 63) ? 1.0f : -1.0f;
  }
}

/* The fit's gradient path with a camera blur (--blur). */
static int blur_bench(double sigma, int runs, int spp, int threads) {
  wv_scene s;
  wv_params p;
  wv_error err = {0};
  if (wv_scene_preset("flat45", &s, &err) || wv_params_default("twill", &p, &err)) {
    fprintf(stderr, "bench_grad: %s\n", err.msg);
    return 1;
  }
  s.psf_sigma = sigma;
  wv_render_opts o = {0};
  o.spp = spp > 0 ? spp : 4, o.threads = threads;
  wv_footprints *fp = NULL;
  if (wv_footprints_create(&s, threads, &fp, &err)) {
    fprintf(stderr, "bench_grad: %s\n", err.msg);
    return 1;
  }
  o.footprints = fp;
  wv_image dc;
  if (wv_image_alloc(&dc, s.width, s.height, 3, &err)) return 1;
  l1_adjoint(&dc);
  double tf[100], tr[100], tu[100], tg[100], tp[100], tt[100], grad[WV_P_COUNT], dsig = 0;
  wv_grad_record *kept = NULL; /* the fit's record, rendered into every iteration */
  for (int r = 0; r < runs; r++) {
    wv_image cap, cap2, cap3;
    wv_grad_record *rec;
    double t0 = omp_get_wtime();
    if (wv_render(&s, &p, &o, &cap, NULL, &err)) goto fail;
    double t1 = omp_get_wtime();
    if (wv_render_record(&s, &p, &o, NULL, &cap2, &rec, &err)) goto fail;
    double t2 = omp_get_wtime();
    wv_record_free(rec);
    wv_image_free(&cap), wv_image_free(&cap2);
    double t3 = omp_get_wtime();
    if (wv_render_record_into(&s, &p, &o, NULL, &cap3, &kept, &err)) goto fail;
    double t4 = omp_get_wtime();
    if (wv_record_grad(kept, &dc, grad, NULL, &err)) goto fail;
    double t5 = omp_get_wtime();
    if (wv_record_grad_psf(kept, &dc, &dsig, &err)) goto fail;
    double t6 = omp_get_wtime();
    wv_image_free(&cap3);
    tf[r] = (t1 - t0) * 1e3, tr[r] = (t2 - t1) * 1e3, tu[r] = (t4 - t3) * 1e3, tg[r] = (t5 - t4) * 1e3;
    tp[r] = (t6 - t5) * 1e3, tt[r] = tu[r] + tg[r] + tp[r];
    printf("run %d: forward %.1f ms, record %.1f ms (reused %.1f ms), record_grad %.1f ms, record_grad_psf %.1f ms\n",
           r + 1, tf[r], tr[r], tu[r], tg[r], tp[r]);
    fflush(stdout);
  }
  printf("{\"scene\": \"flat45\", \"width\": %d, \"height\": %d, \"spp\": %d, \"psf_sigma\": %g, "
         "\"threads\": %d, \"runs\": %d, \"forward_ms\": %.1f, \"record_ms\": %.1f, \"record_reuse_ms\": %.1f, "
         "\"record_grad_ms\": %.1f, \"record_grad_psf_ms\": %.1f, \"gradient_path_ms\": %.1f, \"dsigma\": %.9e}\n",
         s.width, s.height, o.spp, sigma, threads > 0 ? threads : omp_get_max_threads(), runs, median(tf, runs),
         median(tr, runs), median(tu, runs), median(tg, runs), median(tp, runs), median(tt, runs), dsig);
  wv_record_free(kept);
  wv_image_free(&dc);
  wv_footprints_free(fp);
  return 0;
fail:
  fprintf(stderr, "bench_grad: %s\n", err.msg);
  wv_record_free(kept);
  wv_image_free(&dc);
  wv_footprints_free(fp);
  return 1;
}

int main(int argc, char **argv) {
  int runs = 3, spp = 0, threads = 0, check = 0, blur = 0;
  double sigma = 0.64;
  const char *scene_name = "cylinder";
  for (int i = 1; i < argc; i++) {
    if (!strcmp(argv[i], "--runs") && i + 1 < argc) runs = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--spp") && i + 1 < argc) spp = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--threads") && i + 1 < argc) threads = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--scene") && i + 1 < argc) scene_name = argv[++i];
    else if (!strcmp(argv[i], "--grad-check")) check = 1;
    else if (!strcmp(argv[i], "--blur")) blur = 1;
    else if (!strcmp(argv[i], "--sigma") && i + 1 < argc) sigma = atof(argv[++i]);
    else {
      fprintf(stderr, "usage: bench_grad [--runs N] [--spp N] [--threads N] | --grad-check [--scene S] [--spp N] | "
                      "--blur [--sigma S] [--runs N] [--spp N] [--threads N]\n");
      return 1;
    }
  }
  if (check) return grad_check(scene_name, spp);
  if (runs < 1 || runs > 100) runs = 3;
  if (blur) {
    if (!(sigma > 0 && sigma <= WV_PSF_MAX_SIGMA)) {
      fprintf(stderr, "bench_grad: --sigma %g is outside (0, %g]\n", sigma, WV_PSF_MAX_SIGMA);
      return 1;
    }
    return blur_bench(sigma, runs, spp, threads);
  }
  wv_scene s;
  wv_params p;
  wv_error err = {0};
  if (wv_scene_preset("cylinder", &s, &err) || wv_params_default("twill", &p, &err)) {
    fprintf(stderr, "bench_grad: %s\n", err.msg);
    return 1;
  }
  wv_render_opts o = {0};
  o.spp = spp, o.threads = threads;
  wv_image dc;
  if (wv_image_alloc(&dc, s.width, s.height, 3, &err)) return 1;
  l1_adjoint(&dc);
  double tf[100], tg[100], tr[100], tb[100], grad[WV_P_COUNT];
  for (int r = 0; r < runs; r++) {
    wv_image cap, cap2, cap3;
    wv_grad_record *rec;
    double t0 = omp_get_wtime();
    if (wv_render(&s, &p, &o, &cap, NULL, &err)) goto fail;
    double t1 = omp_get_wtime();
    if (wv_render_grad(&s, &p, &o, &dc, grad, &cap2, &err)) goto fail;
    double t2 = omp_get_wtime();
    if (wv_render_record(&s, &p, &o, NULL, &cap3, &rec, &err)) goto fail;
    double t3 = omp_get_wtime();
    if (wv_record_grad(rec, &dc, grad, NULL, &err)) goto fail;
    double t4 = omp_get_wtime();
    tf[r] = (t1 - t0) * 1e3, tg[r] = (t2 - t1) * 1e3, tr[r] = (t3 - t2) * 1e3, tb[r] = (t4 - t3) * 1e3;
    printf("run %d: forward %.0f ms, forward+grad %.0f ms, record %.0f ms + grad %.1f ms\n", r + 1, tf[r], tg[r],
           tr[r], tb[r]);
    fflush(stdout);
    wv_record_free(rec);
    wv_image_free(&cap), wv_image_free(&cap2), wv_image_free(&cap3);
  }
  double fm = median(tf, runs), gm = median(tg, runs), rm = median(tr, runs), bm = median(tb, runs);
  printf("{\"scene\": \"cylinder\", \"width\": %d, \"height\": %d, \"spp\": %d, \"threads\": %d, \"runs\": %d, "
         "\"record_ms\": %.1f, \"record_grad_ms\": %.2f, "
         "\"forward_ms\": %.1f, \"forward_grad_ms\": %.1f, \"ratio\": %.3f}\n",
         s.width, s.height, spp > 0 ? spp : s.spp, threads > 0 ? threads : omp_get_max_threads(), runs, rm, bm, fm,
         gm, gm / fm);
  wv_image_free(&dc);
  return 0;
fail:
  fprintf(stderr, "bench_grad: %s\n", err.msg);
  wv_image_free(&dc);
  return 1;
}
