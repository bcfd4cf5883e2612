/* The public BRDF functions (woven/brdf.h): thin wrappers that put the
 * caller's vectors into the shading kernel's form and call it, so tests of
 * this API test the renderer's arithmetic. Also the specular albedo by
 * quadrature. */
#include "woven/brdf.h"

#include "kernel/kernel.h"

#define PI_F 3.14159265358979f

float wv_sggx_sigma(const float t[3], float alpha, const float w[3]) {
  return wv_sggx_sigma_f(1.0f - alpha * alpha, wv_dot3(w, t));
}

float wv_sggx_D(const float t[3], float alpha, const float h[3]) {
  return wv_sggx_D_f(PI_F * alpha, wv_sggx_q_f(1.0f / (alpha * alpha) - 1.0f, wv_dot3(h, t)));
}

float wv_brdf_specular(const float t[3], float alpha, float thickness, const float wi[3],
                       const float wo[3], const float wm[3]) {
  float mi = wv_dot3(wi, wm), mo = wv_dot3(wo, wm);
  if (mi <= 0.0f || mo <= 0.0f) return 0.0f;
  float h[3] = {wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]};
  float hl = sqrtf(wv_dot3(h, h));
  if (hl < 1e-12f) return 0.0f;
  h[0] /= hl, h[1] /= hl, h[2] /= hl;
  float a2 = alpha * alpha;
  /* the kernel returns f_s mu_i */
  return wv_spongecake_f(wv_dot3(t, wi), wv_dot3(t, wo), wv_dot3(t, h), mi, mo, alpha, 1.0f - a2, 1.0f / a2 - 1.0f,
                         PI_F * alpha, 1.0f / alpha, thickness, 1.0f, NULL) /
         mi;
}

float wv_brdf_diffuse_cos(const float n[3], float blend_w, const float wi[3], const float wm[3]) {
  float mi = wv_dot3(wi, wm);
  if (mi <= 0.0f) return 0.0f;
  return wv_diffuse_f(wv_dot3(wi, n), mi, blend_w, NULL, NULL);
}

double wv_brdf_specular_albedo(const float t[3], float alpha, float thickness, const float wo[3],
                               const float wm[3], int n) {
  /* Build a frame around wm and integrate over (cos theta, phi) cells: d omega = d mu d phi. */
  float a[3] = {1, 0, 0};
  if (fabsf(wm[0]) > 0.9f) a[0] = 0, a[1] = 1;
  float e1[3] = {wm[1] * a[2] - wm[2] * a[1], wm[2] * a[0] - wm[0] * a[2], wm[0] * a[1] - wm[1] * a[0]};
  float l = sqrtf(wv_dot3(e1, e1));
  e1[0] /= l, e1[1] /= l, e1[2] /= l;
  float e2[3] = {wm[1] * e1[2] - wm[2] * e1[1], wm[2] * e1[0] - wm[0] * e1[2], wm[0] * e1[1] - wm[1] * e1[0]};
  double sum = 0;
  for (int i = 0; i < n; i++)
    for (int j = 0; j < n; j++) {
      double mu = (i + 0.5) / n, phi = 2.0 * 3.14159265358979 * (j + 0.5) / n;
      double s = sqrt(1.0 - mu * mu);
      float wi[3];
      for (int k = 0; k < 3; k++)
        wi[k] = (float)(s * cos(phi) * e1[k] + s * sin(phi) * e2[k] + mu * wm[k]);
      sum += wv_brdf_specular(t, alpha, thickness, wi, wo, wm) * mu;
    }
  return sum * (2.0 * 3.14159265358979) / ((double)n * n);
}
