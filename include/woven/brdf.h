/* woven: fabric shading (SPEC section 4, paper section 3.2), one point at a time.
 * SGGX fiber microflakes (Heitz et al. 2015) in a SpongeCake single-scattering
 * slab (Wang et al. 2022) for the specular lobe, blended Lambert for the diffuse.
 * All vectors are unit length and in one common frame; wi (to light) and wo (to
 * camera) point away from the surface. */
#ifndef WOVEN_BRDF_H
#define WOVEN_BRDF_H

#include <math.h>

static inline float wv_dot3(const float a[3], const float b[3]) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* The functions below evaluate the renderer's own shading kernel (one float
 * lane of src/kernel/kernel_impl.h), so what they are tested for is what renders. */

/* SGGX projected area for fiber-like flakes around tangent t:
 * sigma(w) = sqrt(w_b^2 + w_n^2 + alpha^2 w_t^2) = sqrt(1 - (1 - alpha^2)(w.t)^2). */
float wv_sggx_sigma(const float t[3], float alpha, const float w[3]);

/* SGGX flake normal density D(h) = 1 / (pi alpha (h_b^2 + h_n^2 + h_t^2/alpha^2)^2), unit h. */
float wv_sggx_D(const float t[3], float alpha, const float h[3]);

/* SpongeCake single-scattering specular without k_s and U_s:
 * D(h) (1 - exp(-T A)) / (4 mu_i mu_o A), A = sigma(wi)/mu_i + sigma(wo)/mu_o.
 * Returns 0 below the horizon of wm. */
float wv_brdf_specular(const float t[3], float alpha, float thickness, const float wi[3],
                       const float wo[3], const float wm[3]);

/* Diffuse times cosine, without k_d: (w max(0, wi.n) + (1 - w) mu_i) / pi. */
float wv_brdf_diffuse_cos(const float n[3], float blend_w, const float wi[3], const float wm[3]);

/* Directional albedo of the specular lobe for direction wo (k_s = 1, U_s = 1):
 * integral of f_s mu_i over the hemisphere, by stratified quadrature with n^2 cells. */
double wv_brdf_specular_albedo(const float t[3], float alpha, float thickness, const float wo[3],
                               const float wm[3], int n);

#endif
