/* Ray casting against the triangle meshes of a scene with Embree 3: closest hit
 * and occlusion queries. Internal to the library (the mesh renderer's). */
#ifndef WOVEN_TRACER_H
#define WOVEN_TRACER_H

#include <stddef.h>

#include "woven/error.h"
#include "woven/mesh.h"

typedef struct wv_tracer wv_tracer;

typedef struct {
  float t;       /* distance along the (unit) ray direction */
  float b1, b2;  /* barycentrics of vertices 1 and 2 of the triangle */
  int geom;      /* index of the mesh in the list given to wv_tracer_create */
  int prim;      /* triangle index in that mesh */
} wv_trace_hit;

/* Builds the acceleration structure over n meshes (borrowed only during the call).
 * Embree's allocations are counted against limit_bytes (0: no limit): a scene
 * above it is refused with WV_ERR_NOMEM. threads: 0 = all cores. */
wv_status wv_tracer_create(const wv_mesh *const *meshes, int n, int threads, size_t limit_bytes, wv_tracer **out,
                           wv_error *err);
void wv_tracer_free(wv_tracer *t);

/* Closest hits of n rays from o along d[j] (0 < t): got[j] = 0 on a miss, else
 * 1 and hit[j]. Traced together (Embree's coherent packets of 16): for rays that start
 * together and diverge little, camera rays. Returns the number of hits.
 * Thread-safe. */
int wv_tracer_intersect_from(const wv_tracer *t, const float o[3], const float (*d)[3], int n, wv_trace_hit *hit,
                             int *got);
/* Closest hits of n rays from o[j] along d[j] (0 < t), traced together (one
 * Embree stream): got[j] and hit[j] as wv_tracer_intersect_from gives them.
 * Returns the number of hits. Thread-safe. */
int wv_tracer_intersect_n(const wv_tracer *t, const float (*o)[3], const float (*d)[3], int n, wv_trace_hit *hit,
                          int *got);
/* occ[j] = wv_tracer_occluded(t, o[j], d[j], 0, tmax[j]) for n rays traced
 * together (one Embree stream). Thread-safe. */
void wv_tracer_occluded_n(const wv_tracer *t, const float (*o)[3], const float (*d)[3], const float *tmax, int n,
                          int *occ);
/* 1 when anything lies between tmin and tmax. Thread-safe. */
int wv_tracer_occluded(const wv_tracer *t, const float o[3], const float d[3], float tmin, float tmax);

#endif
