/* Descriptor speed: the default descriptor against its former im2col + OpenBLAS path
 * (descriptor_ref.h) in the same run, with how far their results differ; forward and
 * forward + backward for VGG-19 (random weights), VGG-19's convolutions alone, and a
 * plain OpenBLAS sgemm. Prints one JSON object on its last line (medians).
 * --quick: fewer repetitions; --default-only: skip VGG-19 and the sgemm;
 * --profile-former: only the former path's time per part (stderr). */
#include <cblas.h>
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "descriptor_ref.h"
#include "woven/descriptor.h"
#include "woven/nn.h"

static double now_ms(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return t.tv_sec * 1e3 + t.tv_nsec * 1e-6;
}

static int cmp_d(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return x < y ? -1 : x > y;
}

static double median(double *v, int n) {
  qsort(v, n, sizeof *v, cmp_d);
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

static void die(const wv_error *e) {
  fprintf(stderr, "bench_descriptor: %s\n", e->msg);
  exit(1);
}

/* Square matrices for the reference sgemm, allocated once. */
#define SG_N 2048
static float *sg_a, *sg_b, *sg_c;

/* One plain OpenBLAS sgemm (n = 2048) with OpenBLAS's own threads: GFLOP/s. */
static double sgemm_once(void) {
  openblas_set_num_threads(omp_get_max_threads());
  double t0 = now_ms();
  cblas_sgemm(CblasRowMajor, CblasNoTrans, CblasNoTrans, SG_N, SG_N, SG_N, 1, sg_a, SG_N, sg_b,
              SG_N, 0, sg_c, SG_N);
  double t = now_ms() - t0;
  wv_nn_blas_serial();
  /* OpenBLAS's idle workers spin for about 0.1 s after a threaded call and would slow
   * whatever runs next on the two cores: let them fall asleep. */
  struct timespec pause = {0, 250000000};
  nanosleep(&pause, NULL);
  return 2.0 * SG_N * SG_N * SG_N / t * 1e-6;
}

/* The same product through wv_nn_sgemm (OpenMP threads, serial OpenBLAS). */
static double nn_sgemm_once(void) {
  double t0 = now_ms();
  wv_nn_sgemm(0, 0, SG_N, SG_N, SG_N, 1, sg_a, SG_N, sg_b, SG_N, 0, sg_c, SG_N);
  return 2.0 * SG_N * SG_N * SG_N / (now_ms() - t0) * 1e-6;
}

/* A woven-looking test image: stripes plus noise. */
static void make_image(wv_image *img, int w, int h) {
  wv_error e;
  if (wv_image_alloc(img, w, h, 3, &e)) die(&e);
  wv_rng r;
  wv_rng_seed(&r, 3);
  for (int y = 0; y < h; y++)
    for (int x = 0; x < w; x++)
      for (int c = 0; c < 3; c++)
        wv_image_px(img, x, y)[c] =
            0.3f + 0.2f * (((x / 2 + y / 2) & 1) ? 1.0f : 0.0f) + 0.1f * wv_rng_uniform(&r);
}

static void time_desc(wv_descriptor *d, int w, int h, int reps, double *fwd, double *fb) {
  wv_image img, dimg;
  wv_error e;
  make_image(&img, w, h);
  if (wv_image_alloc(&dimg, w, h, 3, &e)) die(&e);
  size_t n = wv_descriptor_size(d);
  float *g = malloc(sizeof(float) * n), *dg = malloc(sizeof(float) * n);
  wv_rng r;
  wv_rng_seed(&r, 4);
  wv_rng_fill_uniform(&r, dg, n, -1, 1);
  double tf[32], tb[32];
  if (wv_descriptor_backward(d, &img, dg, g, &dimg, &e)) die(&e); /* sizes the buffers */
  for (int i = 0; i < reps; i++) {
    double t0 = now_ms();
    if (wv_descriptor_forward(d, &img, g, &e)) die(&e);
    tf[i] = now_ms() - t0;
    t0 = now_ms();
    if (wv_descriptor_backward(d, &img, dg, g, &dimg, &e)) die(&e);
    tb[i] = now_ms() - t0;
  }
  *fwd = median(tf, reps);
  *fb = median(tb, reps);
  fprintf(stderr, "%s %dx%d: forward %.1f ms, forward+backward %.1f ms\n", wv_descriptor_name(d),
          w, h, *fwd, *fb);
  free(g), free(dg);
  wv_image_free(&img), wv_image_free(&dimg);
}

/* ---- The default descriptor against the former path ---- */

static double cpu_ms(void) {
  struct timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return t.tv_sec * 1e3 + t.tv_nsec * 1e-6;
}

/* max |a - b| / max |b|, and the largest elementwise |a - b| / |b| over the elements
 * with |b| above 1e-3 max |b| (smaller ones are sums that cancel). */
static void rel_diff(const float *a, const float *b, size_t n, double *normwise, double *elemwise) {
  double bmax = 0, dmax = 0, emax = 0;
  for (size_t i = 0; i < n; i++) bmax = fmax(bmax, fabs(b[i]));
  for (size_t i = 0; i < n; i++) {
    double d = fabs((double)a[i] - b[i]);
    dmax = fmax(dmax, d);
    if (fabs(b[i]) > 1e-3 * bmax) emax = fmax(emax, d / fabs(b[i]));
  }
  *normwise = bmax > 0 ? dmax / bmax : dmax;
  *elemwise = emax;
}

typedef struct {
  double old_fwd, new_fwd, old_fb, new_fb, old_fit, new_fit; /* median ms */
  double fwd_x, fb_x, fit_x;                                /* median of per-run ratios */
  double cpu_fb_x;                                          /* the same in CPU time */
  double gram_nw, gram_ew, grad_nw, grad_ew;                /* worst over the images */
} cmp_result;

/* A planar input as the descriptor sees it (ImageNet-normalised values): uniform
 * noise for odd seeds, the stripes of make_image for even ones. */
static void planar_input(float *x, int w, int h, uint64_t seed) {
  wv_rng r;
  wv_rng_seed(&r, seed);
  size_t n = (size_t)w * h;
  for (int c = 0; c < 3; c++)
    for (size_t i = 0; i < n; i++) {
      int px = (int)(i % w), py = (int)(i / w);
      float v = seed % 2 ? wv_rng_uniform(&r)
                         : 0.3f + 0.2f * (((px / 2 + py / 2) & 1) ? 1.0f : 0.0f) +
                               0.1f * wv_rng_uniform(&r);
      x[c * n + i] = (v - 0.45f) / 0.225f;
    }
}

/* Old and new paths on the same w x h input, alternating within each repetition:
 * forward, forward + backward (Gram and gradient), and the fit's step (forward, then
 * backward for the gradient alone; the former path had no such call and ran both in
 * full). Then both paths on nimg random inputs for the differences. */
static void compare_default(wv_descriptor *d, int w, int h, int reps, int nimg, cmp_result *o) {
  wv_error e;
  size_t n = wv_descriptor_size(d), nx = (size_t)3 * w * h;
  float *x = malloc(sizeof(float) * nx), *dx0 = malloc(sizeof(float) * nx),
        *dx1 = malloc(sizeof(float) * nx), *g0 = malloc(sizeof(float) * n),
        *g1 = malloc(sizeof(float) * n), *dg = malloc(sizeof(float) * n);
  ref_net R;
  if (ref_init(&R, d, w, h)) {
    fprintf(stderr, "bench_descriptor: not the default descriptor\n");
    exit(1);
  }
  memset(o, 0, sizeof *o);
  for (int k = 0; k < nimg; k++) {
    planar_input(x, w, h, 100 + k);
    wv_rng r;
    wv_rng_seed(&r, 200 + k);
    wv_rng_fill_uniform(&r, dg, n, -1, 1);
    ref_run(&R, x, dg, g0, dx0, NULL);
    if (d->run(d, x, w, h, dg, g1, dx1, &e)) die(&e);
    double nw, ew;
    rel_diff(g1, g0, n, &nw, &ew);
    o->gram_nw = fmax(o->gram_nw, nw), o->gram_ew = fmax(o->gram_ew, ew);
    rel_diff(dx1, dx0, nx, &nw, &ew);
    o->grad_nw = fmax(o->grad_nw, nw), o->grad_ew = fmax(o->grad_ew, ew);
  }
  planar_input(x, w, h, 100);
  double t[6][64], ratio[4][64];
  for (int i = 0; i <= reps; i++) {
    double a = now_ms();
    ref_run(&R, x, NULL, g0, NULL, NULL);
    double b = now_ms();
    if (d->run(d, x, w, h, NULL, g1, NULL, &e)) die(&e);
    double c = now_ms(), cc = cpu_ms();
    ref_run(&R, x, dg, g0, dx0, NULL);
    double dd = now_ms(), cd = cpu_ms();
    if (d->run(d, x, w, h, dg, g1, dx1, &e)) die(&e);
    double ee = now_ms(), ce = cpu_ms();
    ref_run(&R, x, NULL, g0, NULL, NULL);
    ref_run(&R, x, dg, g0, dx0, NULL);
    double f = now_ms();
    if (d->run(d, x, w, h, NULL, g1, NULL, &e) || d->run(d, x, w, h, dg, NULL, dx1, &e)) die(&e);
    double gg = now_ms();
    if (!i) continue; /* warm-up */
    double v[6] = {b - a, c - b, dd - c, ee - dd, f - ee, gg - f};
    for (int j = 0; j < 6; j++) t[j][i - 1] = v[j];
    ratio[0][i - 1] = v[0] / v[1], ratio[1][i - 1] = v[2] / v[3], ratio[2][i - 1] = v[4] / v[5];
    ratio[3][i - 1] = (cd - cc) / (ce - cd);
  }
  o->old_fwd = median(t[0], reps), o->new_fwd = median(t[1], reps);
  o->old_fb = median(t[2], reps), o->new_fb = median(t[3], reps);
  o->old_fit = median(t[4], reps), o->new_fit = median(t[5], reps);
  o->fwd_x = median(ratio[0], reps), o->fb_x = median(ratio[1], reps);
  o->fit_x = median(ratio[2], reps), o->cpu_fb_x = median(ratio[3], reps);
  fprintf(stderr,
          "default %dx%d: forward %.1f -> %.1f ms (%.2fx), forward+backward %.1f -> %.1f ms "
          "(%.2fx, CPU time %.2fx), fit step %.1f -> %.1f ms (%.2fx); new vs old: Gram %.1e, "
          "gradient %.1e (max |diff| / max |old|), elementwise %.1e, %.1e\n",
          w, h, o->old_fwd, o->new_fwd, o->fwd_x, o->old_fb, o->new_fb, o->fb_x, o->cpu_fb_x,
          o->old_fit, o->new_fit, o->fit_x, o->gram_nw, o->grad_nw, o->gram_ew, o->grad_ew);
  ref_free(&R);
  free(x), free(dx0), free(dx1), free(g0), free(g1), free(dg);
}

/* Where the former path's time goes: level 0 of a w x h input, forward + backward, one
 * thread, CPU time per part (medians over reps passes), printed as a table on stderr. */
static void profile_former(wv_descriptor *d, int w, int h, int reps) {
  size_t n = wv_descriptor_size(d), nx = (size_t)3 * w * h;
  float *x = malloc(sizeof(float) * nx), *dx = malloc(sizeof(float) * nx),
        *g = malloc(sizeof(float) * n), *dg = malloc(sizeof(float) * n);
  planar_input(x, w, h, 100);
  wv_rng r;
  wv_rng_seed(&r, 200);
  wv_rng_fill_uniform(&r, dg, n, -1, 1);
  int nt = omp_get_max_threads();
  omp_set_num_threads(1);
  ref_net R;
  if (ref_init(&R, d, w, h)) exit(1);
  double part[REF_PARTS], runs[REF_PARTS][64], total[64];
  for (int i = 0; i <= reps; i++) {
    memset(part, 0, sizeof part);
    ref_run(&R, x, dg, g, dx, part);
    if (!i) continue; /* warm-up */
    total[i - 1] = 0;
    for (int j = 0; j < REF_PARTS; j++) runs[j][i - 1] = part[j], total[i - 1] += part[j];
  }
  /* Multiply-adds per output position of each part (the Gram's upper triangle). */
  static const double flops[REF_PARTS] = {0, 2 * 64 * 27, 0, 64 * 65, 2 * 64 * 64, 2 * 27 * 64, 0};
  double npos = (double)(w - 2) * (h - 2);
  fprintf(stderr, "former path, level 0 of %dx%d, forward + backward, 1 thread, CPU time:\n", w, h);
  for (int j = 0; j < REF_PARTS; j++) {
    double ms = median(runs[j], reps);
    fprintf(stderr, "  %-48s %7.2f ms", ref_part_name[j], ms);
    if (flops[j] > 0) fprintf(stderr, "  %6.1f GFLOP/s", flops[j] * npos / ms * 1e-6);
    fprintf(stderr, "\n");
  }
  fprintf(stderr, "  %-48s %7.2f ms\n", "total", median(total, reps));
  omp_set_num_threads(nt);
  ref_free(&R);
  free(x), free(dx), free(g), free(dg);
}

static void print_cmp(const char *key, const cmp_result *o) {
  printf("\"%s\": {\"old_fwd_ms\": %.2f, \"new_fwd_ms\": %.2f, \"fwd_speedup\": %.2f, "
         "\"old_fwd_bwd_ms\": %.2f, \"new_fwd_bwd_ms\": %.2f, \"fwd_bwd_speedup\": %.2f, "
         "\"fwd_bwd_speedup_cpu_time\": %.2f, "
         "\"old_fit_step_ms\": %.2f, \"new_fit_step_ms\": %.2f, \"fit_step_speedup\": %.2f, "
         "\"gram_max_rel_diff\": %.2e, \"grad_max_rel_diff\": %.2e, "
         "\"gram_max_elementwise_rel_diff\": %.2e, \"grad_max_elementwise_rel_diff\": %.2e}",
         key, o->old_fwd, o->new_fwd, o->fwd_x, o->old_fb, o->new_fb, o->fb_x, o->cpu_fb_x,
         o->old_fit, o->new_fit, o->fit_x, o->gram_nw, o->grad_nw, o->gram_ew, o->grad_ew);
}

static const int vgg_cfg[] = {64,  64,  0,   128, 128, 0,   256, 256, 256, 256, 0,
                              512, 512, 512, 512, 0,   512, 512, 512, 512, 0};
#define VGG_N ((int)(sizeof vgg_cfg / sizeof vgg_cfg[0]))

/* Random He-initialised VGG-19 weights in a safetensors file. */
static void write_vgg19(const char *path) {
  const char *names[32];
  int ndims[32];
  const int64_t *shapes[32];
  const float *data[32];
  int64_t shp[32][4];
  char nm[32][40];
  float *bufs[32];
  int n = 0, idx = 0, c = 3;
  wv_rng r;
  wv_rng_seed(&r, 5);
  for (int i = 0; i < VGG_N; i++) {
    if (!vgg_cfg[i]) {
      idx++;
      continue;
    }
    int oc = vgg_cfg[i];
    for (int wb = 0; wb < 2; wb++) {
      size_t cnt = wb ? (size_t)oc : (size_t)oc * c * 9;
      bufs[n] = malloc(sizeof(float) * cnt);
      float lim = wb ? 0.01f : sqrtf(6.0f / (9.0f * c)); /* uniform with variance 2 / fan-in */
      wv_rng_fill_uniform(&r, bufs[n], cnt, -lim, lim);
      snprintf(nm[n], sizeof nm[n], "features.%d.%s", idx, wb ? "bias" : "weight");
      names[n] = nm[n];
      ndims[n] = wb ? 1 : 4;
      shp[n][0] = oc, shp[n][1] = c, shp[n][2] = 3, shp[n][3] = 3;
      shapes[n] = shp[n];
      data[n] = bufs[n];
      n++;
    }
    c = oc;
    idx += 2;
  }
  wv_error e;
  if (wv_st_write_f32(path, n, names, ndims, shapes, data, &e)) die(&e);
  for (int i = 0; i < n; i++) free(bufs[i]);
}

/* VGG-19's 16 convolutions at the sizes a w x h image gives them, forward and
 * backward to the input (what the descriptor's gradient needs). Each repetition times
 * one pass over all layers and, right after, the plain sgemm, so that both see the
 * same machine (a shared 2-core VM drifts); medians of both are returned. */
static double vgg_conv_gflops(int w, int h, int reps, double *fwd_gf, double *bwd_gf,
                              double *sgemm_gf) {
  typedef struct {
    wv_nn_conv2d cv;
    float *x, *y, *wt, *dx, *s;
  } layer;
  layer L[16];
  int nl = 0, c = 3;
  double flops = 0;
  wv_rng r;
  wv_rng_seed(&r, 6);
  for (int i = 0; i < VGG_N; i++) {
    if (!vgg_cfg[i]) {
      w /= 2, h /= 2;
      continue;
    }
    layer *l = &L[nl++];
    int oc = vgg_cfg[i];
    wv_error e;
    if (wv_nn_conv2d_init(&l->cv, 1, c, h, w, oc, 3, 1, 1, &e)) die(&e);
    size_t nx = (size_t)c * h * w, ny = (size_t)oc * h * w, nw = (size_t)oc * c * 9;
    l->x = malloc(sizeof(float) * nx), l->y = malloc(sizeof(float) * ny);
    l->wt = malloc(sizeof(float) * nw), l->dx = calloc(nx, sizeof(float));
    l->s = malloc(sizeof(float) * wv_nn_conv2d_scratch_floats(&l->cv));
    wv_rng_fill_uniform(&r, l->x, nx, 0, 1);
    wv_rng_fill_uniform(&r, l->wt, nw, -0.1f, 0.1f);
    flops += 2.0 * oc * c * 9.0 * h * w;
    c = oc;
  }
  double tf[16], tb[16], ts[16];
  for (int k = 0; k <= reps; k++) {
    double f = 0, b = 0;
    for (int i = 0; i < nl; i++) {
      double t0 = now_ms();
      wv_nn_conv2d_forward(&L[i].cv, L[i].x, L[i].wt, NULL, L[i].y, L[i].s);
      double t1 = now_ms();
      wv_nn_conv2d_backward(&L[i].cv, L[i].x, L[i].wt, L[i].y, L[i].dx, NULL, NULL, L[i].s);
      f += t1 - t0, b += now_ms() - t1;
    }
    double sg = sgemm_once();
    if (k) tf[k - 1] = f, tb[k - 1] = b, ts[k - 1] = sg; /* the first pass warms up */
  }
  for (int i = 0; i < nl; i++) free(L[i].x), free(L[i].y), free(L[i].wt), free(L[i].dx), free(L[i].s);
  double mf = median(tf, reps), mb = median(tb, reps);
  *fwd_gf = flops / mf * 1e-6;
  *bwd_gf = flops / mb * 1e-6;
  *sgemm_gf = median(ts, reps);
  return 2 * flops / (mf + mb) * 1e-6;
}

int main(int argc, char **argv) {
  int quick = 0, default_only = 0, profile = 0;
  for (int i = 1; i < argc; i++) {
    if (!strcmp(argv[i], "--quick")) quick = 1; /* fewer repetitions */
    else if (!strcmp(argv[i], "--default-only")) default_only = 1;
    else if (!strcmp(argv[i], "--profile-former")) profile = 1;
    else {
      fprintf(stderr, "usage: bench_descriptor [--quick] [--default-only] [--profile-former]\n");
      return 2;
    }
  }
  int reps = quick ? 3 : 7, vreps = quick ? 1 : 3, creps = quick ? 5 : 11;
  wv_error e;
  double load = -1; /* what else runs on the machine: the 1-minute load average */
  FILE *lf = fopen("/proc/loadavg", "r");
  if (lf) {
    if (fscanf(lf, "%lf", &load) != 1) load = -1;
    fclose(lf);
  }

  /* The default descriptor against the former path, in the same process. */
  wv_descriptor *d;
  if (wv_descriptor_create_default(&d, &e)) die(&e);
  if (profile) {
    profile_former(d, 800, 300, quick ? 3 : 7);
    wv_descriptor_free(d);
    return 0;
  }
  static const char *kname[] = {"baseline", "avx2", "avx512"};
  int kernel = wv_descriptor_default_kernel(d, -1);
  cmp_result c800, c512, c800_1;
  compare_default(d, 800, 300, creps, 3, &c800);
  compare_default(d, 512, 512, creps, 3, &c512);
  int nt = omp_get_max_threads();
  omp_set_num_threads(1);
  compare_default(d, 800, 300, creps, 1, &c800_1);
  omp_set_num_threads(nt);
  double dflo, dbls, dfhi, dbhi;
  time_desc(d, 400, 150, reps, &dflo, &dbls);
  time_desc(d, 800, 300, reps, &dfhi, &dbhi);
  size_t dsize = wv_descriptor_size(d);
  wv_descriptor_free(d);

  printf("{\"threads\": %d, \"load_average_1min\": %.2f, \"default_kernel\": \"%s\", "
         "\"default_size\": %zu, ",
         nt, load, kname[kernel], dsize);
  print_cmp("default_vs_former_800x300", &c800);
  printf(", ");
  print_cmp("default_vs_former_512x512", &c512);
  printf(", ");
  print_cmp("default_vs_former_800x300_1_thread", &c800_1);
  printf(", \"default_fwd_ms_400x150\": %.2f, \"default_fwd_bwd_ms_400x150\": %.2f, "
         "\"default_fwd_ms_800x300\": %.2f, \"default_fwd_bwd_ms_800x300\": %.2f",
         dflo, dbls, dfhi, dbhi);
  if (default_only) {
    printf("}\n");
    return 0;
  }

  sg_a = malloc(sizeof(float) * SG_N * SG_N), sg_b = malloc(sizeof(float) * SG_N * SG_N);
  sg_c = malloc(sizeof(float) * SG_N * SG_N);
  wv_rng r;
  wv_rng_seed(&r, 1);
  wv_rng_fill_uniform(&r, sg_a, (size_t)SG_N * SG_N, -1, 1);
  wv_rng_fill_uniform(&r, sg_b, (size_t)SG_N * SG_N, -1, 1);
  double t1[16], t2[16];
  sgemm_once(), nn_sgemm_once(); /* warm up */
  for (int i = 0; i < 5; i++) t1[i] = sgemm_once(), t2[i] = nn_sgemm_once();
  double sg = median(t1, 5), nsg = median(t2, 5);
  fprintf(stderr, "sgemm 2048^3: OpenBLAS threads %.1f GFLOP/s, wv_nn_sgemm %.1f GFLOP/s\n", sg, nsg);

  const char *path = "bench_vgg19_random.safetensors";
  write_vgg19(path);
  if (wv_descriptor_create_vgg19(path, &d, &e)) die(&e);
  remove(path);
  double vflo, vblo, vfhi, vbhi;
  time_desc(d, 400, 150, vreps, &vflo, &vblo);
  time_desc(d, 800, 300, vreps, &vfhi, &vbhi);
  wv_descriptor_free(d);
  double cf, cb, sg2, cg = vgg_conv_gflops(400, 150, quick ? 3 : 9, &cf, &cb, &sg2);
  fprintf(stderr, "VGG-19 convolutions at 400x150: forward %.1f, backward %.1f, overall %.1f GFLOP/s; "
          "sgemm measured alongside %.1f GFLOP/s (%.0f%%)\n", cf, cb, cg, sg2, 100 * cg / sg2);
  sg = sg2;

  printf(", \"vgg19_fwd_ms_400x150\": %.1f, \"vgg19_fwd_bwd_ms_400x150\": %.1f, "
         "\"vgg19_fwd_ms_800x300\": %.1f, \"vgg19_fwd_bwd_ms_800x300\": %.1f, "
         "\"vgg19_conv_fwd_gflops\": %.1f, \"vgg19_conv_bwd_gflops\": %.1f, "
         "\"vgg19_conv_gflops\": %.1f, \"sgemm_gflops\": %.1f, \"nn_sgemm_gflops\": %.1f, "
         "\"vgg19_conv_fraction_of_sgemm\": %.3f}\n",
         vflo, vblo, vfhi, vbhi, cf, cb, cg, sg, nsg, cg / sg);
  free(sg_a), free(sg_b), free(sg_c);
  return 0;
}
