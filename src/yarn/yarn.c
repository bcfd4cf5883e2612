/* The yarn model: built from the fabric parameters, and its derived fields.
 * (Its per-point evaluation, wv_yarn_eval, is the shading kernel's: src/kernel/.) */
#include "woven/yarn.h"

#include <math.h>
#include <string.h>

#define PI_F 3.14159265358979f
#define DEG (3.14159265358979323846 / 180.0)

wv_status wv_params_yarn_model(const wv_params *p, wv_yarn_model *m, wv_error *err) {
  memset(m, 0, sizeof *m);
  wv_status st = wv_params_weave(p, &m->weave, err);
  if (st) return st;
  for (int y = 0; y < 2; y++) {
    m->spacing[y] = (float)(25.4 / p->density[y]);
    m->beta[y] = (float)p->heightfield[y];
  }
  m->umax = (float)(p->inclination_deg * DEG);
  m->psi = (float)(p->twist_deg * DEG);
  m->width = (float)p->yarn_width;
  m->noise_level = p->noise_level;
  m->seed = (uint64_t)p->seed;
  wv_yarn_model_update(m);
  return WV_OK;
}

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
