/* Embree 3 scene of triangle meshes: building it under a memory limit, and the
 * queries the integrator needs (closest hit and occlusion, for one ray or for
 * many together). */
#include "tracer/tracer.h"

#include <embree3/rtcore.h>
#include <math.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Below this many rays a stream is traced ray by ray (a stream's own cost). */
#define WV_STREAM_MIN 8

struct wv_tracer {
  RTCDevice dev;
  RTCScene scene;
  _Atomic long long bytes; /* Embree's live allocations */
  long long limit;
  char msg[256]; /* Embree's first error message */
};

static void on_error(void *user, enum RTCError code, const char *str) {
  struct wv_tracer *t = user;
  if (!t->msg[0]) snprintf(t->msg, sizeof t->msg, "Embree error %d: %s", (int)code, str ? str : "");
}

/* Refuses an allocation that would take Embree above the limit. */
static bool on_memory(void *user, ssize_t bytes, bool post) {
  struct wv_tracer *t = user;
  long long now = atomic_fetch_add(&t->bytes, (long long)bytes) + bytes;
  if (bytes > 0 && !post && t->limit > 0 && now > t->limit) {
    atomic_fetch_sub(&t->bytes, (long long)bytes);
    return false;
  }
  return true;
}

void wv_tracer_free(wv_tracer *t) {
  if (!t) return;
  if (t->scene) rtcReleaseScene(t->scene);
  if (t->dev) rtcReleaseDevice(t->dev);
  free(t);
}

wv_status wv_tracer_create(const wv_mesh *const *meshes, int n, int threads, size_t limit, wv_tracer **out,
                           wv_error *err) {
  *out = NULL;
  struct wv_tracer *t = calloc(1, sizeof *t);
  if (!t) return wv_fail(err, WV_ERR_NOMEM, "out of memory for the ray tracer");
  t->limit = (long long)limit;
  char cfg[64];
  snprintf(cfg, sizeof cfg, "threads=%d,set_affinity=0,verbose=0,hugepages=1", threads > 0 ? threads : 0);
  t->dev = rtcNewDevice(cfg);
  if (!t->dev) {
    free(t);
    return wv_fail(err, WV_ERR_INTERNAL, "cannot start Embree (error %d)", (int)rtcGetDeviceError(NULL));
  }
  rtcSetDeviceErrorFunction(t->dev, on_error, t);
  rtcSetDeviceMemoryMonitorFunction(t->dev, on_memory, t);
  /* (Embree's robust mode off: it took 4% of a render, and the few hits it changes
   * move no image beyond its noise; docs/measurements.md) */
  t->scene = rtcNewScene(t->dev);
  for (int g = 0; g < n && t->scene && !t->msg[0]; g++) {
    const wv_mesh *m = meshes[g];
    RTCGeometry geo = rtcNewGeometry(t->dev, RTC_GEOMETRY_TYPE_TRIANGLE);
    if (!geo) break;
    float *vb = rtcSetNewGeometryBuffer(geo, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                        (size_t)m->nv);
    unsigned *ib = rtcSetNewGeometryBuffer(geo, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned),
                                           (size_t)m->nt);
    if (vb && ib) {
      memcpy(vb, m->pos, (size_t)m->nv * 3 * sizeof(float));
      memcpy(ib, m->idx, (size_t)m->nt * 3 * sizeof(unsigned));
      rtcCommitGeometry(geo);
      rtcAttachGeometryByID(t->scene, geo, (unsigned)g);
    }
    rtcReleaseGeometry(geo);
  }
  if (t->scene && !t->msg[0]) rtcCommitScene(t->scene);
  enum RTCError code = rtcGetDeviceError(t->dev);
  if (!t->scene || code != RTC_ERROR_NONE || t->msg[0]) {
    wv_status st = code == RTC_ERROR_OUT_OF_MEMORY
                       ? wv_fail(err, WV_ERR_NOMEM, "the scene's meshes need more than the memory limit of %zu MB",
                                 limit >> 20)
                       : wv_fail(err, WV_ERR_INTERNAL, "building the ray tracer failed: %s",
                                 t->msg[0] ? t->msg : "unknown Embree error");
    wv_tracer_free(t);
    return st;
  }
  *out = t;
  return WV_OK;
}

static void set_ray(struct RTCRay *r, const float o[3], const float d[3], float tmin, float tmax) {
  r->org_x = o[0], r->org_y = o[1], r->org_z = o[2];
  r->dir_x = d[0], r->dir_y = d[1], r->dir_z = d[2];
  r->tnear = tmin, r->tfar = tmax;
  r->time = 0, r->mask = 0xffffffffu, r->id = 0, r->flags = 0;
}

static void to_hit(const struct RTCRayHit *rh, wv_trace_hit *hit) {
  hit->t = rh->ray.tfar;
  hit->b1 = rh->hit.u, hit->b2 = rh->hit.v;
  hit->geom = (int)rh->hit.geomID, hit->prim = (int)rh->hit.primID;
}

