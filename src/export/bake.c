/* Baking a fabric into standard PBR textures over one weave tile: per texel, the
 * least-squares fit of the standard model (std_model.h) to the woven BRDF x
 * cosine over a fixed set of light/view direction pairs (docs/export.md). */
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "export/export_internal.h"
#include "export/std_model.h"
#include "io/io_internal.h"
#include "util/colour.h"
#include "woven/export.h"
#include "woven/maps.h"

#define MAX_DIRS 256
#define PI_D 3.14159265358979323846

void wv_bake_opts_default(wv_bake_opts *o) {
  o->texture_size = 64;
  o->samples = 3;
  o->directions = 48;
  o->threads = 0;
}

void wv_bake_free(wv_bake *b) {
  wv_image *all[] = {&b->base_color, &b->normal, &b->metal_rough, &b->anisotropy, &b->sheen, &b->diffuse_transmission,
                     &b->open};
  for (size_t i = 0; i < sizeof all / sizeof all[0]; i++) wv_image_free(all[i]);
}

/* The direction pairs: light and view each spread over the cap within 80 degrees
 * of the normal with density proportional to the cosine (grazing directions,
 * which carry little light, weigh less), from two low-discrepancy sequences. */
static void direction_pairs(int n, float wi[][3], float wo[][3]) {
  const double smax = sin(80.0 * PI_D / 180.0);
  for (int k = 0; k < n; k++) {
    double u[4] = {(k + 0.5) / n, fmod(0.5 + k * 0.6180339887498949, 1.0), fmod(0.3 + k * 0.7548776662466927, 1.0),
                   fmod(0.7 + k * 0.5698402909980532, 1.0)};
    for (int s = 0; s < 2; s++) {
      double st = smax * sqrt(u[2 * s]), ct = sqrt(1.0 - st * st), ph = 2.0 * PI_D * u[2 * s + 1];
      float *w = s ? wo[k] : wi[k];
      w[0] = (float)(st * cos(ph)), w[1] = (float)(st * sin(ph)), w[2] = (float)ct;
    }
  }
}

/* min over the box [0,1]^2 of a x^2 + 2 b x y + c y^2 - 2 d x - 2 e y (convex):
 * the interior minimum if it lies in the box, else the best clamped edge minimum. */
static void box_ls2(double a, double b, double c, double d, double e, float *x, float *y) {
  double det = a * c - b * b;
  if (det > 1e-12 * (a * c + 1e-300)) {
    double xi = (d * c - b * e) / det, yi = (a * e - b * d) / det;
    if (xi >= 0 && xi <= 1 && yi >= 0 && yi <= 1) {
      *x = (float)xi, *y = (float)yi;
      return;
    }
  }
  double best = INFINITY, bx = 0, by = 0;
  for (int k = 0; k < 4; k++) {
    double cx, cy;
    if (k < 2) { /* x fixed at 0 or 1 */
      cx = k;
      cy = c > 1e-300 ? (e - b * cx) / c : 0;
      cy = cy < 0 ? 0 : cy > 1 ? 1 : cy;
    } else {
      cy = k - 2;
      cx = a > 1e-300 ? (d - b * cy) / a : 0;
      cx = cx < 0 ? 0 : cx > 1 ? 1 : cx;
    }
    double q = a * cx * cx + 2 * b * cx * cy + c * cy * cy - 2 * d * cx - 2 * e * cy;
    if (q < best) best = q, bx = cx, by = cy;
  }
  *x = (float)bx, *y = (float)by;
}

/* One texel's fit. */
typedef struct {
  int m;                           /* direction pairs */
  const float (*wi)[3], (*wo)[3];
  const wv_std_lut *lut;
  float target[MAX_DIRS][3];
  wv_std_material mat;             /* the current estimate */
  float yarn_n[3];                 /* the texel's mean yarn normal */
  float across[2], along[2];       /* anisotropy axis across the fibre (a > 0) or along it (a < 0) */
  wv_std_terms terms[MAX_DIRS];
  float cached_r, cached_a, cached_sr, cached_l;
} texel_fit;

