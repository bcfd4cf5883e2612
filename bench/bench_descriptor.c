/* Descriptor speed: forward and forward + backward for the default descriptor and
 * VGG-19 (random weights), VGG-19's convolutions alone, and a plain OpenBLAS sgemm
 * in the same run. Prints one JSON object on its last line (medians). */
#include <cblas.h>
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

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
  int quick = argc > 1 && !strcmp(argv[1], "--quick"); /* fewer repetitions */
  int reps = quick ? 3 : 7, vreps = quick ? 1 : 3;
  wv_error e;
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

  wv_descriptor *d;
  if (wv_descriptor_create_default(&d, &e)) die(&e);
  double dflo, dbls, dfhi, dbhi;
  time_desc(d, 400, 150, reps, &dflo, &dbls);
  time_desc(d, 800, 300, reps, &dfhi, &dbhi);
  size_t dsize = wv_descriptor_size(d);
  wv_descriptor_free(d);

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

  printf("{\"threads\": %d, \"default_size\": %zu, "
         "\"default_fwd_ms_400x150\": %.2f, \"default_fwd_bwd_ms_400x150\": %.2f, "
         "\"default_fwd_ms_800x300\": %.2f, \"default_fwd_bwd_ms_800x300\": %.2f, "
         "\"vgg19_fwd_ms_400x150\": %.1f, \"vgg19_fwd_bwd_ms_400x150\": %.1f, "
         "\"vgg19_fwd_ms_800x300\": %.1f, \"vgg19_fwd_bwd_ms_800x300\": %.1f, "
         "\"vgg19_conv_fwd_gflops\": %.1f, \"vgg19_conv_bwd_gflops\": %.1f, "
         "\"vgg19_conv_gflops\": %.1f, \"sgemm_gflops\": %.1f, \"nn_sgemm_gflops\": %.1f, "
         "\"vgg19_conv_fraction_of_sgemm\": %.3f}\n",
         omp_get_max_threads(), dsize, dflo, dbls, dfhi, dbhi, vflo, vblo, vfhi, vbhi, cf, cb, cg, sg,
         nsg, cg / sg);
  free(sg_a), free(sg_b), free(sg_c);
  return 0;
}
