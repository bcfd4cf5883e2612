/* The forward renderer's inner loop, eight samples of a pixel at a time.
 *
 * In a pixel with a bilinear footprint every sample shares the directions, so
 * the work per sample is the same straight-line arithmetic: a natural fit for
 * SIMD. Each lane repeats wv_shade() (render_internal.h, yarn_eval.h) operation
 * for operation, in the same order, with branches turned into selects; IEEE
 * +, -, *, / and sqrt round the same in a vector lane as in a scalar register,
 * so every sample's radiance is bit-identical to wv_shade's, and lane i adds the
 * samples of row i of the pixel's sums (WV_ACC_ROWS) in order, as the scalar paths
 * do. The image therefore does not depend on the path or the CPU, and the
 * gradient kernel (grad_kernel.inc, scalar) still returns exactly wv_render's
 * capture (test_grad checks this).
 *
 * GCC vector extensions, compiled in several versions (target_clones): AVX-512
 * (64-bit multiplies for the hashes in one instruction), AVX2, and plain
 * x86-64, chosen when the program loads. Elsewhere the same code is built for
 * the default target. */
#include <math.h>
#include <string.h>

#include "render/render_internal.h"


#define W 8
_Static_assert(W == WV_ACC_ROWS, "a vector lane holds one row of the pixel's sums");
typedef float v8f __attribute__((vector_size(4 * W)));
typedef int32_t v8i __attribute__((vector_size(4 * W)));
typedef int64_t v8l __attribute__((vector_size(8 * W)));
typedef uint64_t v8u __attribute__((vector_size(8 * W)));

#define INL static inline __attribute__((always_inline))

/* m ? a : b per lane (m is 0 or -1). */
INL v8f sel(v8i m, v8f a, v8f b) { return (v8f)((m & (v8i)a) | (~m & (v8i)b)); }
INL v8i seli(v8i m, v8i a, v8i b) { return (m & a) | (~m & b); }
INL v8f vabs(v8f x) { return (v8f)((v8i)x & 0x7fffffff); }
INL v8f tof(v8i x) { return __builtin_convertvector(x, v8f); }
/* 64-bit lanes from signed 32-bit ones, as the scalar (uint64_t)(int64_t) casts */
INL v8u tou64(v8i x) { return (v8u)__builtin_convertvector(x, v8l); }

/* wv_floor_ll for |x| < 2^31 (the caller checks the range). */
INL v8i vfloor(v8f x) {
  v8i i = __builtin_convertvector(x, v8i);
  return i + (x < tof(i)); /* a true compare is -1 */
}

/* Mathematical x mod n (0 <= result < n) for |x| < 2^22 and 1 <= n <= 32: the
 * float quotient is off by at most one there, and one correction fixes it. */
INL v8i vmod(v8i x, int n) {
  v8i q = vfloor(tof(x) * (1.0f / (float)n));
  v8i r = x - q * n;
  r += (r < 0) & n;
  r -= (r >= n) & n;
  return r;
}

INL v8u vmix64(v8u z) { /* wv_mix64 */
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}
INL v8u vhash2(v8u a, v8u b, uint64_t seed) { /* wv_hash2 */
  return vmix64(vmix64(a * 0x9e3779b97f4a7c15ULL + seed) ^ (b * 0xc2b2ae3d27d4eb4fULL));
}
INL v8f vu01(v8u h) { /* wv_u01 */
  return tof(__builtin_convertvector(h >> 40, v8i)) * (1.0f / 16777216.0f);
}