static void set_aniso(texel_fit *t, float a) {
  t->mat.aniso = fabsf(a);
  const float *d = a >= 0 ? t->across : t->along;
  t->mat.aniso_dir[0] = d[0], t->mat.aniso_dir[1] = d[1];
}

/* The normal map's value: the macro normal bent toward the mean yarn normal by l. */
static void set_normal(texel_fit *t, float l) {
  float n[3] = {l * t->yarn_n[0], l * t->yarn_n[1], 1.0f - l + l * t->yarn_n[2]};
  float len = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  for (int c = 0; c < 3; c++) t->mat.n[c] = len > 0 ? n[c] / len : (c == 2);
}

/* Terms for the current non-linear parameters (recomputed only when they change). */
static void update_terms(texel_fit *t, float r, float a, float sr, float l) {
  if (l != t->cached_l) {
    set_normal(t, l);
    t->cached_l = l, t->cached_r = t->cached_sr = -2.0f; /* everything depends on the normal */
  }
  if (r != t->cached_r || a != t->cached_a) {
    t->mat.roughness = r;
    set_aniso(t, a);
    for (int k = 0; k < t->m; k++) wv_std_spec_terms(&t->mat, t->lut, t->wi[k], t->wo[k], &t->terms[k]);
    t->cached_r = r, t->cached_a = a;
  }
  if (sr != t->cached_sr) {
    t->mat.sheen_roughness = sr;
    for (int k = 0; k < t->m; k++) wv_std_sheen_terms(&t->mat, t->wi[k], t->wo[k], &t->terms[k]);
    t->cached_sr = sr;
  }
}

/* Squared error of the model with colours base, sheen against the target. */
static double model_error(const texel_fit *t, float metallic, const float base[3], const float sheen[3]) {
  double e = 0;
  for (int k = 0; k < t->m; k++) {
    float comp = wv_std_comp(&t->terms[k], sheen);
    for (int c = 0; c < 3; c++) {
      float A, S, C;
      wv_std_linear(&t->terms[k], metallic, wv_std_f0(metallic, base[c]), comp, &A, &S, &C);
      double r = base[c] * A + sheen[c] * S + C - t->target[k][c];
      e += r * r;
    }
  }
  return e;
}

/* The colours for given non-linear parameters: the model is linear in a channel's
 * base and sheen colour once its f0 (through the multiple-scattering factor) and
 * the sheen energy factor are fixed, so alternate: fix them from the current
 * colours, solve the per-channel box-constrained least squares, repeat. */
static double solve_colours(texel_fit *t, float metallic, float base[3], float sheen[3]) {
  for (int it = 0; it < 3; it++) {
    double a[3] = {0}, b[3] = {0}, c[3] = {0}, d[3] = {0}, e[3] = {0};
    for (int k = 0; k < t->m; k++) {
      float comp = wv_std_comp(&t->terms[k], sheen);
      for (int ch = 0; ch < 3; ch++) {
        float A, S, C;
        wv_std_linear(&t->terms[k], metallic, wv_std_f0(metallic, base[ch]), comp, &A, &S, &C);
        double r = t->target[k][ch] - C;
        a[ch] += (double)A * A, b[ch] += (double)A * S, c[ch] += (double)S * S;
        d[ch] += A * r, e[ch] += S * r;
      }
    }
    for (int ch = 0; ch < 3; ch++) box_ls2(a[ch], b[ch], c[ch], d[ch], e[ch], &base[ch], &sheen[ch]);
  }
  return model_error(t, metallic, base, sheen);
}

typedef struct {
  float q[5]; /* metallic, roughness, signed anisotropy, sheen roughness, normal bend */
  float base[3], sheen[3];
  double err;
} fit_state;

