/* The shading kernel's non-inline parts: preparing a fabric (parameters in
 * the kernel's float form, the glint table, the weave's packed cells), the
 * entry points wv_kernel_shade / wv_kernel_shade8 / wv_kernel_open (kernel/kernel.h) and the
 * public per-point yarn evaluation (wv_yarn_eval, woven/yarn.h: the kernel's
 * geometry in scalar float, plus the height the maps need). */
#include "kernel/kernel.h"

#include <math.h>
#include <string.h>

#define DEG (3.14159265358979323846 / 180.0)

void wv_shade_params_from_yarn(const wv_yarn_model *m, wv_shade_params_f *P) {
  for (int t = 0; t < 2; t++) {
    P->beta[t] = m->beta[t];
    P->uos[t] = m->umax_over_spacing[t];
    P->ispc[t] = m->inv_spacing[t];
    P->vsc[t] = m->v_scale[t];
  }
  P->sin_psi = m->sin_psi, P->cos_psi = m->cos_psi;
  P->noise = 0.1f * (float)m->noise_level;
}

void wv_shade_params_set_roughness(wv_shade_params_f *P, int t, float a) {
  P->alpha[t] = a;
  P->k[t] = 1.0f - a * a;
  P->ia2m1[t] = 1.0f / (a * a) - 1.0f;
  P->pia[t] = 3.14159265358979f * a;
  P->ia[t] = 1.0f / a;
}

double wv_forward_band_mean(double width) {
  /* With the light straight behind (omega_i = -z) and a fibre in the plane, s = x / 2 for the
   * outgoing direction's projection (x, y) on the plane, and a cosine-weighted hemisphere
   * projects to the uniform unit disk: the mean is (2 / pi) int_-1^1 sqrt(1 - x^2) g(x / 2) dx,
   * here with x = sin(phi) (midpoint rule; the integrand is smooth in phi). */
  enum { N = 512 };
  const double pi = 3.14159265358979323846;
  double k = 1.0 / (8.0 * width * width), sum = 0;
  for (int i = 0; i < N; i++) {
    double ph = -0.5 * pi + (i + 0.5) * pi / N, x = sin(ph), c = cos(ph);
    double q = 1.0 + x * x * k;
    sum += c * c / (q * q);
  }
  return 2.0 / pi * sum * (pi / N);
}

/* The band's terms the kernel reads (wv_shade_params): 1 / (2 width^2) and 1 / its mean. */
static void forward_band_terms(double width, double *k, double *norm) {
  *k = 0.5 / (width * width);
  *norm = 1.0 / wv_forward_band_mean(width);
}

wv_status wv_fabric_prepare(const wv_params *p, wv_fabric *f, wv_error *err) {
  memset(f, 0, sizeof *f);
  wv_status st = wv_params_validate(p, err);
  if (st) return st;
  if ((st = wv_params_yarn_model(p, &f->ym, err))) return st;
  wv_shade_params_f *P = &f->P;
  wv_shade_params_from_yarn(&f->ym, P);
  for (int t = 0; t < 2; t++) {
    for (int c = 0; c < 3; c++) {
      P->kd[t][c] = (float)p->diffuse[t][c];
      P->ks[t][c] = (float)p->specular[t][c];
      P->kt[t][c] = (float)p->transmission[t][c];
      P->kst[t][c] = (float)p->transmission_specular[t][c];
      P->kf[t][c] = (float)p->transmission_forward[t][c];
    }
    wv_shade_params_set_roughness(P, t, (float)p->roughness[t]);
  }
  P->blend = (float)p->diffuse_blend;
  P->thickness = (float)p->thickness;
  double fw_k, fw_norm;
  forward_band_terms(p->forward_width, &fw_k, &fw_norm);
  P->fw_k = (float)fw_k, P->fw_norm = (float)fw_norm;
  f->glints = p->specular_noise;
  f->inv_glint_cell[0] = 1.0f / (f->ym.spacing[WV_WARP] / 8.0f);
  f->inv_glint_cell[1] = 1.0f / (f->ym.spacing[WV_WEFT] / 8.0f);
  for (int i = 0; i < 4096; i++) {
    float u = (float)-log(1.0 - (i + 0.5) / 4096.0);
    f->glint_table[i] = u < 10.0f ? u : 10.0f;
  }
  f->seed = (uint64_t)p->seed;
  return WV_OK;
}

