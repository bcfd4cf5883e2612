/* woven: the texture loss L_g (include/woven/loss.h): the L1 distance of two Gram
 * vectors from the descriptor, and its gradient. */
#include <string.h>

#include "woven/loss.h"
#include "woven/nn.h"

double wv_loss_gram(const float *a, const float *b, size_t n, float *d) {
  if (d) memset(d, 0, n * sizeof *d);
  double l = wv_nn_l1(a, b, n, 1, d, 1.0f / (float)n); /* differences in float */
  return n ? l / (double)n : 0.0;
}
