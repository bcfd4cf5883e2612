/* The mesh renderer's path tracer (wv_scene3d_render): camera rays through
 * Embree, next-event estimation with multiple importance sampling, cosine-
 * weighted bounces with Russian roulette, fabric shading through the capture
 * renderer's kernel (one adapter, shade_fabric), light through the cloth (the
 * kernel's transmission, bounces through the sheet, paths straight through its
 * open gaps), spatially varying edits, and the capture renderer's pixel sampler
 * for anti-aliasing. */
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "sampler/sampler.h"
#include "scene3d/world_internal.h"
#include "sensor/sensor.h"
#include "util/hash.h"

/* -O3 for this file (its small fixed-size loops unrolled, unswitched and
 * vectorised; about 6% of a render): no reassociation, so results stay the same. */
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC optimize("O3")
#endif

#define PI_F 3.14159265358979f
#define INV_PI_F 0.318309886f /* 1 / pi: a product instead of a division */
#define CMJ_DEPTHS 2 /* path vertices whose light and bounce samples are stratified */
#define ONE_BELOW 0x1.fffffep-1f /* the largest float below 1 */
#define PASS_MAX 256 /* path vertices after which a path ends rather than pass through another gap */

/* Samples idx[0 .. m-1] (all of 0 .. n-1 when idx is NULL) of a pixel's sequence
 * of n (the capture renderer's sampler, sampler/sampler.h), eight at a time: the
 * numbers wv_sample_at_f gives one by one, each into out[its index]. */
WV_SIMD_CLONES static void draw_sequence(int px, int py, int n, int width, uint64_t seed, const int *idx, int m,
                                         float (*out)[2]) {
  int nx, ny;
  wv_pixel_grid(n, &nx, &ny);
  wv_pixel_sampler_f p = wv_pixel_sampler_make(px, py, width, seed);
  wv_pixel_sampler_8 p8 = {(wv_q8){0} + p.hash, (wv_w8){0} + p.keyx, (wv_w8){0} + p.keyy};
  if (!idx) m = n;
  for (int s0 = 0; s0 < m; s0 += 8) {
    wv_i8 s;
    for (int k = 0; k < 8; k++) /* lanes past the end: a valid index, result dropped */
      s[k] = s0 + k < m ? (idx ? idx[s0 + k] : s0 + k) : (idx ? idx[s0] : s0);
    wv_f8 sx, sy;
    wv_sample_at_8(&p8, nx, ny, s, &sx, &sy);
    for (int k = 0; k < 8 && s0 + k < m; k++) out[s[k]][0] = sx[k], out[s[k]][1] = sy[k];
  }
}

/* Per-hit fabric parameters after the edits, handed to shade_fabric. */
typedef struct {
  int active;          /* 0: the material's own parameters */
  float kd[2][3], beta[2], alpha[2];
} fabric_edit;

/* Fabric points shaded eight at a time by the kernel's 8-lane flavour, which
 * gives each lane the scalar flavour's result bit for bit: lane i at position
 * pos[i] (mm), light from wi[i], view wo + wo_step i, unit light; m <= 8 lanes. */
WV_SIMD_CLONES static void shade_lanes(const wv_fabric *f, int m, const float (*pos)[2], const float (*wi)[3],
                                       const float *wo, int wo_step, float (*r)[3]) {
  wv_f8 x, y, vi[3], vo[3], rad[3];
  for (int i = 0; i < 8; i++) {
    int l = i < m ? i : 0; /* lanes past the end: a copy of lane 0, result dropped */
    x[i] = pos[l][0], y[i] = pos[l][1];
    for (int k = 0; k < 3; k++) vi[k][i] = wi[l][k], vo[k][i] = wo[l * wo_step + k];
  }
  wv_dirs_8 d;
  wv_dirs_make_8(vi, vo, wv_splat8(1.0f), &d);
  wv_shade_8(f, &f->P, &d, x, y, rad, NULL);
  for (int i = 0; i < m; i++) r[i][0] = rad[0][i], r[i][1] = rad[1][i], r[i][2] = rad[2][i];
}

/* THE adapter between the mesh renderer and the fabric shading model: for each
 * of nd light directions wi[j] (NULL: not wanted), the average of (f_s + f_d)
 * mu_i over n fabric positions (mm) into out[j], with the view wo, both in the
 * fabric's local frame (x weft, y warp, z macro normal), with the edits applied:
 * reflected for wi above the surface, transmitted (the kernel's wv_shade_trans:
 * specular and diffuse transmission, 0 in an open gap) for wi below it.
 * Everything the mesh renderer knows about the fabric model is here: it runs the
 * shading kernel (kernel/kernel.h; all the points of all directions in 8-lane
 * calls, even one or two: its AVX2 and AVX-512 versions take less time than two
 * points in the scalar flavour, and give each lane its result) with unit light, with
 * the parameters of a per-thread copy of the prepared fabric when edits change
 * k_d, beta or alpha at this point. */
static void shade_fabric(const wv_fabric *base, wv_fabric *scratch, const fabric_edit *e, int nd,
                         const float *const *wi, const float wo[3], const float (*pos)[2], int n, float (*out)[3]) {
  int lanes = 0, on[2];
  for (int j = 0; j < nd; j++) {
    out[j][0] = out[j][1] = out[j][2] = 0.0f;
    on[j] = wi[j] && wi[j][2] != 0.0f && wo[2] > 0.0f; /* zero below the view's horizon (SPEC section 4) */
    lanes += on[j] * n;
  }
  if (!lanes) return;
  const wv_fabric *f = base;
  if (e->active && scratch) {
    for (int y = 0; y < 2; y++) {
      for (int c = 0; c < 3; c++) scratch->P.kd[y][c] = e->kd[y][c];
      scratch->ym.beta[y] = scratch->P.beta[y] = e->beta[y];
      wv_shade_params_set_roughness(&scratch->P, y, e->alpha[y]);
    }
    f = scratch;
  }
  /* lanes in the order (direction, position): each sum in the scalar order */
  float lp[8][2], lw[8][3], r[8][3];
  int owner[8], j = on[0] ? 0 : 1, k = 0;
  for (int l = 0; l < lanes;) {
    int m = 0;
    for (; m < 8 && l < lanes; m++, l++) {
      lp[m][0] = pos[k][0], lp[m][1] = pos[k][1], memcpy(lw[m], wi[j], sizeof lw[m]), owner[m] = j;
      if (++k == n) k = 0, j++;
    }
    shade_lanes(f, m, (const float(*)[2])lp, (const float(*)[3])lw, wo, 0, r);
    for (int i = 0; i < m; i++)
      out[owner[i]][0] += r[i][0], out[owner[i]][1] += r[i][1], out[owner[i]][2] += r[i][2];
  }
  float inv = 1.0f / (float)n;
  for (int j = 0; j < nd; j++)
    if (on[j]) out[j][0] *= inv, out[j][1] *= inv, out[j][2] *= inv;
}