void wv_shade_params_double(const wv_params *p, wv_shade_params_d *P) {
  memset(P, 0, sizeof *P);
  for (int t = 0; t < 2; t++) {
    double spacing = 25.4 / p->density[t], a = p->roughness[t];
    P->beta[t] = p->heightfield[t];
    P->uos[t] = p->inclination_deg * DEG / spacing;
    P->ispc[t] = 1.0 / spacing;
    P->vsc[t] = 3.14159265358979323846 / (spacing * p->yarn_width);
    P->alpha[t] = a;
    P->k[t] = 1.0 - a * a;
    P->ia2m1[t] = 1.0 / (a * a) - 1.0;
    P->pia[t] = 3.14159265358979323846 * a;
    P->ia[t] = 1.0 / a;
    for (int c = 0; c < 3; c++)
      P->kd[t][c] = p->diffuse[t][c], P->ks[t][c] = p->specular[t][c], P->kt[t][c] = p->transmission[t][c],
      P->kst[t][c] = p->transmission_specular[t][c], P->kf[t][c] = p->transmission_forward[t][c];
  }
  forward_band_terms(p->forward_width, &P->fw_k, &P->fw_norm);
  P->sin_psi = sin(p->twist_deg * DEG), P->cos_psi = cos(p->twist_deg * DEG);
  P->noise = 0.1 * (double)p->noise_level;
  P->blend = p->diffuse_blend, P->thickness = p->thickness;
}

void wv_kernel_shade(const wv_fabric *f, float x, float y, const float wi[3], const float wo[3], float out[3]) {
  out[0] = out[1] = out[2] = 0.0f;
  if (!(wi[2] > 0.0f && wo[2] > 0.0f)) return;
  wv_dirs_f d;
  wv_dirs_make_f(wi, wo, 1.0f, &d);
  wv_shade_f(f, &f->P, &d, x, y, out, NULL);
}

WV_SIMD_CLONES
void wv_kernel_shade8(const wv_fabric *f, const float x[8], const float y[8], const float wi[3][8],
                      const float wo[3][8], float out[3][8]) {
  wv_f8 px, py, vi[3], vo[3], rad[3];
  memcpy(&px, x, sizeof px), memcpy(&py, y, sizeof py);
  for (int k = 0; k < 3; k++) memcpy(&vi[k], wi[k], sizeof vi[k]), memcpy(&vo[k], wo[k], sizeof vo[k]);
  wv_i8 up = (vi[2] > 0.0f) & (vo[2] > 0.0f);
  wv_dirs_8 d;
  wv_dirs_make_8(vi, vo, wv_splat8(1.0f), &d);
  wv_shade_8(f, &f->P, &d, px, py, rad, NULL);
  for (int k = 0; k < 3; k++) {
    rad[k] = wv_sel(up, rad[k], wv_splat8(0.0f));
    memcpy(out[k], &rad[k], sizeof rad[k]);
  }
}

int wv_kernel_open(const wv_fabric *f, float x, float y) {
  wv_yarn_cell_f c;
  wv_yarn_locate_f(&f->ym, x, y, &c);
  return wv_cell_open_f(&c) != 0;
}

void wv_yarn_eval(const wv_yarn_model *m, float x, float y, wv_yarn_point *out) {
  wv_yarn_cell_f c;
  wv_yarn_locate_f(m, x, y, &c);
  out->segment = wv_yarn_segment_f(m, &c);
  wv_shade_params_f P;
  wv_shade_params_from_yarn(m, &P);
  float lv, lh;
  wv_cloth_chords_f(&P, &c, &lv, &lh);
  int vis = c.warp ? WV_WARP : WV_WEFT;
  out->open = wv_cell_open_f(&c) != 0;
  out->through = c.lit ? vis : c.cov ? 1 - vis : -1;
  out->thickness = lv + lh;
  if (!c.lit) { /* gap between yarns narrower than their spacing */
    out->type = -1;
    out->n[0] = 0, out->n[1] = 0, out->n[2] = 1;
    out->t[0] = 0, out->t[1] = 1, out->t[2] = 0;
    out->height = 0, out->u = 0, out->v = 0, out->beta = 0;
    return;
  }
  wv_yarn_frame_f f;
  wv_yarn_shape_f(m, &P, &c, &f, NULL);
  wv_to_fabric_f(c.warp, f.n, out->n);
  wv_to_fabric_f(c.warp, f.t, out->t);
  /* Height: circular cross-section plus an arc along the yarn whose end slope is umax. */
  float rho = m->sin_umax > 1e-6f ? c.half_len / m->sin_umax : 0.0f;
  out->height = f.beta * (c.half_w * wv_cos_hp_f(f.v) + rho * (wv_cos_hp_f(f.u) - m->cos_umax));
  out->type = vis;
  out->u = f.u, out->v = f.v, out->beta = f.beta;
}
