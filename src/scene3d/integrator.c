/* The mesh renderer's path tracer (wv_scene3d_render): camera rays through
 * Embree, next-event estimation with multiple importance sampling, cosine-
 * weighted bounces with Russian roulette, fabric shading through the capture
 * renderer's kernel (one adapter, shade_fabric), spatially varying edits, and
 * the capture renderer's pixel sampler for anti-aliasing. */
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "sampler/sampler.h"
#include "scene3d/world_internal.h"
#include "sensor/sensor.h"
#include "util/hash.h"

#define PI_F 3.14159265358979f
#define CMJ_DEPTHS 2 /* path vertices whose light and bounce samples are stratified */

/* One sample sequence of a pixel (the capture renderer's sampler, sampler/sampler.h)
 * and the grid of its spp. */
typedef struct {
  wv_pixel_sampler_f ps;
  int nx, ny;
} wv_pixel_sampler;

static void wv_pixel_sampler_init(wv_pixel_sampler *p, int px, int py, int spp, int width, uint64_t seed) {
  wv_pixel_grid(spp, &p->nx, &p->ny);
  p->ps = wv_pixel_sampler_make(px, py, width, seed);
}

static void wv_pixel_sampler_at(const wv_pixel_sampler *p, int s, float *sx, float *sy) {
  wv_sample_at_f(&p->ps, p->nx, p->ny, s, sx, sy);
}

/* Per-hit fabric parameters after the edits, handed to shade_fabric. */
typedef struct {
  int active;          /* 0: the material's own parameters */
  float kd[2][3], beta[2], alpha[2];
} fabric_edit;

/* THE adapter between the mesh renderer and the fabric shading model: the
 * average of (f_s + f_d) mu_i over n fabric positions (mm), for directions wi
 * (to the light) and wo (to the viewer) in the fabric's local frame (x weft, y
 * warp, z macro normal), with the edits applied. Everything the mesh renderer
 * knows about the fabric model is here: it runs the shading kernel's scalar
 * flavour (wv_shade_f, kernel/kernel.h) with unit light, with the parameters of a
 * per-thread copy of the prepared fabric when edits change k_d, beta or alpha at
 * this point. */
static void shade_fabric(const wv_fabric *base, wv_fabric *scratch, const fabric_edit *e, const float wi[3],
                         const float wo[3], const float (*pos)[2], int n, float out[3]) {
  out[0] = out[1] = out[2] = 0.0f;
  if (wi[2] <= 0.0f || wo[2] <= 0.0f) return; /* SPEC section 4: zero below either horizon */
  const wv_fabric *f = base;
  if (e->active && scratch) {
    for (int y = 0; y < 2; y++) {
      for (int c = 0; c < 3; c++) scratch->P.kd[y][c] = e->kd[y][c];
      scratch->ym.beta[y] = scratch->P.beta[y] = e->beta[y];
      wv_shade_params_set_roughness(&scratch->P, y, e->alpha[y]);
    }
    f = scratch;
  }
  wv_dirs_f d;
  wv_dirs_make_f(wi, wo, 1.0f, &d);
  for (int k = 0; k < n; k++) {
    float r[3];
    wv_shade_f(f, &f->P, &d, pos[k][0], pos[k][1], r, NULL);
    out[0] += r[0], out[1] += r[1], out[2] += r[2];
  }
  float inv = 1.0f / (float)n;
  out[0] *= inv, out[1] *= inv, out[2] *= inv;
}