INL v8f vsqrt(v8f x) { /* compiles to one sqrtps per vector register */
  v8f r;
  for (int i = 0; i < W; i++) r[i] = sqrtf(x[i]);
  return r;
}
INL v8f vsin_hp(v8f x) { /* wv_sin_hp */
  v8f x2 = x * x;
  return x * (1.0f + x2 * (-1.0f / 6 + x2 * (1.0f / 120 + x2 * (-1.0f / 5040 +
             x2 * (1.0f / 362880 + x2 * (-1.0f / 39916800))))));
}
INL v8f vcos_hp(v8f x) { /* wv_cos_hp */
  v8f x2 = x * x;
  return 1.0f + x2 * (-0.5f + x2 * (1.0f / 24 + x2 * (-1.0f / 720 + x2 * (1.0f / 40320 +
         x2 * (-1.0f / 3628800 + x2 * (1.0f / 479001600))))));
}
INL v8f vexpf(v8f x) { /* wv_expf */
  x = sel(x > -87.0f, x, (v8f){0} - 87.0f);
  x = sel(x < 88.0f, x, (v8f){0} + 88.0f);
  v8f kf = (x * 1.44269502f + 12582912.0f) - 12582912.0f;
  v8f r = (x - kf * 0.693145751953125f) - kf * 1.42860677e-6f;
  v8f p = 1.0f + r * (1.0f + r * (0.5f + r * (1.0f / 6 + r * (1.0f / 24 + r * (1.0f / 120 +
          r * (1.0f / 720 + r * (1.0f / 5040)))))));
  return p * (v8f)((__builtin_convertvector(kf, v8i) + 127) << 23);
}

/* wv_pixel_sampler_at for eight consecutive samples of one pixel: the pixel's
 * permutations tabulated once (nx, ny <= 64 as spp <= WV_SCENE_MAX_SPP). */
typedef struct {
  uint64_t hash; /* wv_pixel_hash, the same for every sample of the pixel */
  int nx;
  float fnx, fny, inx;
  float subx[64], suby[64]; /* wv_permute of the row (ny values) and of the column (nx values) */
} pixel_strata;

INL void strata_init(pixel_strata *P, int px, int py, int spp, int width, uint64_t seed) {
  int ny;
  wv_pixel_grid(spp, &P->nx, &ny);
  P->hash = wv_pixel_hash(px, py, width, seed);
  uint64_t keys = wv_pixel_keys(P->hash);
  for (int i = 0; i < ny; i++) P->subx[i] = (float)wv_permute((uint32_t)i, (uint32_t)ny, (uint32_t)keys);
  for (int i = 0; i < P->nx; i++) P->suby[i] = (float)wv_permute((uint32_t)i, (uint32_t)P->nx, (uint32_t)(keys >> 32));
  P->fnx = (float)P->nx, P->fny = (float)ny, P->inx = 1.0f / (float)P->nx;
}

/* Positions in the pixel of samples s0 .. s0+7: cell (s mod nx, s div nx), the
 * sub-cell from the permutations, jitter from the hash. */
INL void sample8(const pixel_strata *P, int s0, v8f *sx, v8f *sy) {
  v8i s = s0 + (v8i){0, 1, 2, 3, 4, 5, 6, 7};
  v8i row, col;
  v8f subx, suby;
  if (P->nx % W == 0) { /* 64, 256, ... spp: the eight samples lie in one row, side by side */
    int r0 = s0 / P->nx, c0 = s0 - r0 * P->nx;
    row = (v8i){0} + r0, col = c0 + (v8i){0, 1, 2, 3, 4, 5, 6, 7};
    subx = (v8f){0} + P->subx[r0];
    memcpy(&suby, P->suby + c0, sizeof suby);
  } else {
    row = vfloor((tof(s) + 0.5f) * P->inx), col = s - row * P->nx; /* off by one at most: see vmod */
    v8i lo = col < 0, hi = col >= P->nx;
    row += lo - hi, col += (lo & P->nx) - (hi & P->nx);
    subx = (v8f){P->subx[row[0]], P->subx[row[1]], P->subx[row[2]], P->subx[row[3]],
                 P->subx[row[4]], P->subx[row[5]], P->subx[row[6]], P->subx[row[7]]};
    suby = (v8f){P->suby[col[0]], P->suby[col[1]], P->suby[col[2]], P->suby[col[3]],
                 P->suby[col[4]], P->suby[col[5]], P->suby[col[6]], P->suby[col[7]]};
  }
  v8u h = vmix64(P->hash ^ (tou64(s) * 0xc2b2ae3d27d4eb4fULL));
  v8f j1 = vu01(h), j2 = tof(__builtin_convertvector((h >> 16) & 0xffffffULL, v8i)) * (1.0f / 16777216.0f);
  *sx = (tof(col) + (subx + j1) / P->fny) / P->fnx;
  *sy = (tof(row) + (suby + j2) / P->fnx) / P->fny;
}

