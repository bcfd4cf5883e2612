/* Stateless hashing for deterministic randomness: every random choice in the
 * renderer is a pure function of (what, where, seed), so renders are
 * reproducible and independent of thread scheduling. */
#ifndef WOVEN_HASH_H
#define WOVEN_HASH_H
#include <stdint.h>

/* SplitMix64 finaliser (Steele, Lea, Flood 2014): a bijective 64-bit mixer.
 * The bodies are macros so that kernel/lanes.h applies the same text to eight
 * 64-bit lanes. */
#define WV_MIX64_BODY(z)                                  \
  ((z) = ((z) ^ ((z) >> 30)) * 0xbf58476d1ce4e5b9ULL,     \
   (z) = ((z) ^ ((z) >> 27)) * 0x94d049bb133111ebULL, (z) ^ ((z) >> 31))
#define WV_HASH2_BODY(mix, a, b, seed) mix(mix((a) * 0x9e3779b97f4a7c15ULL + (seed)) ^ ((b) * 0xc2b2ae3d27d4eb4fULL))
static inline uint64_t wv_mix64(uint64_t z) { return WV_MIX64_BODY(z); }
static inline uint64_t wv_hash4(uint64_t a, uint64_t b, uint64_t c, uint64_t d) {
  uint64_t h = wv_mix64(a + 0x9e3779b97f4a7c15ULL);
  h = wv_mix64(h ^ (b + 0x9e3779b97f4a7c15ULL));
  h = wv_mix64(h ^ (c + 0x9e3779b97f4a7c15ULL));
  return wv_mix64(h ^ (d + 0x9e3779b97f4a7c15ULL));
}
/* Cheaper two-key hash for the renderer's inner loop (two mixing rounds). */
static inline uint64_t wv_hash2(uint64_t a, uint64_t b, uint64_t seed) { return WV_HASH2_BODY(wv_mix64, a, b, seed); }
/* Uniform float in [0,1) from the top 24 bits. */
static inline float wv_u01(uint64_t h) { return (float)(h >> 40) * (1.0f / 16777216.0f); }
/* Uniform double in [0,1) from the top 53 bits. */
static inline double wv_u01d(uint64_t h) { return (double)(h >> 11) * (1.0 / 9007199254740992.0); }

#endif
