#include "woven/weave.h"

#include <string.h>

typedef struct {
  const char *name;
  const char *rows[5];
  int n;
  int rotate; /* build as 1 - P^T of the named base */
} builtin;

static const builtin BUILTINS[] = {
    {"plain", {"10", "01"}, 2, 0},
    {"twill", {"1110", "0111", "1011", "1101"}, 4, 0},
    {"satin", {"11110", "11011", "01111", "11101", "10111"}, 5, 0},
    {"twill90", {"1110", "0111", "1011", "1101"}, 4, 1},
    {"satin90", {"11110", "11011", "01111", "11101", "10111"}, 5, 1},
};

int wv_weave_is_builtin(const char *name) {
  for (size_t i = 0; i < sizeof BUILTINS / sizeof BUILTINS[0]; i++)
    if (!strcmp(name, BUILTINS[i].name)) return 1;
  return 0;
}

/* Fill the segment table: every maximal wrap-around run of 1s down a column is a
 * warp float, every run of 0s along a row a weft float. */
static void build_segments(wv_weave *w) {
  int R = w->rows, C = w->cols;
  for (int i = 0; i < R; i++)
    for (int j = 0; j < C; j++) {
      int warp = w->p[i][j];
      int back = 0, fwd = 0;
      if (warp) {
        while (back < R - 1 && w->p[(i - back - 1 + R * 2) % R][j]) back++;
        if (back == R - 1) { /* whole column is warp: one float of the repeat's length */
          w->cell[i][j] = (wv_weave_cell){WV_WARP, (uint8_t)R, (uint8_t)i};
          continue;
        }
        while (w->p[(i + fwd + 1) % R][j]) fwd++;
      } else {
        while (back < C - 1 && !w->p[i][(j - back - 1 + C * 2) % C]) back++;
        if (back == C - 1) {
          w->cell[i][j] = (wv_weave_cell){WV_WEFT, (uint8_t)C, (uint8_t)j};
          continue;
        }
        while (!w->p[i][(j + fwd + 1) % C]) fwd++;
      }
      w->cell[i][j] = (wv_weave_cell){(uint8_t)(warp ? WV_WARP : WV_WEFT),
                                      (uint8_t)(back + fwd + 1), (uint8_t)back};
    }
}

wv_status wv_weave_from_rows(const char *const *rows, int n, wv_weave *w, wv_error *err) {
  memset(w, 0, sizeof *w);
  if (n < 1 || n > WV_WEAVE_MAX)
    return wv_fail(err, WV_ERR_INVALID, "weave must have 1..%d rows, got %d", WV_WEAVE_MAX, n);
  size_t cols = strlen(rows[0]);
  if (cols < 1 || cols > WV_WEAVE_MAX)
    return wv_fail(err, WV_ERR_INVALID, "weave rows must have 1..%d columns, row 1 has %zu",
                   WV_WEAVE_MAX, cols);
  for (int i = 0; i < n; i++) {
    if (strlen(rows[i]) != cols)
      return wv_fail(err, WV_ERR_INVALID, "weave row %d has %zu columns, row 1 has %zu", i + 1,
                     strlen(rows[i]), cols);
    for (size_t j = 0; j < cols; j++) {
      char ch = rows[i][j];
      if (ch != '0' && ch != '1')
        return wv_fail(err, WV_ERR_INVALID, "weave row %d: character '%c' is not 0 or 1", i + 1,
                       ch);
      w->p[i][j] = (uint8_t)(ch == '1');
    }
  }
  w->rows = n;
  w->cols = (int)cols;
  build_segments(w);
  return WV_OK;
}

wv_status wv_weave_builtin(const char *name, wv_weave *w, wv_error *err) {
  for (size_t b = 0; b < sizeof BUILTINS / sizeof BUILTINS[0]; b++) {
    const builtin *bi = &BUILTINS[b];
    if (strcmp(name, bi->name)) continue;
    wv_status st = wv_weave_from_rows(bi->rows, bi->n, w, err);
    if (st || !bi->rotate) return st;
    /* 90-degree version: transpose with warp and weft roles swapped (1 - P^T). */
    wv_weave base = *w;
    memset(w, 0, sizeof *w);
    w->rows = base.cols;
    w->cols = base.rows;
    for (int i = 0; i < w->rows; i++)
      for (int j = 0; j < w->cols; j++) w->p[i][j] = (uint8_t)(1 - base.p[j][i]);
    build_segments(w);
    return WV_OK;
  }
  return wv_fail(err, WV_ERR_INVALID,
                 "unknown pattern '%s' (expected plain, twill, satin, twill90, satin90 or custom)",
                 name);
}
