/* Powers and exponentials of many values at once (util/vmath.h). On x86-64 with
 * GCC or Clang the calls go to libmvec's functions for the widest vectors the CPU
 * runs. Their names follow the x86-64 vector function ABI: _ZGV, the ISA's letter
 * (b, d, e: SSE, AVX2, AVX-512), N, the lanes, a v per vector argument. A call's last
 * values that do not fill a vector go through a padded copy. Elsewhere, libm's scalar
 * functions. */
#include "util/vmath.h"

#include <math.h>
#include <string.h>

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__)) && !defined(WOVEN_NO_MVEC)
#include <immintrin.h>

#define AVX2 __attribute__((target("avx2,fma")))
#define AVX512 __attribute__((target("avx512f,avx512dq")))
__m128 _ZGVbN4vv_powf(__m128 x, __m128 y);
__m128d _ZGVbN2vv_pow(__m128d x, __m128d y);
__m128d _ZGVbN2v_exp(__m128d x);
AVX2 __m256 _ZGVdN8vv_powf(__m256 x, __m256 y);
AVX2 __m256d _ZGVdN4vv_pow(__m256d x, __m256d y);
AVX2 __m256d _ZGVdN4v_exp(__m256d x);
AVX512 __m512 _ZGVeN16vv_powf(__m512 x, __m512 y);
AVX512 __m512d _ZGVeN8vv_pow(__m512d x, __m512d y);
AVX512 __m512d _ZGVeN8v_exp(__m512d x);

/* 2: AVX-512, 1: AVX2, 0: SSE (every x86-64). The features libmvec's own versions need. */
static int isa(void) {
  __builtin_cpu_init();
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq")) return 2;
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) return 1;
  return 0;
}

/* A function over n values in vectors of L: whole vectors in place, the rest through a
 * copy padded with x[0]. VCALL(p) maps the L values at p to the vector result stored
 * at q. */
#define VMAP(L, T, VCALL)                                                   \
  int i = 0;                                                                \
  for (; i + (L) <= n; i += (L)) VCALL(x + i, y + i);                       \
  if (i < n) {                                                              \
    T a[L], b[L];                                                           \
    for (int k = 0; k < (L); k++) a[k] = i + k < n ? x[i + k] : x[0];       \
    VCALL(a, b);                                                            \
    memcpy(y + i, b, sizeof(T) * (size_t)(n - i));                          \
  }

#define POWF_E(p, q) _mm512_storeu_ps(q, _ZGVeN16vv_powf(_mm512_loadu_ps(p), ve))
#define POWF_D(p, q) _mm256_storeu_ps(q, _ZGVdN8vv_powf(_mm256_loadu_ps(p), ve))
#define POWF_B(p, q) _mm_storeu_ps(q, _ZGVbN4vv_powf(_mm_loadu_ps(p), ve))
#define POW_E(p, q) _mm512_storeu_pd(q, _ZGVeN8vv_pow(_mm512_loadu_pd(p), ve))
#define POW_D(p, q) _mm256_storeu_pd(q, _ZGVdN4vv_pow(_mm256_loadu_pd(p), ve))
#define POW_B(p, q) _mm_storeu_pd(q, _ZGVbN2vv_pow(_mm_loadu_pd(p), ve))
#define EXP_E(p, q) _mm512_storeu_pd(q, _ZGVeN8v_exp(_mm512_loadu_pd(p)))
#define EXP_D(p, q) _mm256_storeu_pd(q, _ZGVdN4v_exp(_mm256_loadu_pd(p)))
#define EXP_B(p, q) _mm_storeu_pd(q, _ZGVbN2v_exp(_mm_loadu_pd(p)))

AVX512 static void powf_e(const float *x, float e, float *y, int n) {
  __m512 ve = _mm512_set1_ps(e);
  VMAP(16, float, POWF_E)
}
AVX2 static void powf_d(const float *x, float e, float *y, int n) {
  __m256 ve = _mm256_set1_ps(e);
  VMAP(8, float, POWF_D)
}
static void powf_b(const float *x, float e, float *y, int n) {
  __m128 ve = _mm_set1_ps(e);
  VMAP(4, float, POWF_B)
}
AVX512 static void pow_e(const double *x, double e, double *y, int n) {
  __m512d ve = _mm512_set1_pd(e);
  VMAP(8, double, POW_E)
}
AVX2 static void pow_d(const double *x, double e, double *y, int n) {
  __m256d ve = _mm256_set1_pd(e);
  VMAP(4, double, POW_D)
}
static void pow_b(const double *x, double e, double *y, int n) {
  __m128d ve = _mm_set1_pd(e);
  VMAP(2, double, POW_B)
}
AVX512 static void exp_e(const double *x, double *y, int n) { VMAP(8, double, EXP_E) }
AVX2 static void exp_d(const double *x, double *y, int n) { VMAP(4, double, EXP_D) }
static void exp_b(const double *x, double *y, int n) { VMAP(2, double, EXP_B) }

void wv_powf_n(const float *x, float e, float *y, int n) {
  if (n <= 0) return;
  switch (isa()) {
    case 2: powf_e(x, e, y, n); break;
    case 1: powf_d(x, e, y, n); break;
    default: powf_b(x, e, y, n);
  }
}
void wv_pow_n(const double *x, double e, double *y, int n) {
  if (n <= 0) return;
  switch (isa()) {
    case 2: pow_e(x, e, y, n); break;
    case 1: pow_d(x, e, y, n); break;
    default: pow_b(x, e, y, n);
  }
}
void wv_exp_n(const double *x, double *y, int n) {
  if (n <= 0) return;
  switch (isa()) {
    case 2: exp_e(x, y, n); break;
    case 1: exp_d(x, y, n); break;
    default: exp_b(x, y, n);
  }
}
#else
void wv_powf_n(const float *x, float e, float *y, int n) {
  for (int i = 0; i < n; i++) y[i] = powf(x[i], e);
}
void wv_pow_n(const double *x, double e, double *y, int n) {
  for (int i = 0; i < n; i++) y[i] = pow(x[i], e);
}
void wv_exp_n(const double *x, double *y, int n) {
  for (int i = 0; i < n; i++) y[i] = exp(x[i]);
}
#endif
