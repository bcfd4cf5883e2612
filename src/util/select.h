/* Order statistics without a full sort: the k-th smallest of an array (a median, a
 * percentile) in linear expected time. */
#ifndef WOVEN_SELECT_H
#define WOVEN_SELECT_H
#include <stddef.h>

/* The k-th smallest value of a[0..n-1] (k < n, no NaN), the value a sorted copy holds at
 * index k. Reorders a: afterwards a[k] is that value, no value before it is larger and
 * none after it smaller. Deterministic (no random pivots). */
float wv_select_float(float *a, size_t n, size_t k);

#endif
