/* Powers of many values at once: glibc's vector maths library
 * (libmvec) on x86-64, libm's one value at a time elsewhere. The sensor response
 * takes two powers of every pixel's every channel, which one at a time cost about a
 * tenth of a fit's iteration. libmvec's results lie within a few units in the last
 * place of libm's. Internal to the library. */
#ifndef WOVEN_VMATH_H
#define WOVEN_VMATH_H

/* y[i] = powf(x[i], e) for i < n. */
void wv_powf_n(const float *x, float e, float *y, int n);
/* y[i] = pow(x[i], e) for i < n. */
void wv_pow_n(const double *x, double e, double *y, int n);

#endif
