/* splitmix64 (Steele, Lea & Flood, "Fast splittable pseudorandom number
 * generators", OOPSLA 2014): a Weyl sequence through a 64-bit finaliser. */
#include <math.h>

#include "woven/nn.h"

void wv_rng_seed(wv_rng *r, uint64_t seed) { r->state = seed; }

uint64_t wv_rng_u64(wv_rng *r) {
  uint64_t z = (r->state += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

float wv_rng_uniform(wv_rng *r) {
  /* 24 bits fill a float mantissa exactly, so the value is platform-independent. */
  return (float)(wv_rng_u64(r) >> 40) * (1.0f / 16777216.0f);
}

float wv_rng_normal(wv_rng *r) {
  double u1 = ((double)(wv_rng_u64(r) >> 11) + 1.0) * (1.0 / 9007199254740992.0); /* (0,1] */
  double u2 = (double)(wv_rng_u64(r) >> 11) * (1.0 / 9007199254740992.0);
  return (float)(sqrt(-2.0 * log(u1)) * cos(6.283185307179586 * u2));
}

void wv_rng_fill_uniform(wv_rng *r, float *x, size_t n, float lo, float hi) {
  for (size_t i = 0; i < n; i++) x[i] = lo + (hi - lo) * wv_rng_uniform(r);
}