/* Per pixel: the constants of wv_shade and wv_yarn_eval_inline, as they round there. */
typedef struct {
  pixel_strata strata;
  float half_w[2], uos[2], vsc[2], beta[2], k[2], ia2m1[2], pia[2];
  float noise; /* 0.1 Q */
  float bm, four_mo, inv_pi;
} pixel_consts;

/* Samples s0 .. s0+7: each sample's radiance (per channel, 0 in a gap) in out.
 * Returns 0, computing nothing, when a coordinate is too large for the 32-bit
 * cell arithmetic; the caller then shades those samples one by one. */
INL int shade8(const wv_fabric *f, const wv_footprint *fp, const pixel_consts *C, int s0, v8f out[3]) {
  const wv_yarn_model *m = &f->ym;
  const wv_dirs *d = &fp->dirs;

  v8f sx, sy;
  sample8(&C->strata, s0, &sx, &sy);

  /* wv_footprint_at */
  v8f w00 = (1 - sx) * (1 - sy), w10 = sx * (1 - sy), w01 = (1 - sx) * sy, w11 = sx * sy;
  v8f x = w00 * fp->fx[0] + w10 * fp->fx[1] + w01 * fp->fx[2] + w11 * fp->fx[3];
  v8f y = w00 * fp->fy[0] + w10 * fp->fy[1] + w01 * fp->fy[2] + w11 * fp->fy[3];

  /* wv_yarn_eval_inline: cell, local coordinates. */
  v8f r = -y * m->inv_spacing[WV_WEFT], c = x * m->inv_spacing[WV_WARP];
  v8f gxf = x * f->inv_glint_cell[0], gyf = y * f->inv_glint_cell[1];
  v8i ok = (vabs(r) < 4194304.0f) & (vabs(c) < 4194304.0f) & (vabs(gxf) < 1073741824.0f) &
           (vabs(gyf) < 1073741824.0f); /* also false for NaN */
  for (int i = 0; i < W; i++)
    if (!ok[i]) return 0;
  v8i I = vfloor(r), J = vfloor(c);
  v8f fr = r - tof(I), fc = c - tof(J);
  v8i wr = vmod(I, m->weave.rows), wc = vmod(J, m->weave.cols); /* wv_weave_at */
  /* a gather of one packed word per lane, built as one vector (writing lanes one
   * by one through memory stalls the read of the whole vector that follows) */
  v8i ci = wr * WV_WEAVE_MAX + wc;
  const int32_t *cpk = m->cellpack;
  v8i pk = {cpk[ci[0]], cpk[ci[1]], cpk[ci[2]], cpk[ci[3]], cpk[ci[4]], cpk[ci[5]], cpk[ci[6]], cpk[ci[7]]};
  v8i ty = pk & 0xff, len = (pk >> 8) & 0xff, idx = pk >> 16;
  v8i warp = ty == WV_WARP;
  const float dx = m->spacing[WV_WARP], dy = m->spacing[WV_WEFT];
  v8f L = tof(len), kk = tof(idx);
  v8f a = sel(warp, (fc - 0.5f) * dx, (fr - 0.5f) * dy);
  v8f l = sel(warp, -((kk + fr) - 0.5f * L) * dy, ((kk + fc) - 0.5f * L) * dx);
  v8i lit = ~(vabs(a) > sel(warp, (v8f){0} + C->half_w[0], (v8f){0} + C->half_w[1])); /* not a gap */

  v8f beta = sel(warp, (v8f){0} + C->beta[0], (v8f){0} + C->beta[1]);
  if (m->noise_level > 0) { /* segment noise U_n, hashed on the float's first cell */
    v8u w64 = tou64(warp); /* the mask widened to 64-bit lanes */
    v8u ha = (w64 & (tou64(J) << 1)) | (~w64 & ((tou64(I) << 1) | 1)), hb = tou64(seli(warp, I, J) - idx);
    v8f xi = vu01(vmix64(vhash2(ha, hb, m->seed) ^ 0x5851f42d4c957f2dULL));
    beta = beta * (1.0f + C->noise * (2.0f * xi - 1.0f));
    beta = sel(beta > 0.0f, beta, (v8f){0});
  }
  /* u = l (2 / L) umax / spacing_along; 2.0f * (1.0f / L) rounds as 2 * INV_LEN[L] */
  v8f u = l * (2.0f * (1.0f / L)) * sel(warp, (v8f){0} + C->uos[1], (v8f){0} + C->uos[0]);
  v8f v = a * sel(warp, (v8f){0} + C->vsc[0], (v8f){0} + C->vsc[1]);

  /* wv_yarn_frame_inline, wv_yarn_scale_inline */
  v8f su = vsin_hp(u), cu = vcos_hp(u), sv = vsin_hp(v), cv = vcos_hp(v);
  const float sp = m->sin_psi, cp = m->cos_psi;
  v8f nx = beta * sv, ny = beta * (su * cv), nz = cu * cv;
  v8f ln2 = nx * nx + ny * ny + nz * nz;
  v8i flat = ln2 < 1e-24f;
  nx = sel(flat, (v8f){0}, nx), ny = sel(flat, (v8f){0}, ny), nz = sel(flat, (v8f){0} + 1, nz);
  ln2 = sel(flat, (v8f){0} + 1, ln2);
  v8f il = 1.0f / vsqrt(ln2);
  nx *= il, ny *= il, nz *= il;
  v8f tx = -cv * sp, tyy = cu * cp + su * sv * sp, tz = beta * (-su * cp + cu * sv * sp);
  v8f lt2 = tx * tx + tyy * tyy + tz * tz;
  v8i up = lt2 < 1e-24f;
  tx = sel(up, (v8f){0}, tx), tyy = sel(up, (v8f){0} + 1, tyy), tz = sel(up, (v8f){0}, tz);
  lt2 = sel(up, (v8f){0} + 1, lt2);
  v8f it = 1.0f / vsqrt(lt2);
  tx *= it, tyy *= it, tz *= it;
  /* weft: the +y frame turned by -90 degrees about z */
  v8f n0 = sel(warp, nx, ny), n1 = sel(warp, ny, -nx);
  v8f t0 = sel(warp, tx, tyy), t1 = sel(warp, tyy, -tx);

  /* wv_shade */
  v8f k = sel(warp, (v8f){0} + C->k[0], (v8f){0} + C->k[1]);
  v8f ti = t0 * d->wi[0] + t1 * d->wi[1] + tz * d->wi[2];
  v8f to = t0 * d->wo[0] + t1 * d->wo[1] + tz * d->wo[2];
  v8f th = t0 * d->h[0] + t1 * d->h[1] + tz * d->h[2];
  v8f si2 = 1.0f - k * ti * ti, so2 = 1.0f - k * to * to;
  v8f si = vsqrt(sel(si2 > 0.0f, si2, (v8f){0})), so = vsqrt(sel(so2 > 0.0f, so2, (v8f){0}));
  v8f A = si / d->mi + so / d->mo;
  v8f q = 1.0f + sel(warp, (v8f){0} + C->ia2m1[0], (v8f){0} + C->ia2m1[1]) * th * th;
  v8f D = 1.0f / (sel(warp, (v8f){0} + C->pia[0], (v8f){0} + C->pia[1]) * q * q);
  v8f spec = D * (1.0f - vexpf(-f->P.thickness * A)) / (C->four_mo * A);
  spec = sel(A > 0.0f, spec, (v8f){0});
  if (f->glints) {
    v8u g = vhash2(tou64(vfloor(gxf)), tou64(vfloor(gyf)), f->seed ^ 0x676c696eULL) >> 52;
    const float *gt = f->glint_table;
    spec *= (v8f){gt[g[0]], gt[g[1]], gt[g[2]], gt[g[3]], gt[g[4]], gt[g[5]], gt[g[6]], gt[g[7]]};
  }
  v8f ni = d->wi[0] * n0 + d->wi[1] * n1 + d->wi[2] * nz;
  v8f diff = (f->P.blend * sel(ni > 0.0f, ni, (v8f){0}) + C->bm) * C->inv_pi;
  for (int ch = 0; ch < 3; ch++) {
    v8f ks = sel(warp, (v8f){0} + f->P.ks[0][ch], (v8f){0} + f->P.ks[1][ch]);
    v8f kd = sel(warp, (v8f){0} + f->P.kd[0][ch], (v8f){0} + f->P.kd[1][ch]);
    out[ch] = sel(lit, d->light * (ks * spec + kd * diff), (v8f){0});
  }
  return 1;
}