static float dot(const float a[3], const float b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static void cross(const float a[3], const float b[3], float o[3]) {
  o[0] = a[1] * b[2] - a[2] * b[1], o[1] = a[2] * b[0] - a[0] * b[2], o[2] = a[0] * b[1] - a[1] * b[0];
}
static float normalize(float v[3]) {
  float l = sqrtf(dot(v, v));
  if (l > 0) v[0] /= l, v[1] /= l, v[2] /= l;
  return l;
}
static float maxc(const float c[3]) { return fmaxf(c[0], fmaxf(c[1], c[2])); }

/* Edit values at UV (u, v) of a fabric material. */
static void eval_edits(const wv_world_material *m, float u, float v, fabric_edit *e) {
  e->active = m->nedits > 0;
  if (!e->active) return;
  const wv_fabric *f = m->fab;
  for (int y = 0; y < 2; y++) {
    for (int c = 0; c < 3; c++) e->kd[y][c] = f->P.kd[y][c];
    e->beta[y] = f->ym.beta[y], e->alpha[y] = f->P.alpha[y];
  }
  for (int i = 0; i < m->nedits; i++) {
    const wv_edit_map *em = &m->edits[i];
    float val[3], mask[3] = {1, 1, 1};
    wv_edit_lookup(em->map, u, v, val);
    if (em->mask) wv_edit_lookup(em->mask, u, v, mask);
    float a = fminf(fmaxf(mask[0], 0.0f), 1.0f);
    for (int c = 0; c < 3; c++) val[c] *= em->gain;
    for (int y = 0; y < 2; y++) {
      switch (em->op) {
        case WV_EDIT_DIFFUSE_MULTIPLY:
          for (int c = 0; c < 3; c++) e->kd[y][c] *= 1.0f + a * (val[c] - 1.0f);
          break;
        case WV_EDIT_DIFFUSE_REPLACE:
          for (int c = 0; c < 3; c++) e->kd[y][c] += a * (fminf(val[c], 1.0f) - e->kd[y][c]);
          break;
        case WV_EDIT_HEIGHTFIELD: e->beta[y] *= 1.0f + a * (val[0] - 1.0f); break;
        case WV_EDIT_ROUGHNESS: e->alpha[y] += a * (fminf(fmaxf(val[0], 0.01f), 1.0f) - e->alpha[y]); break;
      }
    }
  }
  for (int y = 0; y < 2; y++) { /* the parameters' ranges (SPEC section 5) */
    for (int c = 0; c < 3; c++) e->kd[y][c] = fminf(fmaxf(e->kd[y][c], 0.0f), 1.0f);
    e->beta[y] = fmaxf(e->beta[y], 0.0f);
  }
}

/* What the integrator needs about one surface point. */
typedef struct {
  float p[3], ng[3], ns[3], t[3], b[3]; /* position, geometric and shading normals, fabric x and y axes */
  float u, v;
  const wv_world_material *mat;
  int mat_index;
  fabric_edit edit;
  float (*fpos)[2]; /* fabric positions (mm) shaded at this point */
  int nfpos;
} surface;

typedef struct {
  const wv_scene3d *s;
  const wv_world *w;
  wv_camera_rig cam;
  int spp, K;
  float eps; /* ray offset */
} render_ctx;

typedef struct {
  wv_fabric **scratch; /* per material, NULL without edits */
  double rays, shades;
  float (*fpos)[2];    /* K positions */
  wv_pixel_sampler strata[1 + 3 * CMJ_DEPTHS]; /* camera; per depth: environment, area light, bounce */
  wv_pixel_sampler yarn;
  uint64_t pixel;
  int sample;
} thread_state;

/* 2D sample 'which' (0 environment, 1 area light, 2 bounce) at path vertex depth. */
static void rand2(const render_ctx *c, thread_state *ts, int depth, int which, float *u1, float *u2) {
  if (depth < CMJ_DEPTHS) {
    wv_pixel_sampler_at(&ts->strata[1 + 3 * depth + which], ts->sample, u1, u2);
    return;
  }
  uint64_t h = wv_hash4(ts->pixel, (uint64_t)ts->sample, (uint64_t)(16 * depth + which), c->s->seed);
  *u1 = wv_u01(h), *u2 = (float)((h >> 16) & 0xffffff) * (1.0f / 16777216.0f);
}

static void camera_dir(const wv_camera_rig *r, float x, float y, float d[3]) {
  float ndx = (2.0f * x / (float)r->width - 1.0f) * r->tan_half * r->aspect;
  float ndy = (1.0f - 2.0f * y / (float)r->height) * r->tan_half;
  for (int i = 0; i < 3; i++) d[i] = r->fwd[i] + ndx * r->right[i] + ndy * r->up[i];
  normalize(d);
}

/* UV change per unit move within the plane of triangle ix: rows du/dP and dv/dP
 * (the dual basis of the edges, in double: cylinders and drapes have triangles
 * thousands of times longer than wide, where a float solve loses the short side). */
static void uv_gradient(const wv_mesh *m, const uint32_t *ix, float gu[3], float gv[3]) {
  const float *p0 = m->pos + 3 * ix[0], *p1 = m->pos + 3 * ix[1], *p2 = m->pos + 3 * ix[2];
  double e1[3], e2[3];
  for (int i = 0; i < 3; i++) e1[i] = (double)p1[i] - p0[i], e2[i] = (double)p2[i] - p0[i];
  double d00 = e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2], d11 = e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2];
  double d01 = e1[0] * e2[0] + e1[1] * e2[1] + e1[2] * e2[2], den = d00 * d11 - d01 * d01;
  const float *t0 = m->uv + 2 * ix[0], *t1 = m->uv + 2 * ix[1], *t2 = m->uv + 2 * ix[2];
  double du1 = (double)t1[0] - t0[0], du2 = (double)t2[0] - t0[0], dv1 = (double)t1[1] - t0[1], dv2 = (double)t2[1] - t0[1];
  for (int i = 0; i < 3; i++) { /* b1 = g1 . r, b2 = g2 . r for r in the plane */
    double g1 = (d11 * e1[i] - d01 * e2[i]) / den, g2 = (d00 * e2[i] - d01 * e1[i]) / den;
    gu[i] = (float)(g1 * du1 + g2 * du2), gv[i] = (float)(g1 * dv1 + g2 * dv2);
  }
}

