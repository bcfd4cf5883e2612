#include "woven/yarn.h"

#include <math.h>

#include "util/fastmath.h"
#include "util/hash.h"

#define PI_F 3.14159265358979f

void wv_yarn_frame(float u, float v, float psi, float n[3], float t[3]) {
  float su = wv_sin_hp(u), cu = wv_cos_hp(u), sv = wv_sin_hp(v), cv = wv_cos_hp(v);
  float sp = sinf(psi), cp = cosf(psi);
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
void wv_yarn_scale(float beta, float n[3], float t[3]) {
  float nx = beta * n[0], ny = beta * n[1], nz = n[2];
  float ln = sqrtf(nx * nx + ny * ny + nz * nz);
  if (ln < 1e-12f) { /* yarn silhouette flattened completely: face up */
    nx = 0, ny = 0, nz = 1, ln = 1;
  }
  n[0] = nx / ln, n[1] = ny / ln, n[2] = nz / ln;
  float tx = t[0], ty = t[1], tz = beta * t[2];
  float lt = sqrtf(tx * tx + ty * ty + tz * tz);
  if (lt < 1e-12f) { /* fiber along z at beta 0: any in-plane tangent is valid */
    tx = 0, ty = 1, tz = 0, lt = 1;
  }
  t[0] = tx / lt, t[1] = ty / lt, t[2] = tz / lt;
}

static inline int64_t wrap(int64_t v, int period) {
  if (period <= 0) return v;
  int64_t r = v % period;
  return r < 0 ? r + period : r;
}

void wv_yarn_eval(const wv_yarn_model *m, float x, float y, wv_yarn_point *out) {
  const float dx = m->spacing[WV_WARP], dy = m->spacing[WV_WEFT];
  float r = -y / dy, c = x / dx;
  float rf = floorf(r), cf = floorf(c);
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
    seg = wv_hash4(0, (uint64_t)wrap(J, m->period_cols), (uint64_t)wrap(I - cell->index, m->period_rows),
                   m->seed);
  } else {
    a = (fr - 0.5f) * dy;
    l = ((k + fc) - 0.5f * L) * dx;
    d_across = dy, d_along = dx;
    seg = wv_hash4(1, (uint64_t)wrap(I, m->period_rows), (uint64_t)wrap(J - cell->index, m->period_cols),
                   m->seed);
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
  float u = (l / half_len) * m->umax;
  float v = (a / half_w) * (0.5f * PI_F);
  float beta = m->beta[type];
  if (m->noise_level > 0) {
    float xi = wv_u01(wv_mix64(seg ^ 0x5851f42d4c957f2dULL));
    beta = fmaxf(0.0f, beta * (1.0f + 0.1f * (float)m->noise_level * (2.0f * xi - 1.0f)));
  }
  float n[3], t[3];
  wv_yarn_frame(u, v, m->psi, n, t);
  wv_yarn_scale(beta, n, t);
  if (type == WV_WEFT) { /* rotate the +y yarn frame by -90 degrees about z: +y -> +x */
    float n0 = n[0], t0 = t[0];
    n[0] = n[1], n[1] = -n0;
    t[0] = t[1], t[1] = -t0;
  }
  for (int i = 0; i < 3; i++) out->n[i] = n[i], out->t[i] = t[i];
  /* Height: circular cross-section plus an arc along the yarn whose end slope is umax. */
  float su = sinf(m->umax);
  float rho = su > 1e-6f ? half_len / su : 0.0f;
  out->height = beta * (half_w * wv_cos_hp(v) + rho * (wv_cos_hp(u) - cosf(m->umax)));
  out->type = type;
  out->u = u, out->v = v, out->beta = beta;
}
