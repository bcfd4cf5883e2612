/* Counts and sizes read from files stay within the limits that bound what woven
 * allocates: inputs the fuzzers in fuzz/ found (each also kept as a regression input
 * in fuzz/regress/). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"
#include "woven/fit.h"
#include "woven/io.h"

/* Writes a small valid fit checkpoint and returns its text (caller frees). */
static char *checkpoint_text(const char *path) {
  wv_fit_opts o;
  wv_fit_opts_default(&o);
  o.iters = 4;
  wv_params p;
  wv_error err;
  assert_int_equal(wv_params_default("twill", &p, &err), WV_OK);
  wv_fit_state st;
  assert_int_equal(wv_fit_state_init(&st, &p, &o, &err), WV_OK);
  st.iter = 1;
  st.log[0] = (wv_fit_record){.iter = 0, .loss = 0.5, .gram = 0.4, .prior = 0.01, .pixel = 0.09};
  assert_int_equal(wv_fit_checkpoint_write(path, &st, &o, "default", &err), WV_OK);
  wv_fit_state_free(&st);
  char *text;
  assert_int_equal(wv_read_file(path, &text, NULL, &err), WV_OK);
  return text;
}

/* A checkpoint's iteration count sizes the fit's log: 99999999 iterations asked
 * for a 4.8 GB log before the fit started. The count is limited as --iters is. */
static void test_checkpoint_iters(void **state) {
  (void)state;
  const char *dir = tu_tmpdir("limits_iters");
  assert_non_null(dir);
  char path[600];
  snprintf(path, sizeof path, "%s/checkpoint.json", dir);
  char *text = checkpoint_text(path);
  wv_fit_state st;
  wv_fit_opts o;
  char name[64];
  wv_error err;
  assert_int_equal(wv_fit_checkpoint_read(path, &st, &o, name, sizeof name, &err), WV_OK);
  assert_int_equal(o.iters, 4);
  wv_fit_state_free(&st);
  char *at = strstr(text, "\"iters\":4,");
  assert_non_null(at);
  char *edited = malloc(strlen(text) + 16);
  snprintf(edited, strlen(text) + 16, "%.*s\"iters\":99999999,%s", (int)(at - text), text, at + strlen("\"iters\":4,"));
  assert_int_equal(wv_write_file_atomic(path, edited, strlen(edited), &err), WV_OK);
  assert_int_equal(wv_fit_checkpoint_read(path, &st, &o, name, sizeof name, &err), WV_ERR_INVALID);
  assert_non_null(strstr(err.msg, path));
  assert_non_null(strstr(err.msg, "iters' = 99999999"));
  free(text), free(edited);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_checkpoint_iters)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