/* Fills the surface at a hit; wo points back along the ray. */
static void make_surface(const render_ctx *c, thread_state *ts, const wv_trace_hit *hit, const float o[3],
                         const float d[3], int camera, surface *sf) {
  const wv_mesh *m = &c->w->meshes[hit->geom];
  const uint32_t *ix = m->idx + 3 * (size_t)hit->prim;
  float b0 = 1 - hit->b1 - hit->b2, bw[3] = {b0, hit->b1, hit->b2};
  const float *p0 = m->pos + 3 * ix[0], *p1 = m->pos + 3 * ix[1], *p2 = m->pos + 3 * ix[2];
  float e1[3], e2[3];
  for (int i = 0; i < 3; i++) {
    sf->p[i] = o[i] + hit->t * d[i];
    e1[i] = p1[i] - p0[i], e2[i] = p2[i] - p0[i];
    sf->ns[i] = 0, sf->t[i] = 0;
  }
  cross(e1, e2, sf->ng);
  normalize(sf->ng);
  float w_sign = 1;
  for (int k = 0; k < 3; k++)
    for (int i = 0; i < 3; i++) {
      sf->ns[i] += bw[k] * m->nrm[3 * ix[k] + i];
      if (m->tan) sf->t[i] += bw[k] * m->tan[4 * ix[k] + i];
    }
  if (m->tan) w_sign = m->tan[4 * ix[0] + 3];
  if (normalize(sf->ns) == 0.0f) memcpy(sf->ns, sf->ng, sizeof sf->ns);
  if (dot(sf->ns, sf->ng) < 0) /* normals wound against the triangle: trust the normals' side */
    for (int i = 0; i < 3; i++) sf->ng[i] = -sf->ng[i];
  /* two-sided: the side the ray arrives from */
  if (dot(d, sf->ng) > 0)
    for (int i = 0; i < 3; i++) sf->ng[i] = -sf->ng[i], sf->ns[i] = -sf->ns[i];
  if (-dot(d, sf->ns) <= 1e-4f) memcpy(sf->ns, sf->ng, sizeof sf->ns); /* shading normal faces away from the viewer */
  sf->mat_index = c->w->material[hit->geom];
  sf->mat = &c->w->mats[sf->mat_index];
  sf->nfpos = 0;
  if (sf->mat->kind != WV_MAT_FABRIC) return;
  /* fabric frame: x along the interpolated u tangent, made orthogonal to ns; y = +-(ns x t) toward +v */
  float tn = dot(sf->t, sf->ns);
  for (int i = 0; i < 3; i++) sf->t[i] -= tn * sf->ns[i];
  if (normalize(sf->t) == 0.0f) {
    float a[3] = {fabsf(sf->ns[0]) > 0.9f ? 0.0f : 1.0f, fabsf(sf->ns[0]) > 0.9f ? 1.0f : 0.0f, 0};
    cross(sf->ns, a, sf->t);
    normalize(sf->t);
  }
  cross(sf->ns, sf->t, sf->b);
  for (int i = 0; i < 3; i++) sf->b[i] *= w_sign;
  const float *t0 = m->uv + 2 * ix[0], *t1 = m->uv + 2 * ix[1], *t2 = m->uv + 2 * ix[2];
  sf->u = b0 * t0[0] + hit->b1 * t1[0] + hit->b2 * t2[0];
  sf->v = b0 * t0[1] + hit->b1 * t1[1] + hit->b2 * t2[1];
  const wv_world_material *mt = sf->mat;
  eval_edits(mt, sf->u, sf->v, &sf->edit);
  sf->fpos = ts->fpos;
  if (!camera) {
    sf->fpos[0][0] = sf->u * mt->uv_mm[0] + mt->uv_off[0], sf->fpos[0][1] = sf->v * mt->uv_mm[1] + mt->uv_off[1];
    sf->nfpos = 1;
    return;
  }
  /* Sub-pixel yarns: K positions spread over the pixel (a stratified set of spp x K
   * per pixel, K of them for this ray), where their camera rays meet this triangle's plane. */
  const wv_camera_rig *r = &c->cam;
  float gu[3], gv[3], rel[3];
  uv_gradient(m, ix, gu, gv);
  for (int i = 0; i < 3; i++) rel[i] = sf->p[i] - r->cpos[i];
  float pn = dot(rel, sf->ng); /* camera to the plane, along its normal */
  int px = (int)(ts->pixel % (uint64_t)r->width), py = (int)(ts->pixel / (uint64_t)r->width);
  for (int k = 0; k < c->K; k++) {
    float sx, sy, dd[3], u = sf->u, v = sf->v;
    wv_pixel_sampler_at(&ts->yarn, ts->sample * c->K + k, &sx, &sy);
    camera_dir(r, (float)px + sx, (float)py + sy, dd);
    float den = dot(dd, sf->ng);
    if (fabsf(den) > 1e-6f && pn / den > 0) {
      float q[3]; /* from the hit to where this sample's ray meets the plane */
      for (int i = 0; i < 3; i++) q[i] = pn / den * dd[i] - rel[i];
      u += dot(gu, q), v += dot(gv, q);
    }
    sf->fpos[k][0] = u * mt->uv_mm[0] + mt->uv_off[0], sf->fpos[k][1] = v * mt->uv_mm[1] + mt->uv_off[1];
  }
  sf->nfpos = c->K;
}

