#include "woven/yarn.h"

#include <math.h>

#include "yarn/yarn_eval.h"

#define PI_F 3.14159265358979f

void wv_yarn_model_update(wv_yarn_model *m) {
  for (int y = 0; y < 2; y++) {
    m->inv_spacing[y] = 1.0f / m->spacing[y];
    m->umax_over_spacing[y] = m->umax / m->spacing[y];
    m->v_scale[y] = PI_F / (m->spacing[y] * m->width);
  }
  m->sin_psi = sinf(m->psi), m->cos_psi = cosf(m->psi);
  m->sin_umax = sinf(m->umax), m->cos_umax = cosf(m->umax);
}

void wv_yarn_frame(float u, float v, float sp, float cp, float n[3], float t[3]) {
  wv_yarn_frame_inline(u, v, sp, cp, n, t);
}

void wv_yarn_scale(float beta, float n[3], float t[3]) { wv_yarn_scale_inline(beta, n, t); }

void wv_yarn_eval(const wv_yarn_model *m, float x, float y, wv_yarn_point *out) {
  wv_yarn_eval_inline(m, x, y, out);
}
