/* The integrators' inner loop: the samples of a row of pixels, eight at a
 * time, through the 8-wide sampler, tracer and shading kernel, into each
 * pixel's sums (and, for the gradient, its derivative sums).
 *
 * A row is taken in chunks of 8 pixels. Each pixel's first spp - spp mod 8
 * samples go eight at a time, one vector per 8 consecutive samples, so lane i
 * holds row i of the pixel's sums. The remaining t = spp mod 8 samples of the
 * chunk's pixels (all of them when spp < 8) are laid end to end, pixel by
 * pixel, and shaded eight at a time as well: one vector may hold samples of
 * several pixels, each lane with its own footprint and directions. Every lane
 * computes what the scalar kernel computes for its sample, and every sample is
 * added to row s mod 8 of its pixel in sample order, so the image is the same
 * whatever the packing. */
#include <stddef.h>
#include <string.h>

#include "render/render_internal.h"

#define CHUNK 8 /* pixels per chunk: CHUNK * t tail samples always fill whole vectors */
#define PAD 16  /* per-pixel arrays hold CHUNK entries and room for an 8-wide load from any of them */

/* A chunk's pixels, one array per quantity (lane loads gather from them). */
typedef struct {
  float fx[4][PAD], fy[4][PAD]; /* footprint corners */
  float wi[3][PAD], wo[3][PAD], h[3][PAD], mi[PAD], mo[PAD], light[PAD]; /* footprint directions */
  int32_t traced[PAD];          /* -1: trace every sample */
  uint64_t hash[PAD];           /* sampler state */
  uint32_t keyx[PAD], keyy[PAD];
  wv_f8 acc[CHUNK][3];          /* the pixels' sums: lane r = row r */
  wv_f8 open[CHUNK];            /* with the light behind: the samples that see it through an open gap */
  wv_f8 J[CHUNK][2][WV_J_COUNT];
} chunk;

/* The lanes' values of a per-pixel array: pixel slot[k] for lane k. The slots of
 * a vector lie within 8 consecutive pixels from slot[0]: one load and one
 * permutation. */
#if defined(__clang__) /* no variable permutation builtin: lane by lane */
#define LANES(name, V, T)                               \
  WV_INLINE V name(const T *a, wv_i8 slot) {            \
    V v;                                                \
    for (int k = 0; k < 8; k++) v[k] = a[slot[k]];      \
    return v;                                           \
  }
LANES(lanes_q, wv_q8, uint64_t)
#else
#define LANES(name, V, T)                               \
  WV_INLINE V name(const T *a, wv_i8 slot) {            \
    V v;                                                \
    memcpy(&v, a + slot[0], sizeof v);                  \
    return __builtin_shuffle(v, slot - slot[0]);        \
  }
WV_INLINE wv_q8 lanes_q(const uint64_t *a, wv_i8 slot) {
  wv_q8 v;
  memcpy(&v, a + slot[0], sizeof v);
  return __builtin_shuffle(v, __builtin_convertvector(slot - slot[0], wv_l8));
}
#endif
LANES(lanes_f, wv_f8, float)
LANES(lanes_i, wv_i8, int32_t)
LANES(lanes_w, wv_w8, uint32_t)

/* ((v0 + v1) + (v2 + v3)) + ((v4 + v5) + (v6 + v7)): WV_ACC_TREE over the lanes. */
WV_INLINE float tree8(wv_f8 v) { return ((v[0] + v[1]) + (v[2] + v[3])) + ((v[4] + v[5]) + (v[6] + v[7])); }

/* tree8 of eight vectors at once, lane k of the result that of v[k]: the same additions
 * of the same pairs, made across vectors (each level adds neighbouring lanes). */
