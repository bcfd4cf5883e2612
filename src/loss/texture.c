/* woven: the texture loss L_g (include/woven/loss.h): the L1 distance of two Gram
 * vectors from the descriptor, and its gradient. */
#include <math.h>

#include "woven/loss.h"

double wv_loss_gram(const float *a, const float *b, size_t n, float *d) {
  double l = 0;
  for (size_t i = 0; i < n; i++) {
    float df = a[i] - b[i];
    l += fabsf(df);
    if (d) d[i] = (float)((df > 0) - (df < 0)) / (float)n;
  }
  return n ? l / (double)n : 0.0;
}