WV_SIMD_CLONES
void wv_render_fast_pixel(const wv_fabric *f, const wv_footprint *fp, int px, int py, int spp, int width,
                          float acc[WV_ACC_ROWS][3]) {
  const wv_yarn_model *m = &f->ym;
  int k0 = 0;
  /* Tiled maps wrap segment identities (period_rows/cols); the renderer never does. */
  if (m->period_rows == 0 && m->period_cols == 0) {
    pixel_consts C;
    strata_init(&C.strata, px, py, spp, width, f->seed);
    for (int t = 0; t < 2; t++) {
      float a = f->P.alpha[t];
      C.half_w[t] = 0.5f * m->spacing[t] * m->width;
      C.uos[t] = m->umax_over_spacing[t], C.vsc[t] = m->v_scale[t], C.beta[t] = m->beta[t];
      C.k[t] = 1.0f - a * a, C.ia2m1[t] = 1.0f / (a * a) - 1.0f;
      C.pia[t] = 3.14159265358979f * a;
    }
    C.noise = 0.1f * (float)m->noise_level;
    C.bm = (1.0f - f->P.blend) * fp->dirs.mi;
    C.four_mo = 4.0f * fp->dirs.mo;
    C.inv_pi = 1.0f / 3.14159265358979f;
    v8f sum[3]; /* lane i: row i of acc */
    for (int ch = 0; ch < 3; ch++)
      for (int i = 0; i < W; i++) sum[ch][i] = acc[i][ch];
    for (; k0 + W <= spp; k0 += W) {
      v8f rad[3];
      if (!shade8(f, fp, &C, k0, rad)) break;
      for (int ch = 0; ch < 3; ch++) sum[ch] += rad[ch];
    }
    for (int ch = 0; ch < 3; ch++)
      for (int i = 0; i < W; i++) acc[i][ch] = sum[ch][i];
  }
  wv_pixel_sampler ps;
  if (k0 < spp) wv_pixel_sampler_init(&ps, px, py, spp, width, f->seed);
  for (int k = k0; k < spp; k++) { /* the rest, or everything when a block could not be done */
    float sx, sy, fx, fy;
    wv_pixel_sampler_at(&ps, k, &sx, &sy);
    wv_footprint_at(fp, sx, sy, &fx, &fy);
    wv_shade(f, &fp->dirs, fx, fy, acc[k % WV_ACC_ROWS]);
  }
}

