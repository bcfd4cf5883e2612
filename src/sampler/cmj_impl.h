/* The pixel sampler, generic over the lane type (a template: see
 * kernel/lanes.h; instantiated by sampler/sampler.h). One lane is one sample:
 * its pixel's state (hash, permutation keys) and its index s, so the 8-wide
 * form may hold eight samples of one pixel or samples of several pixels. */

/* A permutation of 0 .. len-1 chosen by key (len <= 2^16): a bijection on the
 * next power of two (xor with the key, multiplications by odd numbers and
 * xorshifts are each invertible there), repeated until the value lands below len
 * (cycle walking: the walk stays on the bijection's cycle, so still a bijection).
 * Lanes that have landed keep their value while the others walk on. */
WV_INLINE WV_W WV_FN(wv_permute)(WV_W i, uint32_t len, WV_W key) {
  uint32_t mask = len - 1;
  mask |= mask >> 1, mask |= mask >> 2, mask |= mask >> 4, mask |= mask >> 8;
  WV_M walking = WV_TRUE;
  do {
    WV_W j = i;
    j ^= key & mask;
    j = (j * 0x2c1b3c6dU) & mask;
    j ^= (key >> 16) & mask;
    j ^= j >> 2;
    j = (j * 0x297a2d39U + (key >> 8)) & mask;
    j ^= j >> 1;
    i = wv_selw(walking, j, i);
    walking = walking & (i >= len);
  } while (wv_any(walking));
  return i;
}

/* What every sample of a pixel shares. */
typedef struct {
  WV_U hash;       /* wv_pixel_hash */
  WV_W keyx, keyy; /* the permutations' keys (wv_pixel_keys) */
} WV_FN(wv_pixel_sampler);

/* Sample s of a pixel of spp = nx * ny samples (wv_pixel_grid):
 * correlated multi-jittered (Kensler 2013, "Correlated Multi-Jittered
 * Sampling"). Sample s sits in cell (s mod nx, s div nx) of the grid, as plain
 * jittered sampling, and inside the cell in a sub-column and sub-row given by a
 * per-pixel permutation, so that the x values of all samples fall in distinct
 * 1/(nx ny) strata, and so do the y values. Yarn edges and the glint grid are
 * close to axis-aligned in the image: their coverage then comes out nearly
 * exact, where independent cells leave a sqrt(nx) error per edge. Position
 * (sx, sy) in [0, 1)^2 inside the pixel. */
WV_INLINE void WV_FN(wv_sample_at)(const WV_FN(wv_pixel_sampler) * ps, int nx, int ny, WV_I s, WV_P *sx,
                                   WV_P *sy) {
  WV_U h = wv_mix64g(ps->hash ^ (wv_tou64(s) * 0xc2b2ae3d27d4eb4fULL)); /* = wv_hash2(pixel, s, seed) */
  WV_P j1 = wv_u01g(h), j2 = wv_u01g(h << 24); /* bits 40..63 and 16..39 */
  WV_I row = wv_divn(s, nx), col = s - row * nx;
  WV_P subx = wv_itof((WV_I)WV_FN(wv_permute)((WV_W)row, (uint32_t)ny, ps->keyx));
  WV_P suby = wv_itof((WV_I)WV_FN(wv_permute)((WV_W)col, (uint32_t)nx, ps->keyy));
  *sx = (wv_itof(col) + (subx + j1) / (float)ny) / (float)nx;
  *sy = (wv_itof(row) + (suby + j2) / (float)nx) / (float)ny;
}
