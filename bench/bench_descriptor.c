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

/* Plain OpenBLAS sgemm on square matrices with OpenBLAS's own threads. */
static double sgemm_gflops(int n, int reps) {
  float *a = malloc(sizeof(float) * n * n), *b = malloc(sizeof(float) * n * n),
        *c = malloc(sizeof(float) * n * n);
  wv_rng r;
  wv_rng_seed(&r, 1);
  wv_rng_fill_uniform(&r, a, (size_t)n * n, -1, 1);
  wv_rng_fill_uniform(&r, b, (size_t)n * n, -1, 1);
  openblas_set_num_threads(omp_get_max_threads());
  double t[16];
  for (int i = 0; i <= reps; i++) {
    double t0 = now_ms();
    cblas_sgemm(CblasRowMajor, CblasNoTrans, CblasNoTrans, n, n, n, 1, a, n, b, n, 0, c, n);
    if (i) t[i - 1] = now_ms() - t0; /* the first call warms up */
  }
  wv_nn_blas_serial();
  free(a), free(b), free(c);
  return 2.0 * n * n * n / median(t, reps) * 1e-6;
}

static double nn_sgemm_gflops(int n, int reps) {
  float *a = malloc(sizeof(float) * n * n), *b = malloc(sizeof(float) * n * n),
        *c = malloc(sizeof(float) * n * n);
  wv_rng r;
  wv_rng_seed(&r, 2);
  wv_rng_fill_uniform(&r, a, (size_t)n * n, -1, 1);
  wv_rng_fill_uniform(&r, b, (size_t)n * n, -1, 1);
  double t[16];
  for (int i = 0; i <= reps; i++) {
    double t0 = now_ms();
    wv_nn_sgemm(0, 0, n, n, n, 1, a, n, b, n, 0, c, n);
    if (i) t[i - 1] = now_ms() - t0;
  }
  free(a), free(b), free(c);
  return 2.0 * n * n * n / median(t, reps) * 1e-6;
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
 * backward to the input (what the descriptor's gradient needs): GFLOP/s overall. */
static double vgg_conv_gflops(int w, int h, int reps, double *fwd_gf, double *bwd_gf) {
  int c = 3;
  double flops = 0, tf_all = 0, tb_all = 0;
  wv_rng r;
  wv_rng_seed(&r, 6);
  for (int i = 0; i < VGG_N; i++) {
    if (!vgg_cfg[i]) {
      w /= 2, h /= 2;
      continue;
    }
    int oc = vgg_cfg[i];
    wv_nn_conv2d cv;
    wv_error e;
    if (wv_nn_conv2d_init(&cv, 1, c, h, w, oc, 3, 1, 1, &e)) die(&e);
    size_t nx = (size_t)c * h * w, ny = (size_t)oc * h * w, nw = (size_t)oc * c * 9;
    float *x = malloc(sizeof(float) * nx), *y = malloc(sizeof(float) * ny),
          *wt = malloc(sizeof(float) * nw), *dx = calloc(nx, sizeof(float)),
          *s = malloc(sizeof(float) * wv_nn_conv2d_scratch_floats(&cv, 0));
    wv_rng_fill_uniform(&r, x, nx, 0, 1);
    wv_rng_fill_uniform(&r, wt, nw, -0.1f, 0.1f);
    double tf[16], tb[16];
    for (int k = 0; k <= reps; k++) {
      double t0 = now_ms();
      wv_nn_conv2d_forward(&cv, x, wt, NULL, y, s);
      double t1 = now_ms();
      wv_nn_conv2d_backward(&cv, x, wt, y, dx, NULL, NULL, s);
      double t2 = now_ms();
      if (k) tf[k - 1] = t1 - t0, tb[k - 1] = t2 - t1;
    }
    tf_all += median(tf, reps);
    tb_all += median(tb, reps);
    flops += 2.0 * oc * c * 9.0 * h * w;
    free(x), free(y), free(wt), free(dx), free(s);
    c = oc;
  }
  *fwd_gf = flops / tf_all * 1e-6;
  *bwd_gf = flops / tb_all * 1e-6;
  return 2 * flops / (tf_all + tb_all) * 1e-6;
}

int main(int argc, char **argv) {
  int quick = argc > 1 && !strcmp(argv[1], "--quick"); /* fewer repetitions */
  int reps = quick ? 3 : 7, vreps = quick ? 1 : 3;
  wv_error e;
  double sg = sgemm_gflops(2048, quick ? 3 : 5);
  double nsg = nn_sgemm_gflops(2048, quick ? 3 : 5);
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
  double cf, cb, cg = vgg_conv_gflops(400, 150, vreps, &cf, &cb);
  fprintf(stderr, "VGG-19 convolutions at 400x150: forward %.1f, backward %.1f, overall %.1f GFLOP/s (%.0f%% of sgemm)\n",
          cf, cb, cg, 100 * cg / sg);

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
  return 0;
}