/* Bit i set: wv_rig_trace (rig.c) certainly rejects the ray of sample s0 + i: it
 * misses the cylinder, or the light or the camera is clearly below the surface's
 * horizon there (rows along the top and bottom of the cylinder, which would
 * otherwise be traced sample by sample to no effect). The miss test repeats
 * wv_rig_trace's first steps operation for operation; the horizon tests keep a
 * margin of 1e-4 in the cosine, far above rounding, and leave closer calls to the
 * scalar trace. */
INL unsigned cylinder_rejects8(const wv_camera_rig *r, v8f sx, v8f sy, int px, int py) {
  v8f x = (float)px + sx, y = (float)py + sy;
  v8f ndx = (2.0f * x / (float)r->width - 1.0f) * r->tan_half * r->aspect;
  v8f ndy = (1.0f - 2.0f * y / (float)r->height) * r->tan_half;
  v8f d0 = r->fwd[0] + ndx * r->right[0] + ndy * r->up[0];
  v8f d1 = r->fwd[1] + ndx * r->right[1] + ndy * r->up[1];
  v8f d2 = r->fwd[2] + ndx * r->right[2] + ndy * r->up[2];
  v8f l = vsqrt(d0 * d0 + d1 * d1 + d2 * d2);
  d0 /= l, d1 /= l, d2 /= l;
  const float *o = r->cpos;
  v8f a = d1 * d1 + d2 * d2;
  v8f b = o[1] * d1 + o[2] * d2;
  float c = o[1] * o[1] + o[2] * o[2] - r->radius * r->radius;
  v8f disc = b * b - a * c;
  v8i miss = (a < 1e-12f) | (disc < 0.0f);
  /* where it hits: the nearest point in front, its normal, the two cosines */
  v8f sa = sel(miss, (v8f){0} + 1, a), sq = vsqrt(sel(miss, (v8f){0}, disc));
  v8f t = (-b - sq) / sa;
  t = sel(t <= 0.0f, (-b + sq) / sa, t);
  v8f p0 = o[0] + t * d0, p1 = o[1] + t * d1, p2 = o[2] + t * d2;
  float inv = 1.0f / r->radius;
  v8f n1 = p1 * inv, n2 = p2 * inv;
  v8f cos_o = -(d1 * n1 + d2 * n2); /* |d| = 1 */
  v8f l0 = r->lpos[0] - p0, l1 = r->lpos[1] - p1, l2 = r->lpos[2] - p2;
  v8f ln = l1 * n1 + l2 * n2, ll = l0 * l0 + l1 * l1 + l2 * l2;
  v8i below = (t > 0.0f) & ((cos_o < -1e-4f) | ((ln < 0.0f) & (ln * ln > 1e-8f * ll)));
  miss |= below;
  unsigned bits = 0;
  for (int i = 0; i < W; i++) bits |= (unsigned)(miss[i] & 1) << i;
  return bits;
}

