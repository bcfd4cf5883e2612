/* Powers of many values at once (util/vmath.h). On x86-64 with
 * GCC or Clang the calls go to libmvec's functions for the widest vectors the CPU
 * runs. Their names follow the x86-64 vector function ABI: _ZGV, the ISA's letter
 * (b, d, e: SSE, AVX2, AVX-512), N, the lanes, a v per vector argument. Elsewhere,
 * libm's scalar functions. */
#include "util/vmath.h"

#include <math.h>

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__)) && !defined(WOVEN_NO_MVEC)
#include <immintrin.h>

#define AVX2 __attribute__((target("avx2,fma")))
#define AVX512 __attribute__((target("avx512f,avx512dq")))
__m128 _ZGVbN4vv_powf(__m128 x, __m128 y);
__m128d _ZGVbN2vv_pow(__m128d x, __m128d y);
AVX2 __m256 _ZGVdN8vv_powf(__m256 x, __m256 y);
AVX2 __m256d _ZGVdN4vv_pow(__m256d x, __m256d y);
AVX512 __m512 _ZGVeN16vv_powf(__m512 x, __m512 y);
AVX512 __m512d _ZGVeN8vv_pow(__m512d x, __m512d y);

/* 2: AVX-512, 1: AVX2, 0: SSE (every x86-64). The features libmvec's own versions need. */
static int isa(void) {
  __builtin_cpu_init();
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq")) return 2;
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) return 1;
  return 0;
}

/* Each function maps its values a vector at a time; the last values that do not fill a
 * vector are loaded and stored under a mask (the masked-off lanes compute on zeros, and
 * their results are dropped). No vector lives in memory the code declares: a sanitizer's
 * stack frames need not keep a 64-byte alignment. */
AVX512 static void powf_e(const float *x, float e, float *y, int n) {
  __m512 ve = _mm512_set1_ps(e);
  for (int i = 0; i < n; i += 16) {
    __mmask16 k = n - i >= 16 ? (__mmask16)0xffff : (__mmask16)((1u << (n - i)) - 1);
    _mm512_mask_storeu_ps(y + i, k, _ZGVeN16vv_powf(_mm512_maskz_loadu_ps(k, x + i), ve));
  }
}
AVX512 static void pow_e(const double *x, double e, double *y, int n) {
  __m512d ve = _mm512_set1_pd(e);
  for (int i = 0; i < n; i += 8) {
    __mmask8 k = n - i >= 8 ? (__mmask8)0xff : (__mmask8)((1u << (n - i)) - 1);
    _mm512_mask_storeu_pd(y + i, k, _ZGVeN8vv_pow(_mm512_maskz_loadu_pd(k, x + i), ve));
  }
}

/* AVX2's masks: lane j on where j < m (m the values left). */
AVX2 static __m256i mask8(int m) {
  return _mm256_cmpgt_epi32(_mm256_set1_epi32(m), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
}
AVX2 static __m256i mask4(int m) {
  return _mm256_cmpgt_epi64(_mm256_set1_epi64x(m), _mm256_setr_epi64x(0, 1, 2, 3));
}
AVX2 static void powf_d(const float *x, float e, float *y, int n) {
  __m256 ve = _mm256_set1_ps(e);
  for (int i = 0; i < n; i += 8) {
    __m256i k = mask8(n - i);
    _mm256_maskstore_ps(y + i, k, _ZGVdN8vv_powf(_mm256_maskload_ps(x + i, k), ve));
  }
}
AVX2 static void pow_d(const double *x, double e, double *y, int n) {
  __m256d ve = _mm256_set1_pd(e);
  for (int i = 0; i < n; i += 4) {
    __m256i k = mask4(n - i);
    _mm256_maskstore_pd(y + i, k, _ZGVdN4vv_pow(_mm256_maskload_pd(x + i, k), ve));
  }
}

/* SSE has no masked loads: the rest is made lane by lane in registers. */
static __m128 load4f(const float *x, int m) {
  return _mm_setr_ps(x[0], m > 1 ? x[1] : 0.0f, m > 2 ? x[2] : 0.0f, m > 3 ? x[3] : 0.0f);
}
static void store4f(float *y, int m, __m128 v) {
  y[0] = _mm_cvtss_f32(v);
  if (m > 1) y[1] = _mm_cvtss_f32(_mm_shuffle_ps(v, v, 1));
  if (m > 2) y[2] = _mm_cvtss_f32(_mm_shuffle_ps(v, v, 2));
  if (m > 3) y[3] = _mm_cvtss_f32(_mm_shuffle_ps(v, v, 3));
}
static __m128d load2d(const double *x, int m) { return _mm_setr_pd(x[0], m > 1 ? x[1] : 0.0); }
static void store2d(double *y, int m, __m128d v) {
  _mm_storel_pd(y, v);
  if (m > 1) _mm_storeh_pd(y + 1, v);
}
static void powf_b(const float *x, float e, float *y, int n) {
  __m128 ve = _mm_set1_ps(e);
  for (int i = 0; i < n; i += 4) store4f(y + i, n - i, _ZGVbN4vv_powf(load4f(x + i, n - i), ve));
}
static void pow_b(const double *x, double e, double *y, int n) {
  __m128d ve = _mm_set1_pd(e);
  for (int i = 0; i < n; i += 2) store2d(y + i, n - i, _ZGVbN2vv_pow(load2d(x + i, n - i), ve));
}

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
#else
void wv_powf_n(const float *x, float e, float *y, int n) {
  for (int i = 0; i < n; i++) y[i] = powf(x[i], e);
}
void wv_pow_n(const double *x, double e, double *y, int n) {
  for (int i = 0; i < n; i++) y[i] = pow(x[i], e);
}
#endif
