/* Small helpers shared by the benchmarks: wall time, medians, the .png files of a folder and
 * bilinear sampling of an image. */
#ifndef WOVEN_BENCH_COMMON_H
#define WOVEN_BENCH_COMMON_H
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static inline double bench_now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec + ts.tv_nsec * 1e-9;
}
/* CPU seconds used by the whole process (all threads): on a shared machine this
 * moves less with other jobs' load than wall time does. */
static inline double bench_cpu_now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec + ts.tv_nsec * 1e-9;
}
static int bench_cmp(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}
static inline double bench_median(double *v, int n) {
  qsort(v, n, sizeof *v, bench_cmp);
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}
/* The .png files of dir (at most 64), sorted by name; -1 when dir cannot be read. */
static int bench_cmp_name(const void *a, const void *b) { return strcmp((const char *)a, (const char *)b); }
static inline int bench_list_png(const char *dir, char names[64][256]) {
  DIR *dd = opendir(dir);
  if (!dd) return -1;
  int n = 0;
  for (struct dirent *e; (e = readdir(dd)) && n < 64;) {
    size_t l = strlen(e->d_name);
    if (l > 4 && !strcmp(e->d_name + l - 4, ".png")) snprintf(names[n++], 256, "%s", e->d_name);
  }
  closedir(dd);
  qsort(names, (size_t)n, 256, bench_cmp_name);
  return n;
}
#include "woven/image.h"
/* img at the pixel position (u, v), bilinearly, each channel into out; (u, v) held inside. */
static inline void bench_bilinear(const wv_image *img, double u, double v, float *out) {
  int w = img->w, h = img->h;
  u = u < 0 ? 0 : u > w - 1 ? w - 1 : u, v = v < 0 ? 0 : v > h - 1 ? h - 1 : v;
  int x0 = (int)u, y0 = (int)v, x1 = x0 + 1 < w ? x0 + 1 : x0, y1 = y0 + 1 < h ? y0 + 1 : y0;
  double fx = u - x0, fy = v - y0;
  const float *p00 = wv_image_px(img, x0, y0), *p10 = wv_image_px(img, x1, y0), *p01 = wv_image_px(img, x0, y1),
              *p11 = wv_image_px(img, x1, y1);
  for (int ch = 0; ch < img->c; ch++)
    out[ch] = (float)((1 - fy) * ((1 - fx) * p00[ch] + fx * p10[ch]) + fy * ((1 - fx) * p01[ch] + fx * p11[ch]));
}
#endif
