/* The yarn model's derived fields and the public per-point evaluation
 * (wv_yarn_eval: the shading kernel's geometry in scalar float, plus the
 * height the maps need). */
#include "woven/yarn.h"

#include <math.h>

#include "kernel/kernel.h"

#define PI_F 3.14159265358979f

void wv_yarn_model_update(wv_yarn_model *m) {
  for (int y = 0; y < 2; y++) {
    m->inv_spacing[y] = 1.0f / m->spacing[y];
    m->umax_over_spacing[y] = m->umax / m->spacing[y];
    m->v_scale[y] = PI_F / (m->spacing[y] * m->width);
  }
  m->sin_psi = sinf(m->psi), m->cos_psi = cosf(m->psi);
  m->sin_umax = sinf(m->umax), m->cos_umax = cosf(m->umax);
  for (int r = 0; r < WV_WEAVE_MAX; r++)
    for (int c = 0; c < WV_WEAVE_MAX; c++) {
      const wv_weave_cell *ce = &m->weave.cell[r][c];
      m->cellpack[r * WV_WEAVE_MAX + c] = ce->type | ce->len << 8 | ce->index << 16;
    }
}

void wv_yarn_eval(const wv_yarn_model *m, float x, float y, wv_yarn_point *out) {
  wv_yarn_cell_f c;
  wv_yarn_locate_f(m, x, y, &c);
  out->segment = wv_yarn_segment_f(m, &c);
  if (!c.lit) { /* gap between yarns narrower than their spacing */
    out->type = -1;
    out->n[0] = 0, out->n[1] = 0, out->n[2] = 1;
    out->t[0] = 0, out->t[1] = 1, out->t[2] = 0;
    out->height = 0, out->u = 0, out->v = 0, out->beta = 0;
    return;
  }
  wv_shade_params_f P;
  wv_shade_params_from_yarn(m, &P);
  wv_yarn_frame_f f;
  wv_yarn_shape_f(m, &P, &c, &f, NULL);
  wv_to_fabric_f(c.warp, f.n, out->n);
  wv_to_fabric_f(c.warp, f.t, out->t);
  /* Height: circular cross-section plus an arc along the yarn whose end slope is umax. */
  float rho = m->sin_umax > 1e-6f ? c.half_len / m->sin_umax : 0.0f;
  out->height = f.beta * (c.half_w * wv_cos_hp_f(f.v) + rho * (wv_cos_hp_f(f.u) - m->cos_umax));
  out->type = c.warp ? WV_WARP : WV_WEFT;
  out->u = f.u, out->v = f.v, out->beta = f.beta;
}
