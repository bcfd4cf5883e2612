/* Weave patterns: the built-in library, custom 0/1 matrices, and the segment table
 * (which float each cell belongs to) that the yarn geometry reads. */
#include "woven/weave.h"

#include <string.h>

/* The built-in library. Each entry is generated from its family's rule, so a pattern is
 * one line: twills a/b (a warp over, b under) shift their float start by one column per
 * row, S (rows run down to the right, "\\" ribs in the image, row 0 on top) or Z ("/");
 * an n-harness satin has one weft cell per row, moving `step` columns per row. */
typedef enum { FAM_PLAIN, FAM_BASKET, FAM_TWILL, FAM_SATIN } family;

typedef struct {
  const char *name;
  family fam;
  int a, b; /* twill a/b; satin: harness a, step b */
  int dir;  /* twill: +1 S, -1 Z */
  int rotate; /* the 90-degree variant: 1 - P^T of the base (floats run across) */
} builtin;

/* Canonical names first (the order is the library's index order); plain, basket and the
 * 2/2 twills have no 90-degree variant because 1 - P^T of each is the same pattern
 * shifted. */
static const builtin BUILTINS[] = {
    {"plain", FAM_PLAIN, 1, 1, 0, 0},        {"basket", FAM_BASKET, 2, 2, 0, 0},
    {"twill21s", FAM_TWILL, 2, 1, 1, 0},     {"twill21z", FAM_TWILL, 2, 1, -1, 0},
    {"twill22s", FAM_TWILL, 2, 2, 1, 0},     {"twill22z", FAM_TWILL, 2, 2, -1, 0},
    {"twill31s", FAM_TWILL, 3, 1, 1, 0},     {"twill31z", FAM_TWILL, 3, 1, -1, 0},
    {"satin5", FAM_SATIN, 5, 2, 0, 0},       {"satin8", FAM_SATIN, 8, 3, 0, 0},
    {"twill21s_90", FAM_TWILL, 2, 1, 1, 1},  {"twill21z_90", FAM_TWILL, 2, 1, -1, 1},
    {"twill31s_90", FAM_TWILL, 3, 1, 1, 1},  {"twill31z_90", FAM_TWILL, 3, 1, -1, 1},
    {"satin5_90", FAM_SATIN, 5, 2, 0, 1},    {"satin8_90", FAM_SATIN, 8, 3, 0, 1},
    /* Earlier names, kept so existing parameter files load. */
    {"twill", FAM_TWILL, 3, 1, 1, 0},        {"satin", FAM_SATIN, 5, 2, 0, 0},
    {"twill90", FAM_TWILL, 3, 1, 1, 1},      {"satin90", FAM_SATIN, 5, 2, 0, 1},
};
enum { N_CANONICAL = WV_WEAVE_BUILTINS };

int wv_weave_builtin_count(void) { return N_CANONICAL; }

const char *wv_weave_builtin_name(int i) {
  return i >= 0 && i < N_CANONICAL ? BUILTINS[i].name : NULL;
}

static const builtin *find_builtin(const char *name) {
  for (size_t i = 0; i < sizeof BUILTINS / sizeof BUILTINS[0]; i++)
    if (!strcmp(name, BUILTINS[i].name)) return &BUILTINS[i];
  return NULL;
}

int wv_weave_is_builtin(const char *name) { return name && find_builtin(name) != NULL; }

const char *wv_weave_canonical(const char *name) {
  const builtin *b = name ? find_builtin(name) : NULL;
  if (!b) return NULL;
  for (int i = 0; i < N_CANONICAL; i++)
    if (BUILTINS[i].fam == b->fam && BUILTINS[i].a == b->a && BUILTINS[i].b == b->b &&
        BUILTINS[i].dir == b->dir && BUILTINS[i].rotate == b->rotate)
      return BUILTINS[i].name;
  return NULL;
}

const char *wv_weave_family(const char *name) {
  static const char *const FAMILY[] = {"plain", "basket", "twill", "satin"};
  const builtin *b = name ? find_builtin(name) : NULL;
  return b ? FAMILY[b->fam] : "custom";
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
  const builtin *bi = name ? find_builtin(name) : NULL;
  if (!bi)
    return wv_fail(err, WV_ERR_INVALID,
                   "unknown pattern '%s' (expected plain, basket, twill21s, twill21z, twill22s, "
                   "twill22z, twill31s, twill31z, satin5, satin8, a twill or satin with _90, or "
                   "custom)",
                   name ? name : "");
  wv_weave base;
  memset(&base, 0, sizeof base);
  int n = bi->fam == FAM_PLAIN ? 2 : bi->fam == FAM_BASKET ? 4 : bi->fam == FAM_TWILL ? bi->a + bi->b : bi->a;
  base.rows = base.cols = n;
  for (int i = 0; i < n; i++)
    for (int j = 0; j < n; j++) {
      int up;
      switch (bi->fam) {
      case FAM_PLAIN: up = (i + j + 1) % 2; break;
      case FAM_BASKET: up = (i / 2 + j / 2 + 1) % 2; break;
      case FAM_TWILL: up = (((j - bi->dir * i) % n) + n) % n < bi->a; break;
      default: up = j != (((n - 1 - bi->b * i) % n) + n) % n; break;
      }
      base.p[i][j] = (uint8_t)up;
    }
  memset(w, 0, sizeof *w);
  w->rows = n;
  w->cols = n;
  for (int i = 0; i < n; i++)
    for (int j = 0; j < n; j++)
      /* 90-degree version: transpose with warp and weft roles swapped (1 - P^T). */
      w->p[i][j] = bi->rotate ? (uint8_t)(1 - base.p[j][i]) : base.p[i][j];
  build_segments(w);
  (void)err;
  return WV_OK;
}

int wv_weave_yarn_group(const wv_weave *w, int dir) {
  int n = dir ? w->rows : w->cols, m = dir ? w->cols : w->rows;
  for (int g = 2; g <= n / 2; g++) {
    if (n % g) continue;
    int same = 1;
    for (int k = 0; k < n && same; k++)
      for (int l = 0; l < m && same; l++) {
        int first = k - k % g;
        same = dir ? w->p[k][l] == w->p[first][l] : w->p[l][k] == w->p[l][first];
      }
    if (same) return g;
  }
  return 1;
}

int wv_weave_builtin_twin(int i, int g[2]) {
  wv_weave w, t;
  const char *name = wv_weave_builtin_name(i);
  if (!name || wv_weave_builtin(name, &w, NULL)) return -1;
  g[0] = wv_weave_yarn_group(&w, 0), g[1] = wv_weave_yarn_group(&w, 1);
  if (g[0] < 2 && g[1] < 2) return -1;
  int rows = w.rows / g[1], cols = w.cols / g[0];
  for (int j = 0; j < N_CANONICAL; j++) {
    if (j == i || wv_weave_builtin(BUILTINS[j].name, &t, NULL) || t.rows != rows || t.cols != cols) continue;
    int same = 1;
    for (int r = 0; r < rows && same; r++)
      for (int c = 0; c < cols && same; c++) same = t.p[r][c] == w.p[r * g[1]][c * g[0]];
    if (same) return j;
  }
  return -1;
}