/* BSDF x cosine for light arriving from wi (world), seen from wo. */
static void eval_bsdf(const surface *sf, thread_state *ts, const float wi[3], const float wo[3], float f[3]) {
  f[0] = f[1] = f[2] = 0;
  if (dot(wi, sf->ng) <= 0.0f) return; /* reflection only: the cloth is opaque */
  if (sf->mat->kind == WV_MAT_LAMBERT) {
    float cs = dot(wi, sf->ns);
    if (cs <= 0) return;
    for (int c = 0; c < 3; c++) f[c] = sf->mat->albedo[c] * cs / PI_F;
    return;
  }
  float li[3] = {dot(wi, sf->t), dot(wi, sf->b), dot(wi, sf->ns)}, lo[3] = {dot(wo, sf->t), dot(wo, sf->b), dot(wo, sf->ns)};
  shade_fabric(sf->mat->fab, ts->scratch[sf->mat_index], &sf->edit, li, lo, (const float(*)[2])sf->fpos, sf->nfpos, f);
  ts->shades += sf->nfpos;
}

static float power_heuristic(float a, float b) { return a * a / (a * a + b * b); }
static float cos_pdf(const surface *sf, const float wi[3]) {
  float cs = dot(wi, sf->ns);
  return cs > 0 ? cs / PI_F : 0.0f;
}