WV_SIMD_CLONES
void wv_render_traced_pixel(const wv_camera_rig *rig, const wv_fabric *f, int px, int py, int spp,
                            float acc[WV_ACC_ROWS][3]) {
  pixel_strata P;
  strata_init(&P, px, py, spp, rig->width, f->seed);
  wv_pixel_sampler ps;
  wv_pixel_sampler_init(&ps, px, py, spp, rig->width, f->seed);
  for (int k0 = 0; k0 < spp; k0 += W) {
    /* Most of these pixels lie beside the cylinder or beyond its horizon: reject eight rays at once. */
    int block = k0 + W <= spp && rig->shape == WV_SHAPE_CYLINDER;
    v8f bx, by; /* the block's positions, as wv_pixel_sampler_at gives them */
    unsigned miss = 0;
    if (block) {
      sample8(&P, k0, &bx, &by);
      miss = cylinder_rejects8(rig, bx, by, px, py);
    }
    for (int k = k0; k < k0 + W && k < spp; k++) {
      if (miss >> (k - k0) & 1) continue;
      float sx, sy;
      if (block) sx = bx[k - k0], sy = by[k - k0];
      else wv_pixel_sampler_at(&ps, k, &sx, &sy);
      wv_hit hit;
      if (!wv_rig_trace(rig, (float)px + sx, (float)py + sy, &hit)) continue;
      wv_dirs d;
      wv_dirs_from_hit(&hit, &d);
      wv_shade(f, &d, hit.fx, hit.fy, acc[k % WV_ACC_ROWS]);
    }
  }
}
