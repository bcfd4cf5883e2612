/* The standard material the glTF export is fitted to: glTF 2.0 metallic-roughness
 * with KHR_materials_anisotropy and KHR_materials_sheen, lit by one point light,
 * exactly as three.js (r187, MeshPhysicalMaterial, index of refraction 1.5,
 * specular intensity and colour 1) shades direct light. Written once here; the
 * baker fits it and the tests check it. The formulas, with n the normal-mapped
 * normal, l and v the unit light and view directions, h = normalize(l + v):
 *
 *   out_c = (n.l) [ comp (b_c (1 - m) (1 - t) (1 - F(0.04)) / pi + F(f0_c) V D ms_c) + s_c D_s V_s ]
 *   F(f0) = f0 (1 - w) + w,  w = 2^((-5.55473 (v.h) - 6.98316) (v.h))   (three's Schlick)
 *   f0_c  = 0.04 (1 - m) + m b_c,   ms_c = 1 + f0_c (1/E_ss - 1)        (multiple scattering)
 *   V D   = anisotropic GGX, height-correlated Smith, alpha = r^2 across the anisotropy
 *           axis and alpha_t = mix(alpha, 1, a^2) along it (the axis lies in the
 *           geometric tangent plane, as three builds it from the unperturbed frame)
 *   D_s V_s = Charlie sheen (Estevez & Kulla 2017) with Neubelt's visibility
 *   comp  = 1 - max(s) max(E_s(n.v), E_s(n.l))                          (sheen energy)
 *
 * b base colour, m metallic, t transmission (the light it lets through, from behind, is
 * not part of this reflection model), r roughness, a anisotropy strength, s sheen colour,
 * E_ss the GGX single-scattering albedo (three's DFG table; here computed by
 * importance sampling), E_s three's analytic sheen albedo. Not modelled: three's
 * "geometry roughness" (it adds the screen-space change of the normal to r; 0 on
 * a flat quad). Vectors are in the geometric tangent frame: x tangent, y
 * bitangent, z geometric normal. */
#ifndef WOVEN_STD_MODEL_H
#define WOVEN_STD_MODEL_H

typedef struct {
  float base[3];         /* base colour, linear RGB */
  float metallic;        /* 0..1 */
  float roughness;       /* perceptual roughness r (alpha = r^2), 0..1 */
  float aniso;           /* anisotropy strength a, 0..1 */
  float aniso_dir[2];    /* unit direction of the anisotropy axis in the tangent plane */
  float sheen[3];        /* sheen colour, linear RGB */
  float sheen_roughness; /* 0..1 */
  float n[3];            /* unit shading normal (the normal map's value) */
  float transmission;    /* KHR_materials_transmission's factor t: three keeps (1 - t) of the diffuse */
} wv_std_material;

/* GGX single-scattering albedo E_ss(r, n.v) (F = 1) on a grid, read bilinearly. */
#define WV_STD_LUT 32
typedef struct {
  float ess[WV_STD_LUT][WV_STD_LUT]; /* [roughness index][n.v index], cell centres */
} wv_std_lut;
void wv_std_lut_init(wv_std_lut *lut);
float wv_std_lut_ess(const wv_std_lut *lut, float roughness, float nv);

/* The parts of the model that do not depend on the colours or the metallic. */
typedef struct {
  float nl;        /* saturate(n.l) */
  float w;         /* Schlick weight of v.h */
  float lambert;   /* (1 - t) (1 - F(0.04)) / pi */
  float vd;        /* V D of the anisotropic GGX lobe */
  float ms_k;      /* 1/E_ss - 1 */
  float sheen;     /* D_s V_s */
  float sheen_alb; /* max(E_s(n.v), E_s(n.l)) */
} wv_std_terms;

/* Terms of the specular lobe (nl, w, lambert, vd, ms_k): depend on n, roughness, anisotropy. */
void wv_std_spec_terms(const wv_std_material *m, const wv_std_lut *lut, const float l[3], const float v[3],
                       wv_std_terms *t);
/* Terms of the sheen lobe (sheen, sheen_alb): depend on n and the sheen roughness. */
void wv_std_sheen_terms(const wv_std_material *m, const float l[3], const float v[3], wv_std_terms *t);

/* One channel as a linear function of its base colour b and sheen colour s:
 * out = b A + s S + C, given the metallic, that channel's f0 (through ms) and the
 * sheen energy factor comp. The model's only combination of its terms. */
static inline void wv_std_linear(const wv_std_terms *t, float metallic, float f0, float comp, float *A, float *S,
                                 float *C) {
  float ms = 1.0f + f0 * t->ms_k;
  float spec = t->vd * ms;
  *A = t->nl * comp * ((1.0f - metallic) * t->lambert + metallic * (1.0f - t->w) * spec);
  *C = t->nl * comp * (0.04f * (1.0f - metallic) * (1.0f - t->w) + t->w) * spec;
  *S = t->nl * t->sheen;
}

/* f0 of a channel and the sheen energy factor, from the colours. */
static inline float wv_std_f0(float metallic, float base) { return 0.04f * (1.0f - metallic) + metallic * base; }
static inline float wv_std_comp(const wv_std_terms *t, const float sheen[3]) {
  float mx = sheen[0] > sheen[1] ? sheen[0] : sheen[1];
  mx = mx > sheen[2] ? mx : sheen[2];
  return 1.0f - mx * t->sheen_alb;
}

/* Reflected radiance per unit of light intensity / distance^2 (BRDF x cosine). */
void wv_std_eval(const wv_std_material *m, const wv_std_lut *lut, const float l[3], const float v[3], float out[3]);

#endif
