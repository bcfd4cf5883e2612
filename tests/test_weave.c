/* Weave patterns: built-ins, segment table, custom patterns and their errors. */
#include <string.h>

#include "testutil.h"
#include "woven/weave.h"

/* Check the segment table against its definition by walking the pattern. */
static void check_segments(const wv_weave *w) {
  for (int i = 0; i < w->rows; i++)
    for (int j = 0; j < w->cols; j++) {
      const wv_weave_cell *c = &w->cell[i][j];
      assert_true(c->index < c->len);
      int warp = w->p[i][j];
      assert_int_equal(c->type, warp ? WV_WARP : WV_WEFT);
      /* all cells of the float have the same type, length and consecutive indices */
      for (int k = 0; k < c->len; k++) {
        int d = k - c->index;
        const wv_weave_cell *o = warp ? wv_weave_at(w, i + d, j) : wv_weave_at(w, i, j + d);
        assert_int_equal(o->type, c->type);
        assert_int_equal(o->len, c->len);
        assert_int_equal(o->index, k);
      }
      /* the float is maximal: the cells just before and after are of the other type */
      if (c->len < (warp ? w->rows : w->cols)) {
        const wv_weave_cell *before = warp ? wv_weave_at(w, i - c->index - 1, j) : wv_weave_at(w, i, j - c->index - 1);
        const wv_weave_cell *after = warp ? wv_weave_at(w, i - c->index + c->len, j)
                                          : wv_weave_at(w, i, j - c->index + c->len);
        assert_int_not_equal(before->type, c->type);
        assert_int_not_equal(after->type, c->type);
      }
    }
}

static void test_builtins(void **state) {
  (void)state;
  const char *names[] = {"plain", "twill", "satin", "twill90", "satin90"};
  int sizes[] = {2, 4, 5, 4, 5};
  for (int k = 0; k < 5; k++) {
    wv_weave w;
    wv_error err = {0};
    assert_int_equal(wv_weave_builtin(names[k], &w, &err), WV_OK);
    assert_int_equal(w.rows, sizes[k]);
    assert_int_equal(w.cols, sizes[k]);
    check_segments(&w);
  }
  wv_weave t, t90;
  wv_weave_builtin("twill", &t, NULL);
  wv_weave_builtin("twill90", &t90, NULL);
  for (int i = 0; i < 4; i++)
    for (int j = 0; j < 4; j++) assert_int_equal(t90.p[i][j], 1 - t.p[j][i]);
  /* 3/1 twill: every warp float is 3 long, every weft float 1 long */
  for (int i = 0; i < 4; i++)
    for (int j = 0; j < 4; j++) assert_int_equal(t.cell[i][j].len, t.p[i][j] ? 3 : 1);
  wv_weave s;
  wv_weave_builtin("satin", &s, NULL);
  for (int i = 0; i < 5; i++)
    for (int j = 0; j < 5; j++) assert_int_equal(s.cell[i][j].len, s.p[i][j] ? 4 : 1);
}

static void test_wraparound_lookup(void **state) {
  (void)state;
  wv_weave w;
  wv_weave_builtin("satin", &w, NULL);
  for (int i = -12; i < 12; i++)
    for (int j = -12; j < 12; j++) {
      const wv_weave_cell *a = wv_weave_at(&w, i, j), *b = &w.cell[((i % 5) + 5) % 5][((j % 5) + 5) % 5];
      assert_ptr_equal(a, b);
    }
}

static void test_custom(void **state) {
  (void)state;
  wv_weave w;
  wv_error err = {0};
  const char *basket[] = {"1100", "1100", "0011", "0011"};
  assert_int_equal(wv_weave_from_rows(basket, 4, &w, &err), WV_OK);
  check_segments(&w);
  assert_int_equal(w.cell[0][0].len, 2);
  const char *allwarp[] = {"11", "11"}; /* floats that never go under: one float per repeat */
  assert_int_equal(wv_weave_from_rows(allwarp, 2, &w, &err), WV_OK);
  assert_int_equal(w.cell[1][0].len, 2);
  const char *ragged[] = {"10", "011"};
  assert_int_equal(wv_weave_from_rows(ragged, 2, &w, &err), WV_ERR_INVALID);
  assert_non_null(strstr(err.msg, "row 2"));
  const char *bad[] = {"1x"};
  assert_int_equal(wv_weave_from_rows(bad, 1, &w, &err), WV_ERR_INVALID);
  assert_non_null(strstr(err.msg, "'x'"));
  assert_int_equal(wv_weave_builtin("herringbone", &w, &err), WV_ERR_INVALID);
  assert_non_null(strstr(err.msg, "herringbone"));
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_builtins), cmocka_unit_test(test_wraparound_lookup),
                                     cmocka_unit_test(test_custom)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
