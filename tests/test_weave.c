/* Weave patterns: built-ins, segment table, custom patterns and their errors. */
#include <stdio.h>
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

/* Every canonical built-in: its family prefix, a valid segment table, the float lengths of
 * its family, and its 90-degree variant's definition. */
static void test_library(void **state) {
  (void)state;
  int n = wv_weave_builtin_count();
  assert_int_equal(n, 16);
  assert_null(wv_weave_builtin_name(n));
  assert_null(wv_weave_builtin_name(-1));
  for (int k = 0; k < n; k++) {
    const char *name = wv_weave_builtin_name(k);
    wv_weave w;
    wv_error err = {0};
    assert_int_equal(wv_weave_builtin(name, &w, &err), WV_OK);
    check_segments(&w);
    const char *fam = wv_weave_family(name);
    assert_int_equal(strncmp(name, fam, strlen(fam)), 0);
    assert_string_equal(wv_weave_canonical(name), name);
    int rot = strstr(name, "_90") != NULL;
    if (rot) { /* the variant is 1 - P^T of its base */
      char base[32];
      snprintf(base, sizeof base, "%.*s", (int)(strlen(name) - 3), name);
      wv_weave b;
      assert_int_equal(wv_weave_builtin(base, &b, &err), WV_OK);
      assert_int_equal(w.rows, b.cols);
      for (int i = 0; i < w.rows; i++)
        for (int j = 0; j < w.cols; j++) assert_int_equal(w.p[i][j], 1 - b.p[j][i]);
      continue;
    }
    /* longest warp and weft floats of the base patterns */
    int lw = 0, lf = 0;
    for (int i = 0; i < w.rows; i++)
      for (int j = 0; j < w.cols; j++) {
        int *l = w.p[i][j] ? &lw : &lf;
        if (w.cell[i][j].len > *l) *l = w.cell[i][j].len;
      }
    int a = 1, b = 1;
    if (!strcmp(fam, "basket")) a = b = 2;
    if (!strcmp(fam, "twill")) a = name[5] - '0', b = name[6] - '0';
    if (!strcmp(fam, "satin")) a = w.rows - 1;
    assert_int_equal(lw, a);
    assert_int_equal(lf, b);
    if (!strcmp(fam, "twill")) { /* S: the float start moves right going down; Z: left */
      int dir = name[7] == 's' ? 1 : -1;
      for (int i = 0; i < w.rows; i++)
        for (int j = 0; j < w.cols; j++)
          assert_int_equal(w.p[i][j], w.p[(i + 1) % w.rows][(j + dir + w.cols) % w.cols]);
    }
  }
  /* earlier names load as their canonical patterns */
  const char *alias[4][2] = {{"twill", "twill31s"}, {"satin", "satin5"}, {"twill90", "twill31s_90"},
                             {"satin90", "satin5_90"}};
  for (int k = 0; k < 4; k++) {
    wv_weave a, b;
    assert_int_equal(wv_weave_builtin(alias[k][0], &a, NULL), WV_OK);
    assert_int_equal(wv_weave_builtin(alias[k][1], &b, NULL), WV_OK);
    assert_memory_equal(a.p, b.p, sizeof a.p);
    assert_string_equal(wv_weave_canonical(alias[k][0]), alias[k][1]);
  }
  assert_string_equal(wv_weave_family("custom"), "custom");
  assert_null(wv_weave_canonical("custom"));
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

/* Yarns in groups: a basket's pairs, in both directions, weave as a plain weave; no other
 * built-in has groups; a custom pattern with pairs one way only has them that way. */
static void test_yarn_groups(void **state) {
  (void)state;
  wv_weave w;
  int g[2] = {0, 0};
  for (int i = 0; i < wv_weave_builtin_count(); i++) {
    const char *name = wv_weave_builtin_name(i);
    assert_int_equal(wv_weave_builtin(name, &w, NULL), WV_OK);
    int basket = !strcmp(name, "basket");
    assert_int_equal(wv_weave_yarn_group(&w, 0), basket ? 2 : 1);
    assert_int_equal(wv_weave_yarn_group(&w, 1), basket ? 2 : 1);
    int twin = wv_weave_builtin_twin(i, g);
    if (basket) {
      assert_string_equal(wv_weave_builtin_name(twin), "plain");
      assert_int_equal(g[0], 2);
      assert_int_equal(g[1], 2);
    } else {
      assert_int_equal(twin, -1);
    }
  }
  const char *rib[] = {"1100", "0011"}; /* warp in pairs, weft single */
  assert_int_equal(wv_weave_from_rows(rib, 2, &w, NULL), WV_OK);
  assert_int_equal(wv_weave_yarn_group(&w, 0), 2);
  assert_int_equal(wv_weave_yarn_group(&w, 1), 1);
  assert_int_equal(wv_weave_builtin_twin(-1, g), -1);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_builtins), cmocka_unit_test(test_library), cmocka_unit_test(test_wraparound_lookup),
                                     cmocka_unit_test(test_custom), cmocka_unit_test(test_yarn_groups)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