WV_INLINE wv_f8 pairs8(wv_f8 a, wv_f8 b) { /* a0+a1, a2+a3, b0+b1, b2+b3, a4+a5, a6+a7, b4+b5, b6+b7 */
  return __builtin_shufflevector(a, b, 0, 2, 8, 10, 4, 6, 12, 14) +
         __builtin_shufflevector(a, b, 1, 3, 9, 11, 5, 7, 13, 15);
}
WV_INLINE wv_f8 tree8x8(const wv_f8 v[8]) {
  wv_f8 p = pairs8(pairs8(v[0], v[1]), pairs8(v[2], v[3])), q = pairs8(pairs8(v[4], v[5]), pairs8(v[6], v[7]));
  return __builtin_shufflevector(p, q, 0, 1, 2, 3, 8, 9, 10, 11) +
         __builtin_shufflevector(p, q, 4, 5, 6, 7, 12, 13, 14, 15);
}

/* v's lanes moved to where idx says: lane r takes v[idx[r]]. */
#if defined(__clang__)
WV_INLINE wv_f8 permute8(wv_f8 v, wv_i8 idx) {
  wv_f8 o;
  for (int r = 0; r < 8; r++) o[r] = v[idx[r]];
  return o;
}
WV_INLINE wv_i8 permutei8(wv_i8 v, wv_i8 idx) {
  wv_i8 o;
  for (int r = 0; r < 8; r++) o[r] = v[idx[r]];
  return o;
}
#else
WV_INLINE wv_f8 permute8(wv_f8 v, wv_i8 idx) { return __builtin_shuffle(v, idx); }
WV_INLINE wv_i8 permutei8(wv_i8 v, wv_i8 idx) { return __builtin_shuffle(v, idx); }
#endif

/* Shade the samples s[k] of pixels slot[k] (lanes with live[k]) and add them
 * into their pixels' sums. uniform: one pixel, eight consecutive samples from a
 * multiple of 8, so lane k is row k. */