/* Area light l hit by the ray (o, d) before tmax: distance and the light's cosine. */
static int hit_area(const wv_light3d *l, const float o[3], const float d[3], float tmax, float *t, float *cosl) {
  float n[3] = {(float)l->dir[0], (float)l->dir[1], (float)l->dir[2]}, c[3] = {(float)l->pos[0], (float)l->pos[1], (float)l->pos[2]};
  float dn = dot(d, n);
  if (dn >= 0) return 0; /* behind it or parallel: it emits along +dir only */
  float oc[3] = {c[0] - o[0], c[1] - o[1], c[2] - o[2]};
  float tt = dot(oc, n) / dn;
  if (!(tt > 0 && tt < tmax)) return 0;
  float ex[3], ey[3], q[3];
  float a[3] = {fabsf(n[1]) > 0.99f ? 1.0f : 0.0f, fabsf(n[1]) > 0.99f ? 0.0f : 1.0f, 0};
  cross(a, n, ex), normalize(ex), cross(n, ex, ey);
  for (int i = 0; i < 3; i++) q[i] = o[i] + tt * d[i] - c[i];
  if (fabsf(dot(q, ex)) > 0.5f * (float)l->size[0] || fabsf(dot(q, ey)) > 0.5f * (float)l->size[1]) return 0;
  *t = tt, *cosl = -dn;
  return 1;
}

