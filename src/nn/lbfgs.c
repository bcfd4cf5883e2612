/* Limited-memory BFGS directions on a box (Nocedal & Wright, Numerical Optimization, 2nd ed.,
 * algorithm 7.4, the two-loop recursion), for small problems whose every evaluation is dear:
 * Adam's steps have a fixed length, so a parameter far from its optimum takes as many steps as
 * it is far; a quasi-Newton direction scales itself by the curvature it has seen. */
#include <math.h>
#include <string.h>

#include "woven/nn.h"

void wv_nn_lbfgs_reset(wv_nn_lbfgs *q, int n) {
  memset(q, 0, sizeof *q);
  q->n = n < 0 ? 0 : n > WV_NN_LBFGS_DIM ? WV_NN_LBFGS_DIM : n;
}

void wv_nn_lbfgs_grow(wv_nn_lbfgs *q, int n) {
  n = n > WV_NN_LBFGS_DIM ? WV_NN_LBFGS_DIM : n;
  for (int k = 0; k < WV_NN_LBFGS_MEM; k++)
    for (int i = q->n; i < n; i++) q->s[k][i] = q->y[k][i] = 0;
  if (n > q->n) q->n = n;
  q->has_prev = 0, q->stuck = 0;
}

/* Free at x: inside the box, or on a bound with the descent pointing inside. */
static int is_free(double x, double g, double lo, double hi) {
  return !((x <= lo && g > 0) || (x >= hi && g < 0));
}

void wv_nn_lbfgs_reject(wv_nn_lbfgs *q) {
  if (q->count > 0) { /* curvature out of date: start again from the steepest descent */
    wv_nn_lbfgs_reset(q, q->n);
    return;
  }
  q->stuck = 1; /* the steepest descent itself was turned down at x_prev */
}

int wv_nn_lbfgs_direction(wv_nn_lbfgs *q, const double *x, double f, const double *g, double lo, double hi,
                          double *d) {
  int n = q->n;
  if (q->stuck && q->has_prev && !memcmp(x, q->x_prev, sizeof(double) * (size_t)n)) {
    memset(d, 0, sizeof(double) * (size_t)n);
    return -1;
  }
  q->stuck = 0;
  if (q->has_prev) {
    /* The last step's pair, kept where the curvature is positive and the two gradients tell
     * the step's change of f: their mean along the step (the trapezoid rule, exact on a
     * quadratic) within half of it. A gradient that holds only in a sliver of the step (a
     * slope without bound at a face of the box) would otherwise set the scale of every step
     * after it. */
    double s[WV_NN_LBFGS_DIM], y[WV_NN_LBFGS_DIM], sy = 0, ss = 0, yy = 0, trap = 0;
    for (int i = 0; i < n; i++) {
      s[i] = x[i] - q->x_prev[i], y[i] = g[i] - q->g_prev[i];
      sy += s[i] * y[i], ss += s[i] * s[i], yy += y[i] * y[i], trap += 0.5 * (g[i] + q->g_prev[i]) * s[i];
    }
    int told = fabs((f - q->f_prev) - trap) <= 0.5 * fabs(trap);
    if (told && isfinite(sy) && sy > 1e-10 * sqrt(ss * yy) && sy > 0) {
      if (q->count == WV_NN_LBFGS_MEM) { /* the oldest pair out */
        memmove(q->s[0], q->s[1], sizeof q->s[0] * (WV_NN_LBFGS_MEM - 1));
        memmove(q->y[0], q->y[1], sizeof q->y[0] * (WV_NN_LBFGS_MEM - 1));
        q->count--;
      }
      memcpy(q->s[q->count], s, sizeof s), memcpy(q->y[q->count], y, sizeof y);
      q->count++;
    }
  }
  memcpy(q->x_prev, x, sizeof(double) * (size_t)n), memcpy(q->g_prev, g, sizeof(double) * (size_t)n);
  q->f_prev = f, q->has_prev = 1;
  /* the two loops over the free coordinates (those held on a bound take no part) */
  double r[WV_NN_LBFGS_DIM], a[WV_NN_LBFGS_MEM];
  int freec[WV_NN_LBFGS_DIM];
  for (int i = 0; i < n; i++) {
    freec[i] = is_free(x[i], g[i], lo, hi);
    r[i] = freec[i] ? g[i] : 0;
  }
  for (int k = q->count - 1; k >= 0; k--) {
    double sy = 0, sr = 0;
    for (int i = 0; i < n; i++)
      if (freec[i]) sy += q->s[k][i] * q->y[k][i], sr += q->s[k][i] * r[i];
    a[k] = sy > 0 ? sr / sy : 0;
    for (int i = 0; i < n; i++)
      if (freec[i]) r[i] -= a[k] * q->y[k][i];
  }
  if (q->count > 0) { /* the initial inverse Hessian: the last pair's scale */
    const double *s = q->s[q->count - 1], *y = q->y[q->count - 1];
    double sy = 0, yy = 0;
    for (int i = 0; i < n; i++)
      if (freec[i]) sy += s[i] * y[i], yy += y[i] * y[i];
    double gamma = sy > 0 && yy > 0 ? sy / yy : 1;
    for (int i = 0; i < n; i++) r[i] *= gamma;
  }
  for (int k = 0; k < q->count; k++) {
    double sy = 0, yr = 0;
    for (int i = 0; i < n; i++)
      if (freec[i]) sy += q->s[k][i] * q->y[k][i], yr += q->y[k][i] * r[i];
    double b = sy > 0 ? yr / sy : 0;
    for (int i = 0; i < n; i++)
      if (freec[i]) r[i] += q->s[k][i] * (a[k] - b);
  }
  double gd = 0;
  for (int i = 0; i < n; i++) d[i] = -r[i], gd += g[i] * d[i];
  if (!(gd < 0)) { /* not a descent direction (curvature pairs out of date): steepest descent */
    q->count = 0;
    for (int i = 0; i < n; i++) d[i] = freec[i] ? -g[i] : 0;
  }
  return q->count;
}