WV_INLINE void shade_block(const wv_camera_rig *rig, const wv_fabric *fab, chunk *C, int x0, int py, int nx, int ny,
                           wv_i8 slot, wv_i8 s, wv_i8 live, int uniform, int grad) {
  s = wv_seli(live, s, wv_splati8(0)); /* lanes without a sample: a valid index all the same */
  wv_pixel_sampler_8 ps = {lanes_q(C->hash, slot), lanes_w(C->keyx, slot), lanes_w(C->keyy, slot)};
  wv_f8 sx, sy;
  wv_sample_at_8(&ps, nx, ny, s, &sx, &sy);

  /* pixels with a footprint: a bilinear map of the corners, the centre's directions */
  wv_f8 cx[4], cy[4];
  for (int k = 0; k < 4; k++) cx[k] = lanes_f(C->fx[k], slot), cy[k] = lanes_f(C->fy[k], slot);
  wv_f8 x = wv_footprint_at_8(cx, sx, sy), y = wv_footprint_at_8(cy, sx, sy);
  wv_dirs_8 d;
  for (int k = 0; k < 3; k++)
    d.wi[k] = lanes_f(C->wi[k], slot), d.wo[k] = lanes_f(C->wo[k], slot), d.h[k] = lanes_f(C->h[k], slot);
  d.mi = lanes_f(C->mi, slot), d.mo = lanes_f(C->mo, slot), d.light = lanes_f(C->light, slot);

  /* pixels on the silhouette: trace each sample */
  wv_i8 traced = lanes_i(C->traced, slot) & live;
  if (wv_any(traced)) {
    wv_hit_8 h;
    wv_trace_8(rig, wv_itof(x0 + slot) + sx, (float)py + sy, &h);
    wv_dirs_8 dt;
    wv_dirs_make_8(h.wi, h.wo, h.light, &dt);
    x = wv_sel(traced, h.fx, x), y = wv_sel(traced, h.fy, y);
    for (int k = 0; k < 3; k++) {
      d.wi[k] = wv_sel(traced, dt.wi[k], d.wi[k]);
      d.wo[k] = wv_sel(traced, dt.wo[k], d.wo[k]);
      d.h[k] = wv_sel(traced, dt.h[k], d.h[k]);
    }
    d.mi = wv_sel(traced, dt.mi, d.mi), d.mo = wv_sel(traced, dt.mo, d.mo);
    d.light = wv_sel(traced, dt.light, d.light);
    live &= ~traced | h.hit;
  }
  if (!wv_any(live)) return;
  /* lanes without a sample: a harmless point and direction (the light on the side of
   * the others), result dropped */
  const wv_f8 zero = wv_splat8(0.0f), one = wv_splat8(1.0f), li = wv_splat8(rig->transmit ? -1.0f : 1.0f);
  x = wv_sel(live, x, zero), y = wv_sel(live, y, zero);
  for (int k = 0; k < 3; k++) {
    wv_f8 up = k == 2 ? one : zero;
    d.wi[k] = wv_sel(live, d.wi[k], k == 2 ? li : zero), d.wo[k] = wv_sel(live, d.wo[k], up);
    d.h[k] = wv_sel(live, d.h[k], up);
  }
  d.mi = wv_sel(live, d.mi, li), d.mo = wv_sel(live, d.mo, one), d.light = wv_sel(live, d.light, zero);

  wv_f8 rad[3], open = zero;
  wv_shade_grad_8 G;
  wv_shade_ex_8(fab, &fab->P, &d, x, y, rad, grad ? &G : NULL, rig->transmit ? &open : NULL);
  for (int c = 0; c < 3; c++) rad[c] = wv_sel(live, rad[c], zero);
  open = wv_sel(live, open, zero);
  if (grad)
    for (int j = 0; j < WV_J_COUNT; j++) G.J[j] = wv_sel(live, G.J[j], zero);

  if (uniform) {
    int i = slot[0];
    for (int c = 0; c < 3; c++) C->acc[i][c] += rad[c];
    if (rig->transmit) C->open[i] += open;
    if (grad)
      for (int j = 0; j < WV_J_COUNT; j++) {
        C->J[i][WV_WARP][j] += wv_sel(G.warp, G.J[j], zero);
        C->J[i][WV_WEFT][j] += wv_sel(G.warp, zero, G.J[j]);
      }
    return;
  }
  /* Lanes of several pixels: each pixel's lanes moved to their rows (a pixel has at most
   * one sample per row here, fewer than 8 left), added with zeros in its other rows,
   * which leave the sums as they are (they start at +0 and never become -0). */
  unsigned bits = wv_bits_8(live);
  for (int i = slot[__builtin_ctz(bits)]; bits; i++) {
    wv_i8 idx = WV_IOTA8, in = wv_splati8(0);
    for (unsigned b = bits; b; b &= b - 1) {
      int k = __builtin_ctz(b), r = s[k] % WV_ACC_ROWS;
      if (slot[k] != i) continue;
      idx[r] = k, in[r] = -1;
      bits &= ~(1u << k);
    }
    if (!wv_any(in)) continue; /* a pixel whose samples here all missed */
    for (int c = 0; c < 3; c++) C->acc[i][c] += wv_sel(in, permute8(rad[c], idx), zero);
    if (rig->transmit) C->open[i] += wv_sel(in, permute8(open, idx), zero);
    if (grad) {
      wv_i8 warp = in & permutei8(G.warp, idx), weft = in & ~warp;
      for (int j = 0; j < WV_J_COUNT; j++) {
        wv_f8 v = permute8(G.J[j], idx);
        C->J[i][WV_WARP][j] += wv_sel(warp, v, zero);
        C->J[i][WV_WEFT][j] += wv_sel(weft, v, zero);
      }
    }
  }
}

