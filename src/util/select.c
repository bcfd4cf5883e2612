/* Quickselect (Hoare's FIND) with a median-of-three pivot: see select.h. */
#include "util/select.h"

static void swap(float *a, float *b) {
  float t = *a;
  *a = *b, *b = t;
}

float wv_select_float(float *a, size_t n, size_t k) {
  size_t lo = 0, hi = n - 1;
  while (hi > lo) {
    /* the median of the first, middle and last values as the pivot, moved to a[lo] */
    size_t mid = lo + (hi - lo) / 2;
    if (a[mid] < a[lo]) swap(&a[mid], &a[lo]);
    if (a[hi] < a[lo]) swap(&a[hi], &a[lo]);
    if (a[hi] < a[mid]) swap(&a[hi], &a[mid]);
    swap(&a[lo], &a[mid]);
    float p = a[lo];
    /* Hoare partition: values equal to the pivot go to both sides, so runs of equal values
     * split evenly */
    size_t i = lo, j = hi + 1;
    for (;;) {
      do i++; while (i <= hi && a[i] < p);
      do j--; while (a[j] > p);
      if (i >= j) break;
      swap(&a[i], &a[j]);
    }
    swap(&a[lo], &a[j]); /* the pivot at its place j: a[lo..j-1] <= p <= a[j+1..hi] */
    if (j == k) return a[k];
    if (k < j) hi = j - 1;
    else lo = j + 1;
  }
  return a[k];
}
