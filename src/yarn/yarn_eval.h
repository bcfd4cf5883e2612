/* The per-point yarn evaluation, inline so the renderer's inner loop can drop
 * the outputs it does not use. Internal to the library. */
#ifndef WOVEN_YARN_EVAL_H
#define WOVEN_YARN_EVAL_H

#include <math.h>

#include "util/fastmath.h"
#include "util/hash.h"
#include "woven/yarn.h"

#define WV_PI_F 3.14159265358979f

static inline void wv_yarn_frame_inline(float u, float v, float sp, float cp, float n[3], float t[3]) {
  float su = wv_sin_hp(u), cu = wv_cos_hp(u), sv = wv_sin_hp(v), cv = wv_cos_hp(v);
  n[0] = sv;
  n[1] = su * cv;
  n[2] = cu * cv;
  t[0] = -cv * sp;
  t[1] = cu * cp + su * sv * sp;
  t[2] = -su * cp + cu * sv * sp;
}

/* SPEC scales t's x,y by k = -n'_z t_z / (n'_x t_x + n'_y t_y). Substituting
 * n' = (beta n_x, beta n_y, n_z)/|.| and n.t = 0 gives k = 1/beta exactly, so we
 * scale t_z by beta instead: the same direction, without the 0/0 at t_z = 0. */
static inline void wv_yarn_scale_inline(float beta, float n[3], float t[3]) {
  float nx = beta * n[0], ny = beta * n[1], nz = n[2];
  float ln2 = nx * nx + ny * ny + nz * nz;
  if (ln2 < 1e-24f) { /* yarn silhouette flattened completely: face up */
    nx = 0, ny = 0, nz = 1, ln2 = 1;
  }
  float il = 1.0f / sqrtf(ln2);
  n[0] = nx * il, n[1] = ny * il, n[2] = nz * il;
  float tx = t[0], ty = t[1], tz = beta * t[2];
  float lt2 = tx * tx + ty * ty + tz * tz;
  if (lt2 < 1e-24f) { /* fiber along z at beta 0: any in-plane tangent is valid */
    tx = 0, ty = 1, tz = 0, lt2 = 1;
  }
  float it = 1.0f / sqrtf(lt2);
  t[0] = tx * it, t[1] = ty * it, t[2] = tz * it;
}

static inline int64_t wrap(int64_t v, int period) {
  if (period <= 0) return v;
  int64_t r = v % period;
  return r < 0 ? r + period : r;
}

static inline void wv_yarn_eval_inline(const wv_yarn_model *m, float x, float y, wv_yarn_point *out) {
  const float dx = m->spacing[WV_WARP], dy = m->spacing[WV_WEFT];
  float r = -y * m->inv_spacing[WV_WEFT], c = x * m->inv_spacing[WV_WARP];
  float rf = (float)wv_floor_ll(r), cf = (float)wv_floor_ll(c);
  int64_t I = (int64_t)rf, J = (int64_t)cf;
  float fr = r - rf, fc = c - cf;
  const wv_weave_cell *cell = wv_weave_at(&m->weave, I, J);
  int type = cell->type;
  float L = (float)cell->len, k = (float)cell->index;

  /* Local coordinates: a across the yarn, l along it (see yarn.h for the frame). */
  float a, l, d_across, d_along;
  uint64_t seg;
  if (type == WV_WARP) {
    a = (fc - 0.5f) * dx;
    l = -((k + fr) - 0.5f * L) * dy;
    d_across = dx, d_along = dy;
    seg = wv_hash2((uint64_t)wrap(J, m->period_cols) << 1, (uint64_t)wrap(I - cell->index, m->period_rows), m->seed);
  } else {
    a = (fr - 0.5f) * dy;
    l = ((k + fc) - 0.5f * L) * dx;
    d_across = dy, d_along = dx;
    seg = wv_hash2(((uint64_t)wrap(I, m->period_rows) << 1) | 1, (uint64_t)wrap(J - cell->index, m->period_cols), m->seed);
  }
  float half_w = 0.5f * d_across * m->width;
  float half_len = 0.5f * L * d_along;
  out->segment = seg;
  if (fabsf(a) > half_w) { /* gap between yarns narrower than their spacing */
    out->type = -1;
    out->n[0] = 0, out->n[1] = 0, out->n[2] = 1;
    out->t[0] = 0, out->t[1] = 1, out->t[2] = 0;
    out->height = 0, out->u = 0, out->v = 0, out->beta = 0;
    return;
  }
  static const float INV_LEN[WV_WEAVE_MAX + 1] = {
      0,        1,        1.f / 2,  1.f / 3,  1.f / 4,  1.f / 5,  1.f / 6,  1.f / 7,  1.f / 8,
      1.f / 9,  1.f / 10, 1.f / 11, 1.f / 12, 1.f / 13, 1.f / 14, 1.f / 15, 1.f / 16, 1.f / 17,
      1.f / 18, 1.f / 19, 1.f / 20, 1.f / 21, 1.f / 22, 1.f / 23, 1.f / 24, 1.f / 25, 1.f / 26,
      1.f / 27, 1.f / 28, 1.f / 29, 1.f / 30, 1.f / 31, 1.f / 32};
  /* u = l / (L d_along / 2) * umax,  v = a / (w/2) * pi/2, without divisions */
  float u = l * (2.0f * INV_LEN[cell->len]) * m->umax_over_spacing[type ^ 1];
  float v = a * m->v_scale[type];
  float beta = m->beta[type];
  if (m->noise_level > 0) {
    float xi = wv_u01(wv_mix64(seg ^ 0x5851f42d4c957f2dULL));
    beta = beta * (1.0f + 0.1f * (float)m->noise_level * (2.0f * xi - 1.0f));
    beta = beta > 0.0f ? beta : 0.0f;
  }
  float n[3], t[3];
  wv_yarn_frame_inline(u, v, m->sin_psi, m->cos_psi, n, t);
  wv_yarn_scale_inline(beta, n, t);
  if (type == WV_WEFT) { /* rotate the +y yarn frame by -90 degrees about z: +y -> +x */
    float n0 = n[0], t0 = t[0];
    n[0] = n[1], n[1] = -n0;
    t[0] = t[1], t[1] = -t0;
  }
  for (int i = 0; i < 3; i++) out->n[i] = n[i], out->t[i] = t[i];
  /* Height: circular cross-section plus an arc along the yarn whose end slope is umax. */
  float rho = m->sin_umax > 1e-6f ? half_len / m->sin_umax : 0.0f;
  out->height = beta * (half_w * wv_cos_hp(v) + rho * (wv_cos_hp(u) - m->cos_umax));
  out->type = type;
  out->u = u, out->v = v, out->beta = beta;
}

#endif
