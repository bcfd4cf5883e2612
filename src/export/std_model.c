/* The standard material of the glTF export (see std_model.h for the formulas):
 * three.js's direct-light shading of glTF metallic-roughness with anisotropy and
 * sheen, and its GGX albedo table. */
#include "export/std_model.h"

#include <math.h>

#define PI_F 3.14159265358979f

static float sat(float x) { return x < 0.0f ? 0.0f : x > 1.0f ? 1.0f : x; }
static float dot3(const float a[3], const float b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

static void half_vector(const float l[3], const float v[3], float h[3]) {
  float s[3] = {l[0] + v[0], l[1] + v[1], l[2] + v[2]};
  float len = sqrtf(dot3(s, s));
  float il = len > 0.0f ? 1.0f / len : 0.0f;
  for (int i = 0; i < 3; i++) h[i] = s[i] * il;
}

/* three's isotropic height-correlated Smith visibility V = G / (4 n.l n.v). */
static float vis_iso(float alpha, float nl, float nv) {
  float a2 = alpha * alpha;
  float gv = nl * sqrtf(a2 + (1.0f - a2) * nv * nv);
  float gl = nv * sqrtf(a2 + (1.0f - a2) * nl * nl);
  float s = gv + gl;
  return 0.5f / (s > 1e-6f ? s : 1e-6f);
}

static float clamp_roughness(float r) {
  r = r > 0.045f ? r : 0.045f; /* three's lower bound */
  return r < 1.0f ? r : 1.0f;
}

void wv_std_lut_init(wv_std_lut *lut) {
  /* E_ss(r, mu) = integral of V D (n.l) over l with F = 1, by importance sampling
   * of the GGX normal distribution with a fixed (Hammersley) point set:
   * estimator 4 V (n.l)(v.h) / (n.h) per sample. */
  enum { NS = 1024 };
  for (int i = 0; i < WV_STD_LUT; i++) {
    float r = clamp_roughness((i + 0.5f) / WV_STD_LUT), alpha = r * r, a2 = alpha * alpha;
    for (int j = 0; j < WV_STD_LUT; j++) {
      float mu = (j + 0.5f) / WV_STD_LUT;
      float v[3] = {sqrtf(1.0f - mu * mu), 0.0f, mu};
      double sum = 0;
      for (unsigned k = 0; k < NS; k++) {
        unsigned b = k; /* radical inverse in base 2 */
        b = (b << 16) | (b >> 16);
        b = ((b & 0x55555555u) << 1) | ((b & 0xAAAAAAAAu) >> 1);
        b = ((b & 0x33333333u) << 2) | ((b & 0xCCCCCCCCu) >> 2);
        b = ((b & 0x0F0F0F0Fu) << 4) | ((b & 0xF0F0F0F0u) >> 4);
        b = ((b & 0x00FF00FFu) << 8) | ((b & 0xFF00FF00u) >> 8);
        double u1 = (k + 0.5) / NS, u2 = b * (1.0 / 4294967296.0);
        double ct = sqrt((1.0 - u1) / (1.0 + (a2 - 1.0) * u1)), st = sqrt(1.0 - ct * ct);
        float h[3] = {(float)(st * cos(6.283185307179586 * u2)), (float)(st * sin(6.283185307179586 * u2)), (float)ct};
        float vh = dot3(v, h);
        float l[3] = {2 * vh * h[0] - v[0], 2 * vh * h[1] - v[1], 2 * vh * h[2] - v[2]};
        if (l[2] <= 0.0f || vh <= 0.0f) continue;
        sum += 4.0 * vis_iso(alpha, l[2], mu) * l[2] * vh / h[2];
      }
      lut->ess[i][j] = (float)(sum / NS);
    }
  }
}

float wv_std_lut_ess(const wv_std_lut *lut, float r, float nv) {
  /* Bilinear between cell centres, clamped at the borders (a texture lookup). */
  float x = sat(r) * WV_STD_LUT - 0.5f, y = sat(nv) * WV_STD_LUT - 0.5f;
  x = x < 0 ? 0 : x > WV_STD_LUT - 1 ? WV_STD_LUT - 1 : x;
  y = y < 0 ? 0 : y > WV_STD_LUT - 1 ? WV_STD_LUT - 1 : y;
  int i = (int)x, j = (int)y;
  int i1 = i + 1 < WV_STD_LUT ? i + 1 : i, j1 = j + 1 < WV_STD_LUT ? j + 1 : j;
  float fx = x - i, fy = y - j;
  return (1 - fx) * ((1 - fy) * lut->ess[i][j] + fy * lut->ess[i][j1]) +
         fx * ((1 - fy) * lut->ess[i1][j] + fy * lut->ess[i1][j1]);
}

void wv_std_spec_terms(const wv_std_material *m, const wv_std_lut *lut, const float l[3], const float v[3],
                       wv_std_terms *t) {
  float h[3];
  half_vector(l, v, h);
  const float *n = m->n;
  float nl = sat(dot3(n, l)), nv = sat(dot3(n, v)), nh = sat(dot3(n, h)), vh = sat(dot3(v, h));
  t->nl = nl;
  t->w = exp2f((-5.55473f * vh - 6.98316f) * vh);
  t->lambert = (1.0f - m->transmission) * (1.0f - (0.04f * (1.0f - t->w) + t->w)) / PI_F;
  float r = clamp_roughness(m->roughness), alpha = r * r;
  /* Anisotropy axis T and its partner B in the geometric tangent plane. */
  float a = sat(m->aniso), dx = m->aniso_dir[0], dy = m->aniso_dir[1];
  if (a == 0.0f) dx = 1.0f, dy = 0.0f;
  float at = alpha + (1.0f - alpha) * a * a, ab = alpha;
  at = at > alpha ? at : alpha;
  float tl = dx * l[0] + dy * l[1], tv = dx * v[0] + dy * v[1], th = dx * h[0] + dy * h[1];
  float bl = -dy * l[0] + dx * l[1], bv = -dy * v[0] + dx * v[1], bh = -dy * h[0] + dx * h[1];
  float gv = nl * sqrtf(at * tv * at * tv + ab * bv * ab * bv + nv * nv);
  float gl = nv * sqrtf(at * tl * at * tl + ab * bl * ab * bl + nl * nl);
  float vis = 0.5f / (gv + gl > 1e-6f ? gv + gl : 1e-6f);
  float a2 = at * ab;
  float q[3] = {ab * th, at * bh, a2 * nh};
  float q2 = dot3(q, q);
  float w2 = q2 > 1e-30f ? a2 / q2 : 0.0f;
  t->vd = vis * a2 * w2 * w2 / PI_F;
  t->ms_k = 1.0f / wv_std_lut_ess(lut, r, nv) - 1.0f;
}

/* three's fit of the Charlie sheen's directional albedo. */
static float sheen_albedo(float nv, float r) {
  float r2 = r * r, rinv = 1.0f / (r + 0.1f);
  float a = -1.9362f + 1.0678f * r + 0.4573f * r2 - 0.8469f * rinv;
  float b = -0.6014f + 0.5538f * r - 0.4670f * r2 - 0.1255f * rinv;
  return sat(expf(a * nv + b));
}

void wv_std_sheen_terms(const wv_std_material *m, const float l[3], const float v[3], wv_std_terms *t) {
  float h[3];
  half_vector(l, v, h);
  const float *n = m->n;
  float nl = sat(dot3(n, l)), nv = sat(dot3(n, v)), nh = sat(dot3(n, h));
  float r = m->sheen_roughness < 1e-4f ? 1e-4f : m->sheen_roughness > 1.0f ? 1.0f : m->sheen_roughness;
  float inv = 1.0f / (r * r);
  float s2 = 1.0f - nh * nh;
  s2 = s2 > 0.0078125f ? s2 : 0.0078125f;
  float D = (2.0f + inv) * powf(s2, inv * 0.5f) / (2.0f * PI_F);
  float V = sat(1.0f / (4.0f * (nl + nv - nl * nv)));
  t->sheen = D * V;
  float ev = sheen_albedo(nv, r), el = sheen_albedo(nl, r);
  t->sheen_alb = ev > el ? ev : el;
}

void wv_std_eval(const wv_std_material *m, const wv_std_lut *lut, const float l[3], const float v[3], float out[3]) {
  wv_std_terms t;
  wv_std_spec_terms(m, lut, l, v, &t);
  wv_std_sheen_terms(m, l, v, &t);
  float comp = wv_std_comp(&t, m->sheen);
  for (int c = 0; c < 3; c++) {
    float A, S, C;
    wv_std_linear(&t, m->metallic, wv_std_f0(m->metallic, m->base[c]), comp, &A, &S, &C);
    out[c] = m->base[c] * A + m->sheen[c] * S + C;
  }
}
