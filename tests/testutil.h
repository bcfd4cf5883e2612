/* Shared helpers for the cmocka tests. */
#ifndef WOVEN_TESTUTIL_H
#define WOVEN_TESTUTIL_H
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "woven/scene.h"

/* A seeded uniform generator for test inputs (64-bit LCG, the top 53 bits): tu_rng r = {seed}. */
typedef struct {
  uint64_t s;
} tu_rng;
static inline double tu_rnd(tu_rng *r) {
  r->s = r->s * 6364136223846793005ULL + 1442695040888963407ULL;
  return (double)(r->s >> 11) * (1.0 / 9007199254740992.0);
}

/* The centre w x h pixels of a preset scene (the same pixels as the full image
 * there), rendered at spp. */
void tu_centre_window(wv_scene *s, const char *preset, int w, int h, int spp);

/* A fresh empty directory under the test's working directory. */
const char *tu_tmpdir(const char *name);
#endif