/* Radiance along one camera ray. */
static void trace_path(const render_ctx *c, thread_state *ts, const float o0[3], const float d0[3], float L[3]) {
  const wv_scene3d *s = c->s;
  const wv_world *w = c->w;
  float o[3] = {o0[0], o0[1], o0[2]}, d[3] = {d0[0], d0[1], d0[2]}, thr[3] = {1, 1, 1};
  float prev_pdf = 0; /* bounce pdf of the ray being traced; 0 for the camera ray (no MIS) */
  L[0] = L[1] = L[2] = 0;
  for (int depth = 0;; depth++) {
    wv_trace_hit hit;
    ts->rays++;
    int got = wv_tracer_intersect(w->tracer, o, d, 0.0f, INFINITY, &hit);
    float tmax = got ? hit.t : INFINITY;
    for (int i = 0; i < s->nlights; i++) { /* area lights the ray sees before the surface */
      const wv_light3d *l = &s->lights[i];
      float t, cosl;
      if (l->type != WV_LIGHT_AREA || !hit_area(l, o, d, tmax, &t, &cosl)) continue;
      float pl = t * t / ((float)(l->size[0] * l->size[1]) * cosl), wgt = prev_pdf > 0 ? power_heuristic(prev_pdf, pl) : 1;
      for (int k = 0; k < 3; k++) L[k] += thr[k] * (float)l->color[k] * wgt;
    }
    if (!got) {
      if (w->has_env && (depth > 0 || s->env_visible)) {
        float le[3];
        wv_envmap_eval(&w->env, d, le);
        float wgt = prev_pdf > 0 ? power_heuristic(prev_pdf, wv_envmap_pdf(&w->env, d)) : 1;
        for (int k = 0; k < 3; k++) L[k] += thr[k] * le[k] * wgt;
      }
      return;
    }
    surface sf;
    make_surface(c, ts, &hit, o, d, depth == 0, &sf);
    float wo[3] = {-d[0], -d[1], -d[2]}, org[3];
    int last = depth >= s->max_bounces; /* no bounce follows: light samples take the whole weight */
    for (int i = 0; i < 3; i++) org[i] = sf.p[i] + c->eps * sf.ng[i];
    /* next-event estimation */
    for (int i = 0; i < s->nlights; i++) {
      const wv_light3d *l = &s->lights[i];
      float wi[3], li[3], dist = INFINITY, wgt = 1;
      if (l->type == WV_LIGHT_DIRECTIONAL) {
        for (int k = 0; k < 3; k++) wi[k] = (float)l->dir[k], li[k] = (float)l->color[k];
      } else {
        float lp[3], g = 1;
        for (int k = 0; k < 3; k++) lp[k] = (float)l->pos[k];
        if (l->type == WV_LIGHT_AREA) {
          float u1, u2, n[3] = {(float)l->dir[0], (float)l->dir[1], (float)l->dir[2]}, ex[3], ey[3];
          float a[3] = {fabsf(n[1]) > 0.99f ? 1.0f : 0.0f, fabsf(n[1]) > 0.99f ? 0.0f : 1.0f, 0};
          cross(a, n, ex), normalize(ex), cross(n, ex, ey);
          rand2(c, ts, depth, 1, &u1, &u2);
          for (int k = 0; k < 3; k++)
            lp[k] += (u1 - 0.5f) * (float)l->size[0] * ex[k] + (u2 - 0.5f) * (float)l->size[1] * ey[k];
          for (int k = 0; k < 3; k++) wi[k] = lp[k] - sf.p[k];
          dist = normalize(wi);
          float cosl = -dot(wi, n);
          if (cosl <= 0) continue;
          float pl = dist * dist / ((float)(l->size[0] * l->size[1]) * cosl);
          wgt = last ? 1.0f : power_heuristic(pl, cos_pdf(&sf, wi));
          g = 1.0f / pl;
        } else {
          for (int k = 0; k < 3; k++) wi[k] = lp[k] - sf.p[k];
          dist = normalize(wi);
          g = 1.0f / (dist * dist);
          if (l->type == WV_LIGHT_SPOT) {
            float ca = -(wi[0] * (float)l->dir[0] + wi[1] * (float)l->dir[1] + wi[2] * (float)l->dir[2]);
            float c0 = cosf((float)(l->cone_deg * 3.14159265358979 / 180)),
                  c1 = cosf((float)((l->cone_deg - l->blend_deg) * 3.14159265358979 / 180));
            float x = c1 > c0 ? (ca - c0) / (c1 - c0) : (ca >= c0 ? 1.0f : 0.0f);
            x = fminf(fmaxf(x, 0.0f), 1.0f);
            g *= x * x * (3 - 2 * x);
          }
        }
        for (int k = 0; k < 3; k++) li[k] = (float)l->color[k] * g;
        dist *= 0.9999f;
      }
      if (maxc(li) <= 0) continue;
      float f[3];
      eval_bsdf(&sf, ts, wi, wo, f);
      if (maxc(f) <= 0) continue;
      ts->rays++;
      if (wv_tracer_occluded(w->tracer, org, wi, 0.0f, dist)) continue;
      for (int k = 0; k < 3; k++) L[k] += thr[k] * f[k] * li[k] * wgt;
    }
    if (w->has_env) {
      float u1, u2, wi[3], le[3];
      rand2(c, ts, depth, 0, &u1, &u2);
      float pl = wv_envmap_sample(&w->env, u1, u2, wi, le);
      if (pl > 0 && maxc(le) > 0) {
        float f[3];
        eval_bsdf(&sf, ts, wi, wo, f);
        if (maxc(f) > 0) {
          ts->rays++;
          if (!wv_tracer_occluded(w->tracer, org, wi, 0.0f, INFINITY)) {
            float wgt = last ? 1.0f : power_heuristic(pl, cos_pdf(&sf, wi));
            for (int k = 0; k < 3; k++) L[k] += thr[k] * f[k] * le[k] * wgt / pl;
          }
        }
      }
    }
    if (last) return;
    /* bounce: cosine-weighted about the shading normal */
    float u1, u2;
    rand2(c, ts, depth, 2, &u1, &u2);
    float r = sqrtf(u1), phi = 2 * PI_F * u2, lx = r * cosf(phi), ly = r * sinf(phi), lz = sqrtf(fmaxf(0.0f, 1 - u1));
    float a[3], bx[3], by[3], wi[3];
    a[0] = fabsf(sf.ns[0]) > 0.9f ? 0.0f : 1.0f, a[1] = fabsf(sf.ns[0]) > 0.9f ? 1.0f : 0.0f, a[2] = 0;
    cross(sf.ns, a, bx), normalize(bx), cross(sf.ns, bx, by);
    for (int k = 0; k < 3; k++) wi[k] = lx * bx[k] + ly * by[k] + lz * sf.ns[k];
    float pdf = cos_pdf(&sf, wi), f[3];
    if (pdf <= 0) return;
    eval_bsdf(&sf, ts, wi, wo, f);
    for (int k = 0; k < 3; k++) thr[k] *= f[k] / pdf;
    float q = fminf(0.95f, maxc(thr));
    if (q <= 0) return;
    if (depth >= 1) { /* Russian roulette from the third path vertex on */
      uint64_t h = wv_hash4(ts->pixel, (uint64_t)ts->sample, (uint64_t)(16 * depth + 9), s->seed);
      if (wv_u01(h) >= q) return;
      for (int k = 0; k < 3; k++) thr[k] /= q;
    }
    memcpy(o, org, sizeof o);
    memcpy(d, wi, sizeof d);
    prev_pdf = pdf;
  }
}