static double try_params(texel_fit *t, fit_state *best, const float q[5]) {
  update_terms(t, q[1], q[2], q[3], q[4]);
  float base[3], sheen[3];
  memcpy(base, best->base, sizeof base);
  memcpy(sheen, best->sheen, sizeof sheen);
  double e = solve_colours(t, q[0], base, sheen);
  if (e < best->err) {
    memcpy(best->q, q, sizeof best->q);
    best->err = e;
    memcpy(best->base, base, sizeof base);
    memcpy(best->sheen, sheen, sizeof sheen);
  }
  return e;
}

/* The non-linear parameters (metallic, roughness, signed anisotropy, sheen
 * roughness, normal bend) by coordinate descent: two sweeps over a grid of
 * each, then three halvings of each grid step around the best value. */
static void fit_texel(texel_fit *t, fit_state *s) {
  static const float lo[5] = {0.0f, 0.1f, -1.0f, 0.1f, 0.0f}, hi[5] = {1.0f, 1.0f, 1.0f, 1.0f, 1.0f};
  static const int steps[5] = {10, 15, 20, 9, 10};
  static const float start[5] = {0.0f, 0.6f, 0.0f, 0.5f, 0.5f};
  memcpy(s->q, start, sizeof s->q);
  for (int c = 0; c < 3; c++) s->base[c] = 0.5f, s->sheen[c] = 0.0f;
  s->err = INFINITY;
  t->cached_r = t->cached_a = t->cached_sr = t->cached_l = -2.0f;
  try_params(t, s, s->q);
  for (int sweep = 0; sweep < 2; sweep++)
    for (int p = 0; p < 5; p++)
      for (int k = 0; k <= steps[p]; k++) {
        float q[5];
        memcpy(q, s->q, sizeof q);
        q[p] = lo[p] + (hi[p] - lo[p]) * k / steps[p];
        try_params(t, s, q);
      }
  for (int p = 0; p < 5; p++) {
    float h = (hi[p] - lo[p]) / steps[p];
    for (int level = 0; level < 3; level++) {
      h *= 0.5f;
      for (int sg = -1; sg <= 1; sg += 2) {
        float q[5];
        memcpy(q, s->q, sizeof q);
        q[p] += sg * h;
        q[p] = q[p] < lo[p] ? lo[p] : q[p] > hi[p] ? hi[p] : q[p];
        try_params(t, s, q);
      }
    }
  }
  set_normal(t, s->q[4]);
}

static float q8(float v) { return (float)wv_io_quantise(v, 255u) / 255.0f; }

