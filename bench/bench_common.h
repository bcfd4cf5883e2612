/* Small helpers shared by the benchmarks: wall time and medians. */
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
#endif