/* Closest hits of n rays from o + j ostride (ostride 0: one origin for all)
 * along d[j], in streams of up to 64 rays. */
static int intersect_stream(const wv_tracer *t, const float *o, size_t ostride, const float (*d)[3], int n,
                            enum RTCIntersectContextFlags flags, wv_trace_hit *hit, int *got) {
  enum { B = 64 };
  struct RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  ctx.flags = flags;
  struct RTCRayHit rh[B];
  int hits = 0;
  for (int j0 = 0; j0 < n; j0 += B) {
    int m = n - j0 < B ? n - j0 : B;
    for (int j = 0; j < m; j++) {
      set_ray(&rh[j].ray, o + (size_t)(j0 + j) * ostride, d[j0 + j], 0.0f, INFINITY);
      rh[j].hit.geomID = RTC_INVALID_GEOMETRY_ID;
      rh[j].hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    }
    if (m < WV_STREAM_MIN)
      for (int j = 0; j < m; j++) rtcIntersect1(t->scene, &ctx, &rh[j]);
    else
      rtcIntersect1M(t->scene, &ctx, rh, (unsigned)m, sizeof *rh);
    for (int j = 0; j < m; j++) {
      got[j0 + j] = rh[j].hit.geomID != RTC_INVALID_GEOMETRY_ID;
      hits += got[j0 + j];
      if (got[j0 + j]) to_hit(&rh[j], &hit[j0 + j]);
    }
  }
  return hits;
}

/* Rays from one origin in packets of 16 with Embree's coherent traversal (1% of a
 * render faster than the same rays as one coherent stream). */
int wv_tracer_intersect_from(const wv_tracer *t, const float o[3], const float (*d)[3], int n, wv_trace_hit *hit,
                             int *got) {
  struct RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  int hits = 0;
  for (int j0 = 0; j0 < n; j0 += 16) {
    _Alignas(64) struct RTCRayHit16 rh;
    _Alignas(64) int valid[16];
    for (int k = 0; k < 16; k++) {
      int j = j0 + k < n ? j0 + k : j0; /* lanes past the end: a copy of the first, not traced */
      valid[k] = j0 + k < n ? -1 : 0;
      rh.ray.org_x[k] = o[0], rh.ray.org_y[k] = o[1], rh.ray.org_z[k] = o[2];
      rh.ray.dir_x[k] = d[j][0], rh.ray.dir_y[k] = d[j][1], rh.ray.dir_z[k] = d[j][2];
      rh.ray.tnear[k] = 0.0f, rh.ray.tfar[k] = INFINITY, rh.ray.time[k] = 0.0f, rh.ray.mask[k] = 0xffffffffu;
      rh.ray.id[k] = 0, rh.ray.flags[k] = 0;
      rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID, rh.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
    }
    rtcIntersect16(valid, t->scene, &ctx, &rh);
    for (int k = 0; k < 16 && j0 + k < n; k++) {
      int j = j0 + k;
      got[j] = rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID;
      hits += got[j];
      if (got[j])
        hit[j] = (wv_trace_hit){rh.ray.tfar[k], rh.hit.u[k], rh.hit.v[k], (int)rh.hit.geomID[k], (int)rh.hit.primID[k]};
    }
  }
  return hits;
}

int wv_tracer_intersect_n(const wv_tracer *t, const float (*o)[3], const float (*d)[3], int n, wv_trace_hit *hit,
                          int *got) {
  return intersect_stream(t, o[0], 3, d, n, RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT, hit, got);
}

void wv_tracer_occluded_n(const wv_tracer *t, const float (*o)[3], const float (*d)[3], const float *tmax, int n,
                          int *occ) {
  enum { B = 64 };
  struct RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  struct RTCRay r[B];
  for (int j0 = 0; j0 < n; j0 += B) {
    int m = n - j0 < B ? n - j0 : B;
    for (int j = 0; j < m; j++) set_ray(&r[j], o[j0 + j], d[j0 + j], 0.0f, tmax[j0 + j]);
    if (m < WV_STREAM_MIN)
      for (int j = 0; j < m; j++) rtcOccluded1(t->scene, &ctx, &r[j]);
    else
      rtcOccluded1M(t->scene, &ctx, r, (unsigned)m, sizeof *r);
    for (int j = 0; j < m; j++) occ[j0 + j] = r[j].tfar < 0.0f;
  }
}

int wv_tracer_occluded(const wv_tracer *t, const float o[3], const float d[3], float tmin, float tmax) {
  struct RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  struct RTCRay r;
  set_ray(&r, o, d, tmin, tmax);
  rtcOccluded1(t->scene, &ctx, &r);
  return r.tfar < 0.0f;
}