wv_status wv_bake_fabric(const wv_params *p, const wv_bake_opts *o, wv_bake *b, wv_error *err) {
  memset(b, 0, sizeof *b);
  wv_bake_opts def, use = o ? *o : (wv_bake_opts){0};
  wv_bake_opts_default(&def); /* 0 in a field takes its default */
  if (!use.texture_size) use.texture_size = def.texture_size;
  if (!use.samples) use.samples = def.samples;
  if (!use.directions) use.directions = def.directions;
  o = &use;
  if (o->texture_size < 8 || o->texture_size > 1024)
    return wv_fail(err, WV_ERR_INVALID, "texture size %d is outside 8..1024", o->texture_size);
  if (o->samples < 1 || o->samples > 8)
    return wv_fail(err, WV_ERR_INVALID, "samples per texel side %d is outside 1..8", o->samples);
  if (o->directions < 8 || o->directions > MAX_DIRS)
    return wv_fail(err, WV_ERR_INVALID, "direction pairs %d is outside 8..%d", o->directions, MAX_DIRS);
  wv_export_fabric *fab;
  wv_status st = wv_export_fabric_create(p, &fab, err);
  if (st) return st;
  const wv_yarn_model *ym = wv_export_fabric_yarns(fab);
  int S = o->texture_size, n = o->samples, M = o->directions;
  wv_image *all[] = {&b->base_color, &b->normal, &b->metal_rough, &b->anisotropy, &b->sheen, &b->diffuse_transmission,
                     &b->open};
  for (size_t i = 0; i < sizeof all / sizeof all[0] && !st; i++)
    st = wv_image_alloc(all[i], S, S, i == 4 || i == 5 ? 4 : 3, err);
  wv_std_lut *lut = st ? NULL : malloc(sizeof *lut);
  if (!st && !lut) st = wv_fail(err, WV_ERR_NOMEM, "out of memory for the bake");
  if (st) {
    wv_bake_free(b);
    wv_export_fabric_free(fab);
    return st;
  }
  wv_std_lut_init(lut);
  float wi[MAX_DIRS][3], wo[MAX_DIRS][3];
  direction_pairs(M, wi, wo);
  double tw = ym->weave.cols * (double)ym->spacing[WV_WARP], th = ym->weave.rows * (double)ym->spacing[WV_WEFT];
  b->tile_mm[0] = tw, b->tile_mm[1] = th;
  b->directions = M;
  double sq_res = 0, sq_tgt = 0;
  int any_open = 0;
  int threads = o->threads > 0 ? o->threads : omp_get_max_threads();
#pragma omp parallel num_threads(threads) reduction(+ : sq_res, sq_tgt) reduction(| : any_open)
  {
    texel_fit *t = malloc(sizeof *t);
#pragma omp for schedule(dynamic, 1)
    for (int ty = 0; ty < S; ty++)
      for (int tx = 0; tx < S && t; tx++) {
        memset(t, 0, sizeof *t);
        t->m = M, t->wi = (const float(*)[3])wi, t->wo = (const float(*)[3])wo, t->lut = lut;
        /* The texel's woven reflectance, averaged over n x n positions, and its
         * mean normal and fibre direction (fibres have no sign: the doubled
         * angle is averaged). */
        double nsum[3] = {0}, c2 = 0, s2 = 0, kt[3] = {0}, open = 0;
        for (int j = 0; j < n; j++)
          for (int i = 0; i < n; i++) {
            float fx = (float)((tx + (i + 0.5) / n) / S * tw), fy = (float)(-(ty + (j + 0.5) / n) / S * th);
            wv_yarn_point yp;
            wv_yarn_eval(ym, fx, fy, &yp);
            float ktp[3];
            wv_maps_transmission_at(p, &yp, ktp);
            for (int c = 0; c < 3; c++) kt[c] += ktp[c] / (n * n);
            open += (double)yp.open / (n * n);
            if (yp.type >= 0) {
              for (int c = 0; c < 3; c++) nsum[c] += yp.n[c];
              c2 += (double)yp.t[0] * yp.t[0] - (double)yp.t[1] * yp.t[1], s2 += 2.0 * yp.t[0] * yp.t[1];
            }
            for (int k = 0; k < M; k++) {
              float v[3];
              wv_export_woven_eval(fab, fx, fy, wi[k], wo[k], v);
              for (int c = 0; c < 3; c++) t->target[k][c] += v[c] / (float)(n * n);
            }
          }
        double nl = sqrt(nsum[0] * nsum[0] + nsum[1] * nsum[1] + nsum[2] * nsum[2]);
        float nrm[3] = {0, 0, 1};
        if (nl > 1e-9)
          for (int c = 0; c < 3; c++) nrm[c] = (float)(nsum[c] / nl);
        double fib = 0.5 * atan2(s2, c2);
        t->along[0] = (float)cos(fib), t->along[1] = (float)sin(fib);
        t->across[0] = -t->along[1], t->across[1] = t->along[0];
        for (int c = 0; c < 3; c++) t->yarn_n[c] = nrm[c];
        /* The open area is transmission in glTF, which keeps only (1 - t) of the
         * diffuse reflection: the fit knows it (the stored, 8-bit t). */
        float *dt = wv_image_px(&b->diffuse_transmission, tx, ty), *op = wv_image_px(&b->open, tx, ty);
        for (int c = 0; c < 3; c++) op[c] = q8((float)open);
        any_open |= op[0] > 0;
        t->mat.transmission = op[0];
        /* The diffuse transmission as factor x colour, the factor as small as the colour
         * (at most 1) allows: the factor takes its share of the diffuse reflection in
         * an engine that honours it. */
        double f = fmax(kt[0], fmax(kt[1], kt[2]));
        dt[3] = q8((float)f);
        for (int c = 0; c < 3; c++) dt[c] = q8(wv_srgb_encode_f(dt[3] > 0 ? (float)fmin(1.0, kt[c] / dt[3]) : 1.0f));
        fit_state s;
        fit_texel(t, &s);
        for (int c = 0; c < 3; c++) nrm[c] = t->mat.n[c];
        /* The stored values: what the PNGs hold (colours sRGB-encoded, vectors
         * 0.5 v + 0.5), each quantised to 8 bits as the file will. */
        float *bc = wv_image_px(&b->base_color, tx, ty), *nm = wv_image_px(&b->normal, tx, ty);
        float *mr = wv_image_px(&b->metal_rough, tx, ty), *an = wv_image_px(&b->anisotropy, tx, ty);
        float *sh = wv_image_px(&b->sheen, tx, ty);
        const float *ad = s.q[2] >= 0 ? t->across : t->along;
        for (int c = 0; c < 3; c++) {
          bc[c] = q8(wv_srgb_encode_f(s.base[c]));
          sh[c] = q8(wv_srgb_encode_f(s.sheen[c]));
          nm[c] = q8(0.5f * nrm[c] + 0.5f);
        }
        sh[3] = q8(s.q[3]);
        mr[0] = 1.0f, mr[1] = q8(s.q[1]), mr[2] = q8(s.q[0]);
        an[0] = q8(0.5f * ad[0] + 0.5f), an[1] = q8(0.5f * ad[1] + 0.5f), an[2] = q8(fabsf(s.q[2]));
        /* The residual of the stored material, decoded as a renderer reads it. */
        wv_std_material q;
        float qn[3] = {2 * nm[0] - 1, 2 * nm[1] - 1, 2 * nm[2] - 1};
        float ql = sqrtf(qn[0] * qn[0] + qn[1] * qn[1] + qn[2] * qn[2]);
        float qd[2] = {2 * an[0] - 1, 2 * an[1] - 1}, qdl = sqrtf(qd[0] * qd[0] + qd[1] * qd[1]);
        for (int c = 0; c < 3; c++) {
          q.base[c] = wv_srgb_decode_f(bc[c]);
          q.sheen[c] = wv_srgb_decode_f(sh[c]);
          q.n[c] = ql > 0 ? qn[c] / ql : (c == 2);
        }
        q.metallic = mr[2], q.roughness = mr[1], q.aniso = an[2], q.sheen_roughness = sh[3];
        q.transmission = op[0];
        q.aniso_dir[0] = qdl > 0 ? qd[0] / qdl : 1.0f, q.aniso_dir[1] = qdl > 0 ? qd[1] / qdl : 0.0f;
        for (int k = 0; k < M; k++) {
          float y[3];
          wv_std_eval(&q, lut, wi[k], wo[k], y);
          for (int c = 0; c < 3; c++) {
            double r = (double)y[c] - t->target[k][c];
            sq_res += r * r, sq_tgt += (double)t->target[k][c] * t->target[k][c];
          }
        }

      }
    if (!t) sq_res = NAN; /* a thread without memory: reported below */
    free(t);
  }
  free(lut);
  wv_export_fabric_free(fab);
  if (isnan(sq_res)) {
    wv_bake_free(b);
    return wv_fail(err, WV_ERR_NOMEM, "out of memory for the bake");
  }
  b->has_open = any_open;
  double cnt = (double)S * S * M * 3;
  b->rms = sqrt(sq_res / cnt), b->target_rms = sqrt(sq_tgt / cnt);
  b->relative = b->target_rms > 0 ? b->rms / b->target_rms : 0.0;
  return WV_OK;
}
