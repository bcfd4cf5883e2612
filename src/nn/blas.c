/* sgemm split over OpenMP threads, each part a single-threaded OpenBLAS call
 * (see nn.h for why OpenBLAS's own threads are not used). */
#include <cblas.h>
#include <omp.h>

#include "woven/nn.h"

void wv_nn_blas_serial(void) {
  if (openblas_get_num_threads() != 1) openblas_set_num_threads(1);
}

const char *wv_nn_blas_core(void) {
  const char *name = openblas_get_corename();
  return name && *name ? name : "unknown";
}

static void gemm1(int ta, int tb, int m, int n, int k, float alpha, const float *a, int lda,
                  const float *b, int ldb, float beta, float *c, int ldc) {
  if (m <= 0 || n <= 0) return;
  cblas_sgemm(CblasRowMajor, ta ? CblasTrans : CblasNoTrans, tb ? CblasTrans : CblasNoTrans, m, n,
              k, alpha, a, lda, b, ldb, beta, c, ldc);
}

void wv_nn_sgemm(int ta, int tb, int m, int n, int k, float alpha, const float *a, int lda,
                 const float *b, int ldb, float beta, float *c, int ldc) {
  if (m <= 0 || n <= 0) return;
  wv_nn_blas_serial();
  int nt = omp_in_parallel() ? 1 : omp_get_max_threads();
  /* Below about a million multiply-adds, a fork costs more than it saves. */
  if (nt <= 1 || (double)m * n * k < 1e6) {
    gemm1(ta, tb, m, n, k, alpha, a, lda, b, ldb, beta, c, ldc);
    return;
  }
  int split_n = n >= m;
  int len = split_n ? n : m;
  if (len < 2 * nt) {
    gemm1(ta, tb, m, n, k, alpha, a, lda, b, ldb, beta, c, ldc);
    return;
  }
#pragma omp parallel num_threads(nt)
  {
    int t = omp_get_thread_num(), nth = omp_get_num_threads();
    /* Part boundaries on multiples of 16 keep the kernels' vector tiles full. */
    int step = ((len + nth - 1) / nth + 15) / 16 * 16;
    int i0 = t * step, i1 = i0 + step < len ? i0 + step : len;
    if (i0 < i1) {
      if (split_n) {
        const float *bp = tb ? b + (size_t)i0 * ldb : b + i0;
        gemm1(ta, tb, m, i1 - i0, k, alpha, a, lda, bp, ldb, beta, c + i0, ldc);
      } else {
        const float *ap = ta ? a + i0 : a + (size_t)i0 * lda;
        gemm1(ta, tb, i1 - i0, n, k, alpha, ap, lda, b, ldb, beta, c + (size_t)i0 * ldc, ldc);
      }
    }
  }
}
