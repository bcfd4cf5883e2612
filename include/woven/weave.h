/* woven: weave patterns and their segment table (SPEC section 2).
 * P[i][j] = 1 when warp yarn j lies over weft yarn i. Row 0 is the top row of
 * the pattern as seen in an image (fabric y decreases with the row index). */
#ifndef WOVEN_WEAVE_H
#define WOVEN_WEAVE_H

#include <stdint.h>
#include "woven/error.h"

#define WV_WEAVE_MAX 32

enum { WV_WARP = 0, WV_WEFT = 1 };

/* What is visible in one cell: the float it belongs to, that float's length in
 * cells, and the cell's index inside the float (warp floats count rows downward,
 * weft floats count columns rightward). Precomputed so lookup is O(1). */
typedef struct {
  uint8_t type;  /* WV_WARP or WV_WEFT */
  uint8_t len;   /* float length L in cells */
  uint8_t index; /* 0..len-1 */
} wv_weave_cell;

typedef struct {
  int rows, cols;
  uint8_t p[WV_WEAVE_MAX][WV_WEAVE_MAX];
  wv_weave_cell cell[WV_WEAVE_MAX][WV_WEAVE_MAX];
} wv_weave;

/* The built-in library: plain, basket, twills 2/1, 2/2 and 3/1 in S and Z direction
 * (twill21s ... twill31z), 5- and 8-harness satins (satin5, satin8), and the 90-degree
 * variants of the asymmetric ones (name + "_90": floats run across the image). Each name
 * starts with its family. The earlier names twill, satin, twill90 and satin90 still load
 * (twill31s, satin5 and their _90 variants). */
wv_status wv_weave_builtin(const char *name, wv_weave *w, wv_error *err);
int wv_weave_is_builtin(const char *name);
/* Canonical built-ins, in a fixed order (the index FabricNet's pattern head uses). */
#define WV_WEAVE_BUILTINS 16 /* wv_weave_builtin_count(), for arrays over the library */
int wv_weave_builtin_count(void);
const char *wv_weave_builtin_name(int i); /* NULL outside 0..count-1 */
/* The canonical name of a built-in (also of an earlier alias), NULL when not built in. */
const char *wv_weave_canonical(const char *name);
/* "plain", "basket", "twill", "satin", or "custom" for any other name. */
const char *wv_weave_family(const char *name);
/* The size of the groups of adjacent columns (dir 0) or rows (dir 1) that weave alike (a
 * basket's pairs): the smallest g > 1 dividing the repeat such that every column (row)
 * weaves as the first of its group; 1 when there is none. */
int wv_weave_yarn_group(const wv_weave *w, int dir);
/* The built-in that built-in i's groups of yarns weave as, each group taken as one yarn
 * (basket: plain), with the group sizes in g (columns, rows); -1 when i has no groups or
 * they weave as no built-in. Through a camera's blur i at densities d looks like that
 * built-in at d / g with yarns g times as wide. */
int wv_weave_builtin_twin(int i, int g[2]);
/* A custom pattern from n text rows of '0'/'1' of equal length (1..WV_WEAVE_MAX). */
wv_status wv_weave_from_rows(const char *const *rows, int n, wv_weave *w, wv_error *err);
/* Cell lookup for any integer row/column (wraps around the repeat). */
static inline const wv_weave_cell *wv_weave_at(const wv_weave *w, int64_t row, int64_t col) {
  int64_t r = row % w->rows, c = col % w->cols;
  if (r < 0) r += w->rows;
  if (c < 0) c += w->cols;
  return &w->cell[r][c];
}

#endif