/* One chunk of n <= CHUNK pixels from px0. */
WV_INLINE void render_chunk(const wv_camera_rig *rig, const wv_fabric *fab, chunk *C, int py, int px0, int n, int spp,
                            float (*rad)[3], wv_grad_pixel *gp, int grad) {
  int nx, ny;
  wv_pixel_grid(spp, &nx, &ny);
  memset(C, 0, grad ? sizeof *C : offsetof(chunk, J)); /* the derivative sums only when made */
  for (int i = 0; i < n; i++) {
    wv_footprint fp;
    wv_footprint_prepare(rig, px0 + i, py, &fp);
    for (int k = 0; k < 4; k++) C->fx[k][i] = fp.fx[k], C->fy[k][i] = fp.fy[k];
    for (int k = 0; k < 3; k++) C->wi[k][i] = fp.dirs.wi[k], C->wo[k][i] = fp.dirs.wo[k], C->h[k][i] = fp.dirs.h[k];
    C->mi[i] = fp.dirs.mi, C->mo[i] = fp.dirs.mo, C->light[i] = fp.dirs.light;
    C->traced[i] = fp.fast ? 0 : -1;
    wv_pixel_sampler_f ps = wv_pixel_sampler_make(px0 + i, py, rig->width, fab->seed);
    C->hash[i] = ps.hash, C->keyx[i] = ps.keyx, C->keyy[i] = ps.keyy;
  }
  const wv_i8 all = wv_splati8(-1);
  int full = spp - spp % WV_LANES; /* samples per pixel in whole vectors */
  for (int i = 0; i < n; i++)
    for (int s0 = 0; s0 < full; s0 += WV_LANES)
      shade_block(rig, fab, C, px0, py, nx, ny, wv_splati8(i), s0 + WV_IOTA8, all, 1, grad);
  /* the rest: t samples per pixel, laid end to end pixel after pixel, 8 at a time */
  int t = spp - full;
  for (int g0 = 0; g0 < n * t; g0 += WV_LANES) {
    wv_i8 g = g0 + WV_IOTA8, slot = wv_divn(g, t); /* lane: sample g - slot t of the rest of pixel slot */
    shade_block(rig, fab, C, px0, py, nx, ny, slot, full + (g - slot * t), g < n * t, 0, grad);
  }
  for (int i = 0; i < n; i++) {
    float tot[3], sums[2 * WV_J_COUNT] = {0};
    if (grad) { /* the sums eight at a time */
      const wv_f8 *J = &C->J[i][0][0];
      int j = 0;
      for (; j + 8 <= 2 * WV_J_COUNT; j += 8) {
        wv_f8 t = tree8x8(J + j);
        memcpy(sums + j, &t, sizeof t);
      }
      for (; j < 2 * WV_J_COUNT; j++) sums[j] = tree8(J[j]);
    }
    for (int c = 0; c < 3; c++) tot[c] = tree8(C->acc[i][c]) / (float)spp;
    if (rig->transmit) { /* the light seen through the open gaps, out of focus (wv_gap_glow) */
      float glow = wv_gap_glow(rig, px0 + i, py) * (tree8(C->open[i]) / (float)spp);
      for (int c = 0; c < 3; c++) tot[c] += glow;
    }
    if (rad)
      for (int c = 0; c < 3; c++) rad[i][c] = tot[c];
    if (gp) {
      for (int c = 0; c < 3; c++) gp[i].rad[c] = tot[c];
      for (int y = 0; y < 2; y++)
        for (int j = 0; j < WV_J_COUNT; j++) gp[i].J[y][j] = sums[y * WV_J_COUNT + j];
    }
  }
}

WV_SIMD_CLONES
void wv_render_row(const wv_camera_rig *rig, const wv_fabric *fab, int py, int x0, int n, int spp, float (*rad)[3],
                   wv_grad_pixel *grad) {
  chunk C;
  for (int i = 0; i < n; i += CHUNK) {
    int m = n - i < CHUNK ? n - i : CHUNK;
    if (grad) render_chunk(rig, fab, &C, py, x0 + i, m, spp, rad ? rad + i : NULL, grad + i, 1);
    else render_chunk(rig, fab, &C, py, x0 + i, m, spp, rad + i, NULL, 0);
  }
}
