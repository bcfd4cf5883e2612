/* Shared parts of the descriptors: the object, input normalisation, layer weights. */
#ifndef WOVEN_DESCRIPTOR_INTERNAL_H
#define WOVEN_DESCRIPTOR_INTERNAL_H

#include "woven/descriptor.h"

#define WV_DESC_MAX_LAYERS 8

struct wv_descriptor {
  char name[16];
  int nlayers;
  int layer_c[WV_DESC_MAX_LAYERS];
  size_t layer_off[WV_DESC_MAX_LAYERS];
  float layer_w[WV_DESC_MAX_LAYERS];
  size_t size;
  int min_side;
  /* Forward on the normalised image x (3 x h x w, planar); with dgram, also the
   * gradient of sum(dgram .* gram) into dx (3 x h x w, overwritten). With dgram,
   * gram may be NULL: the Gram matrices are then not wanted. */
  wv_status (*run)(wv_descriptor *d, const float *x, int w, int h, const float *dgram,
                   float *gram, float *dx, wv_error *err);
  void (*destroy)(void *impl);
  void *impl;
  /* Scratch of the common part. */
  int cur_w, cur_h;
  float *x, *dx, *dgram;
};

/* Allocates the object with layer sizes filled in (weights 1). */
wv_status wv_descriptor_alloc(wv_descriptor **out, const char *name, int nlayers,
                              const int *channels, wv_error *err);

/* For tests: the default descriptor's filters of pyramid level `level` (c x 3 x k x k);
 * returns the number of levels, or -1 if d is not the default descriptor. */
int wv_descriptor_default_filters(const wv_descriptor *d, int level, int *k, int *c,
                                  const float **w);

/* The default descriptor's kernels (default.c): the widest one the CPU supports runs
 * unless a test or benchmark asks for a narrower one. */
enum { WV_DESC_KERNEL_BASE = 0, WV_DESC_KERNEL_AVX2 = 1, WV_DESC_KERNEL_AVX512 = 2 };
/* With limit >= 0, selects the widest kernel the CPU runs up to `limit`; returns the
 * kernel in use, or -1 if d is not the default descriptor. */
int wv_descriptor_default_kernel(wv_descriptor *d, int limit);

#endif
