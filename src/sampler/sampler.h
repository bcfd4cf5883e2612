/* The pixel sampler: correlated multi-jittered sample positions, scalar
 * (wv_sample_at_f) and 8-wide (wv_sample_at_8) from one template
 * (sampler/cmj_impl.h), and the per-pixel state they share. Every position
 * is a hash of (pixel, sample, seed). Internal to the library. */
#ifndef WOVEN_SAMPLER_H
#define WOVEN_SAMPLER_H

#include <math.h>
#include <stdint.h>

#include "kernel/lanes.h"
#include "util/hash.h"

#define WV_LANE WV_LANE_F
#include "kernel/lane_begin.h"
#include "sampler/cmj_impl.h"
#include "kernel/lane_end.h"
#define WV_LANE WV_LANE_8
#include "kernel/lane_begin.h"
#include "sampler/cmj_impl.h"
#include "kernel/lane_end.h"

/* Sample grid of a pixel: nx columns by ny rows, nx * ny = spp exactly (ny the largest
 * divisor of spp not above its square root), so that the samples cover the whole pixel: a
 * grid with more cells than samples leaves its last cells unsampled, a part of every pixel
 * that thin gaps and edges then miss (docs/measurements.md, "The sampler at any spp"). */
static inline void wv_pixel_grid(int spp, int *nx, int *ny) {
  int r = spp > 1 ? (int)sqrt((double)spp) : 1;
  while (r > 1 && (long long)r * r > spp) r--;
  while ((long long)(r + 1) * (r + 1) <= spp) r++;
  while (r > 1 && spp % r) r--;
  *ny = r;
  *nx = spp > 0 ? spp / r : 1;
}

/* The pixel's state: its hash (wv_hash2's first round) and its two permutation keys. */
static inline wv_pixel_sampler_f wv_pixel_sampler_make(int px, int py, int width, uint64_t seed) {
  wv_pixel_sampler_f ps;
  ps.hash = wv_mix64(((uint64_t)py * (uint64_t)width + (uint64_t)px) * 0x9e3779b97f4a7c15ULL + (seed ^ 0x70697865ULL));
  uint64_t keys = wv_mix64(ps.hash ^ 0x6d756c7469ULL);
  ps.keyx = (uint32_t)keys, ps.keyy = (uint32_t)(keys >> 32);
  return ps;
}

#endif