wv_status wv_scene3d_render(const wv_scene3d *s, const wv_world *w, const wv_scene3d_opts *opt, wv_image *capture,
                            wv_image *radiance, wv_scene3d_stats *stats, wv_error *err) {
  render_ctx c = {0};
  c.s = s, c.w = w;
  c.spp = opt && opt->spp > 0 ? opt->spp : s->spp;
  c.K = s->yarn_samples > 0 ? s->yarn_samples : 1;
  if (c.spp > WV_SCENE_MAX_SPP) return wv_fail(err, WV_ERR_INVALID, "spp %d is above the limit %d", c.spp, WV_SCENE_MAX_SPP);
  if ((long long)s->width * s->height * c.spp > WV_SCENE_MAX_SAMPLES)
    return wv_fail(err, WV_ERR_NOMEM, "%d x %d pixels x %d spp is too many samples", s->width, s->height, c.spp);
  if ((long long)c.spp * c.K > 65536)
    return wv_fail(err, WV_ERR_INVALID, "spp x yarn_samples = %lld is above 65536", (long long)c.spp * c.K);
  /* the capture renderer's camera basis, from a capture scene with this camera */
  wv_scene cs = s->response;
  cs.width = s->width, cs.height = s->height, cs.vfov_deg = s->vfov_deg;
  for (int i = 0; i < 3; i++) cs.cam_pos[i] = s->cam_pos[i], cs.cam_look_at[i] = s->cam_look_at[i], cs.cam_up[i] = s->cam_up[i];
  wv_rig_prepare(&cs, &c.cam);
  float extent = w->scene_radius;
  for (int i = 0; i < 3; i++) extent = fmaxf(extent, fabsf(c.cam.cpos[i]));
  c.eps = 2e-5f * extent;
  int threads = opt && opt->threads > 0 ? opt->threads : omp_get_max_threads();
  wv_image rad;
  wv_status st = wv_image_alloc(&rad, s->width, s->height, 3, err);
  if (st) return st;
  if ((st = wv_image_alloc(capture, s->width, s->height, 3, err))) {
    wv_image_free(&rad);
    return st;
  }
  thread_state *ts = calloc((size_t)threads, sizeof *ts);
  int fail = !ts;
  for (int t = 0; t < threads && !fail; t++) {
    ts[t].scratch = calloc((size_t)w->nmats, sizeof *ts[t].scratch);
    ts[t].fpos = malloc(sizeof *ts[t].fpos * (size_t)c.K);
    fail |= !ts[t].scratch || !ts[t].fpos;
    for (int m = 0; m < w->nmats && !fail; m++)
      if (w->mats[m].nedits) {
        fail |= !(ts[t].scratch[m] = malloc(sizeof(wv_fabric)));
        if (!fail) *ts[t].scratch[m] = *w->mats[m].fab;
      }
  }
  int rows_done = 0;
  if (!fail) {
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
    for (int py = 0; py < s->height; py++) {
      thread_state *me = &ts[omp_get_thread_num()];
      if (opt && opt->progress && omp_get_thread_num() == 0) {
        int done;
#pragma omp atomic read
        done = rows_done;
        opt->progress(opt->progress_user, (double)done / s->height);
      }
      for (int px = 0; px < s->width; px++) {
        me->pixel = (uint64_t)py * (uint64_t)s->width + (uint64_t)px;
        wv_pixel_sampler_init(&me->strata[0], px, py, c.spp, s->width, s->seed);
        for (int k = 1; k < 1 + 3 * CMJ_DEPTHS; k++)
          wv_pixel_sampler_init(&me->strata[k], px, py, c.spp, s->width, wv_mix64(s->seed + 0x51ed27ULL * (uint64_t)k));
        wv_pixel_sampler_init(&me->yarn, px, py, c.spp * c.K, s->width, wv_mix64(s->seed ^ 0x7961726eULL));
        double acc[3] = {0, 0, 0};
        for (int j = 0; j < c.spp; j++) {
          me->sample = j;
          float sx, sy, d[3], L[3];
          wv_pixel_sampler_at(&me->strata[0], j, &sx, &sy);
          camera_dir(&c.cam, (float)px + sx, (float)py + sy, d);
          trace_path(&c, me, c.cam.cpos, d, L);
          for (int k = 0; k < 3; k++) acc[k] += isfinite(L[k]) ? L[k] : 0.0f;
        }
        float *out = wv_image_px(&rad, px, py);
        for (int k = 0; k < 3; k++) out[k] = (float)(acc[k] / c.spp);
      }
#pragma omp atomic update
      rows_done++;
    }
  }
  double rays = 0, shades = 0;
  for (int t = 0; t < threads && ts; t++) {
    rays += ts[t].rays, shades += ts[t].shades;
    for (int m = 0; m < w->nmats && ts[t].scratch; m++) free(ts[t].scratch[m]);
    free(ts[t].scratch), free(ts[t].fpos);
  }
  free(ts);
  if (fail) {
    wv_image_free(&rad), wv_image_free(capture);
    return wv_fail(err, WV_ERR_NOMEM, "out of memory for the render threads");
  }
  if (opt && opt->progress) opt->progress(opt->progress_user, 1.0);
  wv_scene_response(&s->response, &rad, capture);
  if (stats) stats->spp = c.spp, stats->rays = rays, stats->shade_calls = shades;
  if (radiance) *radiance = rad;
  else wv_image_free(&rad);
  return WV_OK;
}
