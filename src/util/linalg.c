/* Small dense linear algebra (linalg.h). */
#include "util/linalg.h"

#include <math.h>

int wv_solve_spd(double *m, double *b, int n) {
  for (int j = 0; j < n; j++) {
    double s = m[j * n + j];
    for (int k = 0; k < j; k++) s -= m[j * n + k] * m[j * n + k];
    if (!(s > 0)) return 0;
    m[j * n + j] = sqrt(s);
    for (int i = j + 1; i < n; i++) {
      double t = m[i * n + j];
      for (int k = 0; k < j; k++) t -= m[i * n + k] * m[j * n + k];
      m[i * n + j] = t / m[j * n + j];
    }
  }
  for (int i = 0; i < n; i++) { /* L y = b */
    for (int k = 0; k < i; k++) b[i] -= m[i * n + k] * b[k];
    b[i] /= m[i * n + i];
  }
  for (int i = n - 1; i >= 0; i--) { /* L^T x = y */
    for (int k = i + 1; k < n; k++) b[i] -= m[k * n + i] * b[k];
    b[i] /= m[i * n + i];
  }
  return 1;
}