static float dot(const float a[3], const float b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static void cross(const float a[3], const float b[3], float o[3]) {
  o[0] = a[1] * b[2] - a[2] * b[1], o[1] = a[2] * b[0] - a[0] * b[2], o[2] = a[0] * b[1] - a[1] * b[0];
}
static float normalize(float v[3]) {
  float l = sqrtf(dot(v, v));
  if (l > 0) {
    float inv = 1.0f / l;
    v[0] *= inv, v[1] *= inv, v[2] *= inv;
  }
  return l;
}
/* Unit vectors x and y completing the unit n to the bounce's frame: x = n x a
 * normalised (a: the x axis, or the y axis when n is near the x axis), y = n x x.
 * (Another frame would draw the same distribution, but its stratified directions
 * would no longer line up with those of references rendered with this one.) */
static void frame(const float n[3], float x[3], float y[3]) {
  float a[3] = {fabsf(n[0]) > 0.9f ? 0.0f : 1.0f, fabsf(n[0]) > 0.9f ? 1.0f : 0.0f, 0};
  cross(n, a, x), normalize(x), cross(n, x, y);
}
/* fmaxf and fminf as the comparisons they are (a NaN loses to a number), inline:
 * the baseline build calls libm for them. */
static float max2(float a, float b) {
  float m = a > b ? a : b; /* maxss; then a NaN b loses (no branches) */
  return b != b ? a : m;
}
static float min2(float a, float b) {
  float m = a < b ? a : b;
  return b != b ? a : m;
}
static float maxc(const float c[3]) { return max2(c[0], max2(c[1], c[2])); }
/* maxc(c) > 0, without a chain of selects */
static int any_pos(const float c[3]) { return (c[0] > 0.0f) | (c[1] > 0.0f) | (c[2] > 0.0f); }

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
  int trans;        /* a fabric that transmits: light from below the surface is shaded too */
  int nopen;        /* of the positions, those in an open gap (the path may pass straight through) */
  float pback;      /* probability that a bounce goes through the sheet */
  float pscatter;   /* probability that the path scatters here (not straight through a gap) */
  const float (*frame)[3]; /* x and y completing ns to an orthonormal frame (a flat face's), or NULL */
} surface;

/* A path's vertex between vertex_begin and vertex_end (render_pixel shades the
 * directions of several fabric vertices together in between). */
typedef struct {
  surface sf;
  float wo[3], org[3], orgb[3];      /* the view; ray origins on the path's side and the other */
  float ewi[3], ele[3], epl;         /* the environment's sample */
  float bwi[3], bpdf;                /* the bounce */
  float side[2], cs[2], fb[2][3];    /* the two directions' cosines and BSDF x cosine */
  int last, pass, env_on, plane, nshade;
  float li[2][3], lo[3];             /* a fabric's directions and view in its frame, to shade */
  const float *lwant[2];
} vertex;

typedef struct {
  const wv_scene3d *s;
  const wv_world *w;
  wv_camera_rig cam;
  int spp, K;
  int gaps;                     /* a fabric transmits and has open gaps: paths may pass through */
  float eps;                    /* ray offset */
  int cull;                     /* rays leaving a planar object may skip the tracer (wv_world_leaves_scene) */
  wv_turn_table turn;           /* the bounce's turn about the normal */
  int need[1 + 3 * CMJ_DEPTHS]; /* the stratified dimensions paths use (see rand2) */
} render_ctx;

/* One camera path of a pixel between two vertices: the ray to follow and what
 * the path has gathered. */
typedef struct {
  float o[3], d[3], thr[3], L[3];
  float prev_pdf;   /* bounce pdf of the ray (o, d); 0 for the camera ray (no MIS) */
  int depth;        /* the path vertex the ray leads to */
  int bounces;      /* scattering vertices before it (passing through an open gap is none) */
  int got;          /* the ray meets the scene, at hit */
  wv_trace_hit hit;
  wv_env_at at;     /* the environment's texel along a bounce ray */
  int shadow;       /* a shadow ray toward the environment's sample waits (render_pixel traces it) */
  float sh_o[3], sh_d[3], sh_add[3]; /* it, and what it adds to L when nothing blocks it */
  int sh_leave, leave; /* the planar object the shadow ray and the ray (o, d) leave, or -1 */
} path;

/* Per thread: scratch, counters, the current pixel's paths and their stratified
 * numbers, drawn for the paths that need them (render_pixel). */
typedef struct {
  _Alignas(64) wv_fabric **scratch; /* per material, NULL without edits; the state on cache lines of its own */
  double rays, shades;
  float (*fpos)[2];    /* spp x K: the fabric positions of each path's surface */
  float (*u)[2];       /* (1 + 3 CMJ_DEPTHS) x spp: camera; per depth: environment, area light, bounce */
  float (*yarn)[2];    /* spp x K: the yarn positions */
  wv_env_sample *env;  /* CMJ_DEPTHS x spp: the environment's samples of the numbers in u */
  float (*dir)[3];     /* spp: camera rays, then the bounce rays traced together */
  float (*org)[3];     /* spp: the bounce rays' origins */
  float (*sh_o)[3], (*sh_d)[3], *sh_t; /* spp: the shadow rays traced together */
  int *sh_idx, *sh_occ;                /* spp: their paths, and whether they are blocked */
  float (*ydir)[3];    /* K: the rays through a camera ray's yarn positions */
  wv_trace_hit *hit;   /* spp: where they meet the scene */
  int *got;            /* spp: whether they do */
  path *paths;         /* spp */
  int *act;            /* spp: the paths that reach a vertex */
  int *idx;            /* spp: of them, those that reach a surface there */
  int *yidx;           /* spp x K: the yarn positions wanted */
  float (*ug)[2];      /* spp: the numbers of the environment samples wanted */
  wv_env_sample *eg;   /* spp: their samples */
  vertex *vtx;         /* spp: the paths' vertices between vertex_begin and vertex_end */
  int *dq;             /* spp: the fabric vertices whose shading waits (shade_waiting) */
  uint64_t pixel;
  int sample;
} thread_state;

/* 2D sample 'which' (0 environment, 1 area light, 2 bounce) at path vertex depth. */
static void rand2(const render_ctx *c, thread_state *ts, int depth, int which, float *u1, float *u2) {
  if (depth < CMJ_DEPTHS) {
    const float *v = ts->u[(1 + 3 * depth + which) * c->spp + ts->sample];
    *u1 = v[0], *u2 = v[1];
    return;
  }
  uint64_t h = wv_hash4(ts->pixel, (uint64_t)ts->sample, (uint64_t)(16 * depth + which), c->s->seed);
  *u1 = wv_u01(h), *u2 = (float)((h >> 16) & 0xffffff) * (1.0f / 16777216.0f);
}

/* Unit directions of the camera rays through the points s[0 .. n-1] (offsets in
 * [0, 1)^2) of pixel (px, py), eight at a time. */
WV_SIMD_CLONES static void camera_dirs(const wv_camera_rig *r, int px, int py, int n, const float (*s)[2],
                                       float (*d)[3]) {
  for (int j0 = 0; j0 < n; j0 += 8) {
    wv_f8 x, y, v[3];
    for (int k = 0; k < 8; k++) {
      int j = j0 + k < n ? j0 + k : j0; /* lanes past the end: a copy, result dropped */
      x[k] = (float)px + s[j][0], y[k] = (float)py + s[j][1];
    }
    wv_f8 ndx = (2.0f * x / (float)r->width - 1.0f) * r->tan_half * r->aspect;
    wv_f8 ndy = (1.0f - 2.0f * y / (float)r->height) * r->tan_half;
    for (int i = 0; i < 3; i++) v[i] = r->fwd[i] + ndx * r->right[i] + ndy * r->up[i];
    wv_f8 l = wv_sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    l = wv_sel(l > 0.0f, l, wv_splat8(1.0f)); /* normalize()'s operations */
    for (int i = 0; i < 3; i++) v[i] = v[i] / l;
    for (int k = 0; k < 8 && j0 + k < n; k++) d[j0 + k][0] = v[0][k], d[j0 + k][1] = v[1][k], d[j0 + k][2] = v[2][k];
  }
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

void wv_faces_make(const wv_mesh *m, wv_face *out, wv_face_uv *fuv, wv_uv_grad *grad) {
  for (int t = 0; t < m->nt; t++) {
    const uint32_t *ix = m->idx + 3 * (size_t)t;
    const float *p0 = m->pos + 3 * ix[0], *p1 = m->pos + 3 * ix[1], *p2 = m->pos + 3 * ix[2];
    float e1[3], e2[3];
    for (int i = 0; i < 3; i++) e1[i] = p1[i] - p0[i], e2[i] = p2[i] - p0[i];
    wv_face *f = &out[t];
    memset(f, 0, sizeof *f);
    cross(e1, e2, f->ng);
    normalize(f->ng);
    for (int k = 0; k < 3; k++) memcpy(f->nrm[k], m->nrm + 3 * ix[k], sizeof f->nrm[k]);
    f->flat = !memcmp(f->nrm[0], f->nrm[1], sizeof f->nrm[0]) && !memcmp(f->nrm[0], f->nrm[2], sizeof f->nrm[0]) &&
              normalize(f->nrm[0]) > 0.0f;
    if (f->flat) {
      if (dot(f->nrm[0], f->ng) < 0)
        for (int i = 0; i < 3; i++) f->ng[i] = -f->ng[i];
      frame(f->nrm[0], f->nrm[1], f->nrm[2]);
    }
    if (grad) uv_gradient(m, ix, grad[t].gu, grad[t].gv);
    if (!fuv) continue;
    wv_face_uv *g = &fuv[t];
    memset(g, 0, sizeof *g);
    g->w_sign = m->tan ? m->tan[4 * ix[0] + 3] : 1.0f;
    for (int k = 0; k < 3; k++) {
      memcpy(g->uv[k], m->uv + 2 * ix[k], sizeof g->uv[k]);
      if (m->tan) memcpy(g->tan[k], m->tan + 4 * ix[k], sizeof g->tan[k]);
    }
  }
}

/* Where a transmitting fabric has gaps: how many of the surface's positions are
 * in an open gap (the kernel's wv_kernel_open; edits do not move the gaps), and
 * so the probability that the path scatters there rather than going straight on. */
static void count_open(const render_ctx *c, surface *sf) {
  const wv_fabric *f = sf->mat->fab;
  if (!sf->trans || !c->gaps || !(f->ym.width < 1.0f)) return;
  for (int k = 0; k < sf->nfpos; k++) sf->nopen += wv_kernel_open(f, sf->fpos[k][0], sf->fpos[k][1]);
  sf->pscatter = 1.0f - (float)sf->nopen / (float)sf->nfpos;
}

/* The probability that a fabric's bounce goes through the sheet (a choice of
 * sampling, not of the result): its diffuse transmission at normal incidence
 * (k_t t(T)) against its reflection's albedos (k_d + k_s), within 0.05..0.5. */
float wv_back_prob(const wv_fabric *f) {
  float r = 0, t = 0, tt = WV_CLOTH_TRANSMITTANCE(f->P.thickness);
  for (int y = 0; y < 2; y++) r += maxc(f->P.kd[y]) + maxc(f->P.ks[y]), t += maxc(f->P.kt[y]) * tt;
  float p = r + t > 0 ? t / (r + t) : 0.5f;
  return min2(0.5f, max2(0.05f, p));
}

static void fabric_surface(const render_ctx *c, thread_state *ts, const wv_trace_hit *hit, int camera, surface *sf);

/* Fills the surface at a hit; wo points back along the ray. The path tracer's hot
 * path: a fabric's frame and positions are filled out of line (fabric_surface). */
static inline __attribute__((always_inline)) void make_surface(const render_ctx *c, thread_state *ts,
                                                               const wv_trace_hit *hit, const float o[3],
                                                               const float d[3], int camera, surface *sf) {
  /* in locals (the compiler cannot tell sf from the face and the ray), copied element
   * by element: a block copy of a local written element by element reads it back
   * from memory, wider than its stores were (a stall: no store forwarding) */
  const float b1 = hit->b1, b2 = hit->b2, b0 = 1 - b1 - b2, t = hit->t;
  const wv_face *fc = &c->w->faces[hit->geom][hit->prim];
  float ng[3], ns[3], flip = 1;
  for (int i = 0; i < 3; i++) sf->p[i] = o[i] + t * d[i], ng[i] = fc->ng[i];
  sf->frame = NULL;
  if (fc->flat) { /* ng already on the normals' side */
    for (int i = 0; i < 3; i++) ns[i] = fc->nrm[0][i];
    sf->frame = &fc->nrm[1];
  } else {
    for (int i = 0; i < 3; i++) ns[i] = b0 * fc->nrm[0][i] + b1 * fc->nrm[1][i] + b2 * fc->nrm[2][i];
    if (normalize(ns) == 0.0f)
      for (int i = 0; i < 3; i++) ns[i] = ng[i];
    if (dot(ns, ng) < 0) flip = -1; /* normals wound against the triangle: trust the normals' side */
  }
  /* two-sided: the side the ray arrives from (the face's frame is that of its own normal) */
  if (flip * dot(d, ng) > 0) flip = -flip, ns[0] = -ns[0], ns[1] = -ns[1], ns[2] = -ns[2], sf->frame = NULL;
  for (int i = 0; i < 3; i++) ng[i] *= flip;
  if (-dot(d, ns) <= 1e-4f) { /* shading normal faces away from the viewer */
    for (int i = 0; i < 3; i++) ns[i] = ng[i];
    sf->frame = NULL;
  }
  for (int i = 0; i < 3; i++) sf->ng[i] = ng[i], sf->ns[i] = ns[i];
  sf->mat_index = c->w->material[hit->geom];
  sf->mat = &c->w->mats[sf->mat_index];
  sf->nfpos = 0, sf->trans = 0, sf->nopen = 0, sf->pback = 0, sf->pscatter = 1;
  if (sf->mat->kind == WV_MAT_FABRIC) fabric_surface(c, ts, hit, camera, sf);
}

/* A fabric's part of the surface at a hit (after make_surface's). */
static __attribute__((noinline)) void fabric_surface(const render_ctx *c, thread_state *ts, const wv_trace_hit *hit,
                                                     int camera, surface *sf) {
  const float b1 = hit->b1, b2 = hit->b2, b0 = 1 - b1 - b2, *ns = sf->ns;
  if (!c->s->opaque) sf->trans = 1, sf->pback = sf->mat->pback;
  /* fabric frame: x along the interpolated u tangent, made orthogonal to ns; y = +-(ns x t) toward +v */
  const wv_face_uv *fu = &c->w->face_uv[hit->geom][hit->prim];
  float w_sign = fu->w_sign, tg[3], bt[3];
  for (int i = 0; i < 3; i++) tg[i] = b0 * fu->tan[0][i] + b1 * fu->tan[1][i] + b2 * fu->tan[2][i];
  float tn = dot(tg, ns);
  for (int i = 0; i < 3; i++) tg[i] -= tn * ns[i];
  if (normalize(tg) == 0.0f) {
    float a[3] = {fabsf(ns[0]) > 0.9f ? 0.0f : 1.0f, fabsf(ns[0]) > 0.9f ? 1.0f : 0.0f, 0};
    cross(ns, a, tg);
    normalize(tg);
  }
  cross(ns, tg, bt);
  for (int i = 0; i < 3; i++) sf->t[i] = tg[i], sf->b[i] = bt[i] * w_sign;
  sf->u = b0 * fu->uv[0][0] + b1 * fu->uv[1][0] + b2 * fu->uv[2][0];
  sf->v = b0 * fu->uv[0][1] + b1 * fu->uv[1][1] + b2 * fu->uv[2][1];
  const wv_world_material *mt = sf->mat;
  eval_edits(mt, sf->u, sf->v, &sf->edit);
  sf->fpos = ts->fpos + (size_t)ts->sample * c->K;
  if (!camera) {
    sf->fpos[0][0] = sf->u * mt->uv_mm[0] + mt->uv_off[0], sf->fpos[0][1] = sf->v * mt->uv_mm[1] + mt->uv_off[1];
    sf->nfpos = 1;
    count_open(c, sf);
    return;
  }
  /* Sub-pixel yarns: K positions spread over the pixel (a stratified set of spp x K
   * per pixel, K of them for this ray), where their camera rays meet this triangle's plane. */
  const wv_camera_rig *r = &c->cam;
  const float *gu = c->w->uv_grad[hit->geom][hit->prim].gu, *gv = c->w->uv_grad[hit->geom][hit->prim].gv;
  float rel[3];
  for (int i = 0; i < 3; i++) rel[i] = sf->p[i] - r->cpos[i];
  float pn = dot(rel, sf->ng); /* camera to the plane, along its normal */
  int px = (int)(ts->pixel % (uint64_t)r->width), py = (int)(ts->pixel / (uint64_t)r->width);
  float(*ydir)[3] = ts->ydir;
  camera_dirs(r, px, py, c->K, (const float(*)[2])ts->yarn + (size_t)ts->sample * c->K, ydir);
  for (int k = 0; k < c->K; k++) {
    float *dd = ydir[k], u = sf->u, v = sf->v;
    float den = dot(dd, sf->ng);
    if (fabsf(den) > 1e-6f && pn / den > 0) {
      float q[3]; /* from the hit to where this sample's ray meets the plane */
      for (int i = 0; i < 3; i++) q[i] = pn / den * dd[i] - rel[i];
      u += dot(gu, q), v += dot(gv, q);
    }
    sf->fpos[k][0] = u * mt->uv_mm[0] + mt->uv_off[0], sf->fpos[k][1] = v * mt->uv_mm[1] + mt->uv_off[1];
  }
  sf->nfpos = c->K;
  count_open(c, sf);
}

/* BSDF x cosine for light arriving from each of nd <= 2 directions wi[j] (world;
 * NULL: not wanted, f[j] = 0), seen from wo, given their cosines with the
 * geometric and the shading normal (side[j], cs[j]) (eval_bsdf): a fabric is shaded
 * for all of them in one call. Light from below the surface passes a transmitting
 * fabric (the geometric and shading normals agreeing on the side), nothing else.
 * In two halves: bsdf_prepare evaluates a Lambert surface and leaves a fabric's
 * wanted directions in its frame (want[j] = li[j] or NULL, the view in lo; returns
 * their count), shade_surface shades them. */
static inline __attribute__((always_inline)) int bsdf_prepare(const surface *sf, thread_state *ts, int nd,
                                                             const float *const *wi, const float *side,
                                                             const float *cs, const float wo[3], float (*f)[3],
                                                             float (*li)[3], const float **want, float lo[3]) {
  int any = 0;
  for (int j = 0; j < nd; j++) {
    f[j][0] = f[j][1] = f[j][2] = 0, want[j] = NULL;
    if (!wi[j]) continue;
    if (side[j] <= 0.0f && !(sf->trans && side[j] < 0.0f)) continue; /* an opaque surface reflects only */
    if (sf->mat->kind == WV_MAT_LAMBERT) {
      if (cs[j] <= 0) continue;
      for (int c = 0; c < 3; c++) f[j][c] = sf->mat->albedo[c] * (cs[j] * INV_PI_F);
      continue;
    }
    li[j][0] = dot(wi[j], sf->t), li[j][1] = dot(wi[j], sf->b), li[j][2] = cs[j];
    if ((side[j] > 0.0f) != (cs[j] > 0.0f)) continue; /* the triangle and the shading normal disagree on the side */
    want[j] = li[j], any++;
    ts->shades += sf->nfpos;
  }
  if (any) lo[0] = dot(wo, sf->t), lo[1] = dot(wo, sf->b), lo[2] = dot(wo, sf->ns);
  return any;
}
/* (eval_bsdf's second half: the fabric's wanted directions, as bsdf_prepare left them) */
static void shade_surface(const surface *sf, thread_state *ts, const float *const *want, const float lo[3],
                          float (*f)[3]) {
  shade_fabric(sf->mat->fab, ts->scratch[sf->mat_index], &sf->edit, 2, want, lo, (const float(*)[2])sf->fpos,
               sf->nfpos, f);
}
static inline __attribute__((always_inline)) void eval_bsdf(const surface *sf, thread_state *ts, int nd,
                                                          const float *const *wi, const float *side,
                                                          const float *cs, const float wo[3], float (*f)[3]) {
  float li[2][3], lo[3];
  const float *want[2] = {NULL, NULL};
  if (bsdf_prepare(sf, ts, nd, wi, side, cs, wo, f, li, want, lo))
    shade_fabric(sf->mat->fab, ts->scratch[sf->mat_index], &sf->edit, nd, want, lo, (const float(*)[2])sf->fpos,
                 sf->nfpos, f);
}

static float power_heuristic(float a, float b) { return a * a / (a * a + b * b); }


/* The bounce's pdf of a direction at cosine cs with the shading normal:
 * cosine-weighted about the shading normal (reflection only), or on a transmitting
 * fabric, the side chosen with pback and cosine-weighted about the normal there,
 * times the probability of scattering here at all (pscatter: not straight through
 * an open gap). */
static float bounce_pdf(const surface *sf, float cs) {
  if (!sf->trans) return cs > 0 ? cs * INV_PI_F : 0.0f;
  return (cs > 0 ? 1.0f - sf->pback : sf->pback) * fabsf(cs) * INV_PI_F * sf->pscatter;
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

/* Next-event estimation toward the point, spot, directional and area lights: one
 * shadow ray each (out of the hot path; scenes with the environment alone skip it). */
static __attribute__((noinline)) void light_samples(const render_ctx *c, thread_state *ts, const surface *sf,
                                                    int depth, int last, const float wo[3], const float org[3],
                                                    const float orgb[3], const float thr[3], float L[3]) {
  const wv_scene3d *s = c->s;
  const wv_world *w = c->w;
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
        for (int k = 0; k < 3; k++) wi[k] = lp[k] - sf->p[k];
        dist = normalize(wi);
        float cosl = -dot(wi, n);
        if (cosl <= 0) continue;
        float pl = dist * dist / ((float)(l->size[0] * l->size[1]) * cosl);
        wgt = last ? 1.0f : power_heuristic(pl, bounce_pdf(sf, dot(wi, sf->ns)));
        g = 1.0f / pl;
      } else {
        for (int k = 0; k < 3; k++) wi[k] = lp[k] - sf->p[k];
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
    float f[1][3], lside = dot(wi, sf->ng), lcs = dot(wi, sf->ns);
    const float *lw[1] = {wi};
    eval_bsdf(sf, ts, 1, lw, &lside, &lcs, wo, f);
    if (maxc(f[0]) <= 0) continue;
    ts->rays++;
    if (wv_tracer_occluded(w->tracer, lside > 0 ? org : orgb, wi, 0.0f, dist)) continue;
    for (int k = 0; k < 3; k++) L[k] += thr[k] * f[0][k] * li[k] * wgt;
  }
}

/* The area lights the path's ray (o, d) meets before its hit, weighed against their
 * samples (out of the hot path). */
static __attribute__((noinline)) void area_hits(const wv_scene3d *s, path *p) {
  float tmax = p->got ? p->hit.t : INFINITY;
  for (int i = 0; i < s->nlights; i++) {
    const wv_light3d *l = &s->lights[i];
    float t, cosl;
    if (l->type != WV_LIGHT_AREA || !hit_area(l, p->o, p->d, tmax, &t, &cosl)) continue;
    float pl = t * t / ((float)(l->size[0] * l->size[1]) * cosl),
          wgt = p->prev_pdf > 0 ? power_heuristic(p->prev_pdf, pl) : 1;
    for (int k = 0; k < 3; k++) p->L[k] += p->thr[k] * (float)l->color[k] * wgt;
  }
}

/* A path whose ray (o, d) meets nothing: the environment it sees, weighed against
 * the environment's samples (render_pixel calls it directly without area lights). */
static inline void escape(const render_ctx *c, path *p) {
  const wv_world *w = c->w;
  if (w->has_env && (p->bounces > 0 || c->s->env_visible)) {
    float le[3], wgt = 1;
    if (p->prev_pdf > 0) wgt = power_heuristic(p->prev_pdf, wv_envmap_read(&w->env, p->at, le));
    else wv_envmap_eval(&w->env, p->d, le);
    for (int k = 0; k < 3; k++) p->L[k] += p->thr[k] * le[k] * wgt;
  }
}

/* The first half of what the path's ray (o, d) meets at vertex p->depth (p->got,
 * p->hit): the surface, the environment's sample and the bounce's direction, with
 * the BSDF of a Lambert surface, and what is left to shade of a fabric (v->nshade
 * directions, v->lwant in its frame). ts->sample is the path's sample. */
WV_SIMD_CLONES static void vertex_begin(const render_ctx *c, thread_state *ts, path *p, vertex *v) {
  const wv_scene3d *s = c->s;
  const wv_world *w = c->w;
  const int depth = p->depth;
  const float *d = p->d;
  surface *sf = &v->sf;
  make_surface(c, ts, &p->hit, p->o, d, depth == 0, sf);
  /* on a planar object, rays leaving it from the side the path came from (from org)
   * cannot meet it again: render_pixel tests them against the other objects' box */
  v->plane = c->cull && w->planar[p->hit.geom] ? p->hit.geom : -1;
  p->leave = -1;
  float *org = v->org, *orgb = v->orgb, *side = v->side, *cs = v->cs, *ewi = v->ewi, *ele = v->ele, *bwi = v->bwi;
  for (int i = 0; i < 3; i++) v->wo[i] = -d[i];
  int last = v->last = p->bounces >= s->max_bounces; /* no bounce follows: light samples take the whole weight */
  /* ray origins on the side the ray came from, and on the other (light through the sheet) */
  for (int i = 0; i < 3; i++) org[i] = sf->p[i] + c->eps * sf->ng[i], orgb[i] = sf->p[i] - c->eps * sf->ng[i];
  /* Straight through an open gap with the probability of the positions' open fraction
   * (the kernel shades those positions 0), else scatter: the light samples below are
   * taken either way, the bounce only when scattering. The bounce's numbers make the
   * choice (u1 below the open fraction), so it is stratified as they are; u1 is then
   * stretched back over 0..1 for the bounce. */
  float u1 = 0, u2 = 0;
  if (!last) rand2(c, ts, depth, 2, &u1, &u2);
  else if (sf->nopen) u1 = wv_u01(wv_hash4(ts->pixel, (uint64_t)ts->sample, (uint64_t)(16 * depth + 10), s->seed));
  int pass = 0;
  if (sf->nopen) {
    float po = 1.0f - sf->pscatter;
    pass = sf->nopen == sf->nfpos || u1 < po;
    if (!pass) u1 = min2((u1 - po) / sf->pscatter, ONE_BELOW);
  }
  v->pass = pass;
  /* the environment's sample and the bounce direction first: the surface is
   * evaluated for both in one call */
  for (int k = 0; k < 3; k++) ewi[k] = ele[k] = bwi[k] = 0;
  v->epl = 0, v->bpdf = 0, side[0] = side[1] = cs[0] = cs[1] = 0; /* cosines with the normals ng and ns */
  int env_on = 0;
  if (w->has_env) {
    if (depth < CMJ_DEPTHS) {
      const wv_env_sample *es = &ts->env[depth * c->spp + ts->sample];
      memcpy(ewi, es->d, sizeof v->ewi), memcpy(ele, es->rgb, sizeof v->ele), v->epl = es->pdf;
    } else {
      float e1, e2;
      rand2(c, ts, depth, 0, &e1, &e2);
      v->epl = wv_envmap_sample(&w->env, e1, e2, ewi, ele);
    }
    env_on = v->epl > 0 && any_pos(ele);
    if (env_on) side[0] = dot(ewi, sf->ng), cs[0] = dot(ewi, sf->ns);
    /* through the sheet, the sample is taken with the probability min(1, 2 pback) (and
     * weighed up by its inverse): behind cloth that transmits little it seldom adds
     * much, and most of it would be shadow rays blocked under the cloth */
    if (env_on && sf->trans && side[0] < 0) {
      float q = min2(1.0f, 2.0f * sf->pback);
      if (q < 1.0f) {
        env_on = wv_u01(wv_hash4(ts->pixel, (uint64_t)ts->sample, (uint64_t)(16 * depth + 12), s->seed)) < q;
        float iq = 1.0f / q;
        for (int k = 0; k < 3; k++) ele[k] *= iq;
      }
    }
  }
  v->env_on = env_on;
  if (!last && !pass) { /* bounce: cosine-weighted about the shading normal, or through a transmitting fabric */
    int below = 0; /* through the sheet where u2 falls below pback, u2 then stretched back over 0..1 */
    if (sf->trans) {
      below = u2 < sf->pback;
      u2 = below ? u2 / sf->pback : min2((u2 - sf->pback) / (1.0f - sf->pback), ONE_BELOW);
    }
    float r = sqrtf(u1), cphi, sphi, lz = sqrtf(max2(0.0f, 1 - u1));
    wv_turn(&c->turn, u2, &cphi, &sphi);
    float lx = r * cphi, ly = r * sphi;
    if (below) lz = -lz;
    float bx[3], by[3];
    if (sf->frame) memcpy(bx, sf->frame[0], sizeof bx), memcpy(by, sf->frame[1], sizeof by);
    else frame(sf->ns, bx, by);
    for (int k = 0; k < 3; k++) bwi[k] = lx * bx[k] + ly * by[k] + lz * sf->ns[k];
    side[1] = dot(bwi, sf->ng), cs[1] = dot(bwi, sf->ns);
    v->bpdf = bounce_pdf(sf, cs[1]);
  }
  const float *want[2] = {env_on ? ewi : NULL, v->bpdf > 0 ? bwi : NULL};
  v->nshade = bsdf_prepare(sf, ts, 2, want, side, cs, v->wo, v->fb, v->li, v->lwant, v->lo);
}

/* The rest of path_vertex's vertex, its BSDF evaluated (v->fb): the light samples, the
 * shadow ray toward the environment's sample, and the next ray. Returns 0 when the
 * path ends. */
WV_SIMD_CLONES static int vertex_end(const render_ctx *c, thread_state *ts, path *p, vertex *v) {
  const wv_scene3d *s = c->s;
  const int depth = p->depth, last = v->last;
  const surface *sf = &v->sf;
  float *thr = p->thr, (*fb)[3] = v->fb;
  if (s->nlights) light_samples(c, ts, sf, depth, last, v->wo, v->org, v->orgb, thr, p->L); /* next-event estimation */
  if (v->env_on && any_pos(fb[0])) {
    ts->rays++;
    /* the power heuristic's weight over the pdf, epl / (epl^2 + bounce pdf^2), in one division */
    float bp = last ? 0.0f : bounce_pdf(sf, v->cs[0]), ws = v->epl / (v->epl * v->epl + bp * bp);
    p->shadow = 1, p->sh_leave = v->side[0] > 0 ? v->plane : -1;
    memcpy(p->sh_o, v->side[0] > 0 ? v->org : v->orgb, sizeof p->sh_o), memcpy(p->sh_d, v->ewi, sizeof p->sh_d);
    for (int k = 0; k < 3; k++) p->sh_add[k] = thr[k] * fb[0][k] * v->ele[k] * ws;
  }
  if (v->pass) { /* straight on from the far side: the throughput stays (probability and weight both the open fraction) */
    if (depth >= PASS_MAX) return 0;
    memcpy(p->o, v->orgb, sizeof p->o);
    p->prev_pdf = 0; /* no light sample sees through the gap: what the ray meets counts whole */
    p->depth++;
    return 1;
  }
  if (last || v->bpdf <= 0) return 0;
  if (sf->mat->kind == WV_MAT_LAMBERT) { /* (albedo cos / pi) / (cos / pi) */
    for (int k = 0; k < 3; k++) thr[k] *= v->side[1] > 0.0f ? sf->mat->albedo[k] : 0.0f;
  } else {
    float ib = 1.0f / v->bpdf;
    for (int k = 0; k < 3; k++) thr[k] *= fb[1][k] * ib;
  }
  float q = min2(0.95f, maxc(thr));
  if (q <= 0) return 0;
  if (p->bounces >= 1) { /* Russian roulette from the third path vertex on */
    uint64_t h = wv_hash4(ts->pixel, (uint64_t)ts->sample, (uint64_t)(16 * depth + 9), s->seed);
    if (wv_u01(h) >= q) return 0;
    float iq = 1.0f / q;
    for (int k = 0; k < 3; k++) thr[k] *= iq;
  }
  memcpy(p->o, v->side[1] > 0 ? v->org : v->orgb, sizeof p->o);
  memcpy(p->d, v->bwi, sizeof p->d);
  p->leave = v->side[1] > 0 ? v->plane : -1;
  p->prev_pdf = v->bpdf;
  p->depth++, p->bounces++;
  return 1;
}

/* Lanes of shade_waiting: m of them shaded, each result added to its sum. */
static void shade_flush(const wv_fabric *f, int m, const float (*lp)[2], const float (*lw)[3], const float (*lo)[3],
                        float *const *dst) {
  float r[8][3];
  shade_lanes(f, m, lp, lw, lo[0], 3, r);
  for (int i = 0; i < m; i++)
    for (int c = 0; c < 3; c++) dst[i][c] += r[i][c];
}

/* The fabric vertices ts->dq[0 .. nq-1] (without edits) shaded together: the
 * positions of their wanted directions, eight lanes (vertex, direction, position) to
 * a kernel call, a call's lanes all of one fabric; each sum over the positions in
 * shade_fabric's order, and its mean, as shade_fabric gives it. */
static void shade_waiting(thread_state *ts, int nq) {
  float lp[8][2], lw[8][3], lo[8][3], *dst[8];
  const wv_fabric *f = NULL;
  int m = 0;
  for (int q = 0; q < nq; q++) {
    vertex *v = &ts->vtx[ts->dq[q]];
    for (int j = 0; j < 2; j++) {
      if (!(v->lwant[j] && v->lwant[j][2] != 0.0f && v->lo[2] > 0.0f)) continue; /* as shade_fabric's */
      for (int k = 0; k < v->sf.nfpos; k++) {
        if (m == 8 || (m && v->sf.mat->fab != f)) shade_flush(f, m, lp, lw, lo, dst), m = 0;
        f = v->sf.mat->fab;
        memcpy(lp[m], v->sf.fpos[k], sizeof lp[m]), memcpy(lw[m], v->lwant[j], sizeof lw[m]);
        memcpy(lo[m], v->lo, sizeof lo[m]), dst[m++] = v->fb[j];
      }
    }
  }
  if (m) shade_flush(f, m, lp, lw, lo, dst);
  for (int q = 0; q < nq; q++) {
    vertex *v = &ts->vtx[ts->dq[q]];
    float inv = 1.0f / (float)v->sf.nfpos;
    for (int j = 0; j < 2; j++)
      if (v->lwant[j] && v->lwant[j][2] != 0.0f && v->lo[2] > 0.0f)
        v->fb[j][0] *= inv, v->fb[j][1] *= inv, v->fb[j][2] *= inv;
  }
}

/* After path p's vertex (on: it goes on): its shadow ray and its next ray into the
 * pixel's lists for the tracer, unless the box around the other objects decides them. */
static inline __attribute__((always_inline)) void queue_rays(const wv_world *w, thread_state *ts, path *p, int j,
                                                           int on, int *nsh, int *nb, int *nt) {
  if (p->shadow) {
    if (p->sh_leave >= 0 && wv_world_leaves_scene(w, p->sh_leave, p->sh_o, p->sh_d)) { /* unblocked */
      for (int k = 0; k < 3; k++) p->L[k] += p->sh_add[k];
    } else {
      memcpy(ts->sh_o[*nsh], p->sh_o, sizeof p->sh_o), memcpy(ts->sh_d[*nsh], p->sh_d, sizeof p->sh_d);
      ts->sh_t[*nsh] = INFINITY, ts->sh_idx[(*nsh)++] = j;
    }
  }
  if (!on) return;
  ts->act[(*nb)++] = j;
  if (p->leave >= 0 && wv_world_leaves_scene(w, p->leave, p->o, p->d)) { /* escapes */
    p->got = 0;
    return;
  }
  memcpy(ts->dir[*nt], p->d, sizeof p->d), memcpy(ts->org[*nt], p->o, sizeof p->o);
  ts->idx[(*nt)++] = j; /* (the vertex's list is no longer needed) */
}

/* The stratified numbers of path vertex depth (environment, area light, bounce)
 * for the samples idx[0 .. m-1], the paths that reach a surface there, and their
 * environment samples. */
static void draw_depth(const render_ctx *c, thread_state *ts, int px, int py, int depth, const int *idx, int m) {
  if (!m || depth >= CMJ_DEPTHS) return;
  const int spp = c->spp;
  for (int which = 0; which < 3; which++) {
    int k = 1 + 3 * depth + which;
    if (c->need[k])
      draw_sequence(px, py, spp, c->s->width, wv_mix64(c->s->seed + 0x51ed27ULL * (uint64_t)k), idx, m,
                    ts->u + (size_t)k * spp);
  }
  if (!c->need[1 + 3 * depth]) return;
  const float(*u)[2] = (const float(*)[2])ts->u + (size_t)(1 + 3 * depth) * spp;
  for (int i = 0; i < m; i++) ts->ug[i][0] = u[idx[i]][0], ts->ug[i][1] = u[idx[i]][1];
  wv_envmap_sample_n(&c->w->env, m, (const float(*)[2])ts->ug, ts->eg);
  for (int i = 0; i < m; i++) ts->env[(size_t)depth * spp + idx[i]] = ts->eg[i];
}

/* Starts fetching what make_surface reads of the n hits (got[i]: a hit) into the
 * second-level cache, while the paths before them are handled (prefetch_path
 * brings each into the first shortly before its turn). */
static void prefetch_hits(const wv_world *w, const wv_trace_hit *hit, const int *got, int n) {
  for (int i = 0; i < n; i++) {
    if (!got[i]) continue;
    __builtin_prefetch(&w->faces[hit[i].geom][hit[i].prim], 0, 2);
    if (w->face_uv[hit[i].geom]) __builtin_prefetch(&w->face_uv[hit[i].geom][hit[i].prim], 0, 2);
  }
}
static void prefetch_path(const wv_world *w, const path *p) {
  if (p->got) {
    __builtin_prefetch(&w->faces[p->hit.geom][p->hit.prim]);
    if (w->face_uv[p->hit.geom]) __builtin_prefetch(&w->face_uv[p->hit.geom][p->hit.prim]);
  } else if (w->has_env) {
    __builtin_prefetch(w->env.texel + 4 * p->at.texel);
  }
}

/* The pixel's spp paths, taken together from vertex to vertex: each vertex's
 * stratified numbers and environment samples are drawn, in batches, only for the
 * paths that reach a surface there, and the paths' shadow rays toward the
 * environment and their bounce rays are traced as streams. Each path is the same
 * as traced alone, and the mean is summed in sample order. */
WV_SIMD_CLONES static void render_pixel(const render_ctx *c, thread_state *ts, int px, int py, float out[3]) {
  const wv_scene3d *s = c->s;
  const wv_world *w = c->w;
  const int spp = c->spp, K = c->K;
  path *P = ts->paths;
  ts->pixel = (uint64_t)py * (uint64_t)s->width + (uint64_t)px;
  draw_sequence(px, py, spp, s->width, s->seed, NULL, spp, ts->u);
  camera_dirs(&c->cam, px, py, spp, (const float(*)[2])ts->u, ts->dir);
  wv_tracer_intersect_from(w->tracer, c->cam.cpos, (const float(*)[3])ts->dir, spp, ts->hit, ts->got);
  prefetch_hits(w, ts->hit, ts->got, spp);
  int nyarn = 0;
  for (int j = 0; j < spp; j++) {
    path *p = &P[j];
    memcpy(p->o, c->cam.cpos, sizeof p->o), memcpy(p->d, ts->dir[j], sizeof p->d);
    p->thr[0] = p->thr[1] = p->thr[2] = 1, p->L[0] = p->L[1] = p->L[2] = 0;
    p->prev_pdf = 0, p->depth = 0, p->bounces = 0, p->got = ts->got[j], p->at = (wv_env_at){0};
    ts->act[j] = j;
    if (!p->got) continue;
    p->hit = ts->hit[j];
    if (w->mats[w->material[p->hit.geom]].kind == WV_MAT_FABRIC)
      for (int k = 0; k < K; k++) ts->yidx[nyarn++] = j * K + k;
  }
  ts->rays += spp;
  if (nyarn) draw_sequence(px, py, spp * K, s->width, wv_mix64(s->seed ^ 0x7961726eULL), ts->yidx, nyarn, ts->yarn);
  for (int depth = 0, n = spp; n > 0; depth++) { /* the n paths in act reach vertex depth */
    int m = 0, nsh = 0, nb = 0, nt = 0, nq = 0; /* nt of the nb rays that go on need the tracer */
    for (int i = 0; i < n; i++)
      if (P[ts->act[i]].got) ts->idx[m++] = ts->act[i];
    draw_depth(c, ts, px, py, depth, ts->idx, m);
    for (int i = 0; i < n; i++) {
      int j = ts->act[i];
      path *p = &P[j];
      if (i + 4 < n) prefetch_path(w, &P[ts->act[i + 4]]);
      if (s->nlights) area_hits(s, p); /* area lights the ray sees before the surface */
      if (!p->got) {
        escape(c, p);
        continue;
      }
      ts->sample = j, p->shadow = 0;
      vertex *v = &ts->vtx[j];
      vertex_begin(c, ts, p, v);
      if (v->nshade && !v->sf.edit.active) { /* shaded with the others like it, below */
        ts->dq[nq++] = j;
        continue;
      }
      if (v->nshade) shade_surface(&v->sf, ts, v->lwant, v->lo, v->fb);
      queue_rays(w, ts, p, j, vertex_end(c, ts, p, v), &nsh, &nb, &nt);
    }
    shade_waiting(ts, nq);
    for (int q = 0; q < nq; q++) {
      int j = ts->dq[q];
      ts->sample = j;
      queue_rays(w, ts, &P[j], j, vertex_end(c, ts, &P[j], &ts->vtx[j]), &nsh, &nb, &nt);
    }
    wv_tracer_occluded_n(w->tracer, (const float(*)[3])ts->sh_o, (const float(*)[3])ts->sh_d, ts->sh_t, nsh,
                         ts->sh_occ);
    for (int i = 0; i < nsh; i++)
      if (!ts->sh_occ[i])
        for (int k = 0; k < 3; k++) P[ts->sh_idx[i]].L[k] += P[ts->sh_idx[i]].sh_add[k];
    ts->rays += nb;
    wv_tracer_intersect_n(w->tracer, (const float(*)[3])ts->org, (const float(*)[3])ts->dir, nt, ts->hit, ts->got);
    prefetch_hits(w, ts->hit, ts->got, nt);
    for (int i = 0; i < nt; i++) {
      path *p = &P[ts->idx[i]];
      p->got = ts->got[i];
      if (p->got) p->hit = ts->hit[i];
    }
    for (int i = 0; i < nb; i++) { /* the environment's texel of a bounce ray that escapes, read at the next vertex */
      path *p = &P[ts->act[i]];
      p->at = (wv_env_at){0};
      if (!p->got && w->has_env && p->prev_pdf > 0) p->at = wv_envmap_at(&w->env, p->d);
    }
    n = nb;
  }
  double acc[3] = {0, 0, 0};
  for (int j = 0; j < spp; j++)
    for (int k = 0; k < 3; k++) acc[k] += isfinite(P[j].L[k]) ? P[j].L[k] : 0.0f;
  for (int k = 0; k < 3; k++) out[k] = (float)(acc[k] / spp);
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
  c.cull = c.eps >= 4 * w->plane_tol;
  wv_turn_table_make(&c.turn);
  /* the stratified dimensions a path can use: camera; per depth environment, area light, bounce */
  int area = 0;
  for (int i = 0; i < s->nlights; i++) area |= s->lights[i].type == WV_LIGHT_AREA;
  for (int m = 0; m < w->nmats; m++)
    c.gaps |= !s->opaque && w->mats[m].kind == WV_MAT_FABRIC && w->mats[m].fab->ym.width < 1.0f;
  /* (a path through a gap reaches vertex d after fewer than d bounces) */
  c.need[0] = 1;
  for (int d = 0; d < CMJ_DEPTHS; d++)
    c.need[1 + 3 * d] = w->has_env && (d <= s->max_bounces || c.gaps),
                 c.need[2 + 3 * d] = area && (d <= s->max_bounces || c.gaps),
                 c.need[3 + 3 * d] = d < s->max_bounces || (c.gaps && s->max_bounces > 0);
  int threads = opt && opt->threads > 0 ? opt->threads : omp_get_max_threads();
  wv_image rad;
  wv_status st = wv_image_alloc(&rad, s->width, s->height, 3, err);
  if (st) return st;
  if ((st = wv_image_alloc(capture, s->width, s->height, 3, err))) {
    wv_image_free(&rad);
    return st;
  }
  const size_t spp = (size_t)c.spp, K = (size_t)c.K;
  thread_state *ts = aligned_alloc(_Alignof(thread_state), (size_t)threads * sizeof *ts); /* no line shared by two threads */
  if (ts) memset(ts, 0, (size_t)threads * sizeof *ts);
  int fail = !ts;
  for (int t = 0; t < threads && !fail; t++) {
    thread_state *me = &ts[t];
    me->scratch = calloc((size_t)w->nmats, sizeof *me->scratch);
    me->fpos = malloc(sizeof *me->fpos * spp * K);
    me->u = malloc(sizeof *me->u * (1 + 3 * CMJ_DEPTHS) * spp);
    me->yarn = malloc(sizeof *me->yarn * spp * K);
    me->env = malloc(sizeof *me->env * CMJ_DEPTHS * spp);
    me->dir = malloc(sizeof *me->dir * spp);
    me->org = malloc(sizeof *me->org * spp);
    me->sh_o = malloc(sizeof *me->sh_o * spp), me->sh_d = malloc(sizeof *me->sh_d * spp);
    me->sh_t = malloc(sizeof *me->sh_t * spp), me->sh_idx = malloc(sizeof *me->sh_idx * spp);
    me->sh_occ = malloc(sizeof *me->sh_occ * spp);
    me->ydir = malloc(sizeof *me->ydir * K);
    me->hit = malloc(sizeof *me->hit * spp);
    me->got = malloc(sizeof *me->got * spp);
    me->paths = malloc(sizeof *me->paths * spp);
    me->idx = malloc(sizeof *me->idx * spp);
    me->act = malloc(sizeof *me->act * spp);
    me->yidx = malloc(sizeof *me->yidx * spp * K);
    me->ug = malloc(sizeof *me->ug * spp);
    me->eg = malloc(sizeof *me->eg * spp);
    me->vtx = malloc(sizeof *me->vtx * spp), me->dq = malloc(sizeof *me->dq * spp);
    fail |= !me->scratch || !me->fpos || !me->u || !me->yarn || !me->env || !me->dir || !me->org || !me->sh_o ||
            !me->sh_d || !me->sh_t || !me->sh_idx || !me->sh_occ || !me->ydir || !me->hit || !me->got || !me->paths ||
            !me->idx || !me->act || !me->yidx || !me->ug || !me->eg || !me->vtx || !me->dq;
    for (int m = 0; m < w->nmats && !fail; m++)
      if (w->mats[m].nedits) {
        fail |= !(me->scratch[m] = malloc(sizeof(wv_fabric)));
        if (!fail) *me->scratch[m] = *w->mats[m].fab;
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
      for (int px = 0; px < s->width; px++) render_pixel(&c, me, px, py, wv_image_px(&rad, px, py));
#pragma omp atomic update
      rows_done++;
    }
  }
  double rays = 0, shades = 0;
  for (int t = 0; t < threads && ts; t++) {
    thread_state *me = &ts[t];
    rays += me->rays, shades += me->shades;
    for (int m = 0; m < w->nmats && me->scratch; m++) free(me->scratch[m]);
    free(me->scratch), free(me->fpos), free(me->u), free(me->yarn), free(me->env);
    free(me->dir), free(me->org), free(me->sh_o), free(me->sh_d), free(me->sh_t), free(me->sh_idx), free(me->sh_occ), free(me->ydir), free(me->hit), free(me->got), free(me->paths), free(me->idx), free(me->act), free(me->yidx), free(me->ug);
    free(me->eg), free(me->vtx), free(me->dq);
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
