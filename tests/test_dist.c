/* Tests of the dist module without an MPI launcher: the share of one process, the
 * output directory lock (refusal, stale takeover, another host), and the photo list
 * of a capture batch. The MPI paths run in tests/cli_mpi.sh and tests/cli_batch.sh. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "testutil.h"
#include "woven/batch.h"
#include "woven/dist.h"

static void write_text(const char *path, const char *text) {
  FILE *f = fopen(path, "w");
  assert_non_null(f);
  fputs(text, f);
  fclose(f);
}

static int every_third_done(void *user, int k) {
  (*(int *)user)++;
  return k % 3 == 0;
}

static void test_share_one_process(void **state) {
  (void)state;
  wv_dist d;
  wv_error err = {0};
  assert_int_equal(wv_dist_begin(&d, &err), WV_OK);
  assert_int_equal(d.rank, 0);
  assert_int_equal(d.size, 1);
  int calls = 0, *mine = NULL, nmine = 0, ntodo = 0;
  assert_int_equal(wv_dist_share(&d, 10, every_third_done, &calls, &mine, &nmine, &ntodo, &err), WV_OK);
  assert_int_equal(calls, 10); /* every item checked once */
  assert_int_equal(ntodo, 6);
  assert_int_equal(nmine, 6);
  const int want[6] = {1, 2, 4, 5, 7, 8};
  for (int i = 0; i < 6; i++) assert_int_equal(mine[i], want[i]);
  free(mine);
  assert_int_equal(wv_dist_sum_int(&d, 7), 7);
  assert_int_equal(wv_dist_max_int(&d, 3), 3);
  wv_dist_end(&d);
}

static long dead_pid(void) {
  pid_t p = fork();
  if (p == 0) _exit(0);
  waitpid(p, NULL, 0);
  return (long)p;
}

static void test_lock(void **state) {
  (void)state;
  const char *dir = tu_tmpdir("dist_lock");
  wv_dir_lock a, b;
  char note[4400], path[4200], host[256], text[512];
  wv_error err = {0};
  assert_int_equal(wv_dir_lock_acquire(dir, &a, note, sizeof note, &err), WV_OK);
  assert_string_equal(note, "");
  snprintf(path, sizeof path, "%s/woven.lock", dir);
  struct stat sb;
  assert_int_equal(stat(path, &sb), 0);
  /* a second job (here: this live process again) is refused and the lock stays */
  assert_int_equal(wv_dir_lock_acquire(dir, &b, note, sizeof note, &err), WV_ERR_IO);
  assert_non_null(strstr(err.msg, "in use by another woven job"));
  assert_int_equal(b.held, 0);
  assert_int_equal(stat(path, &sb), 0);
  wv_dir_lock_release(&a);
  assert_int_not_equal(stat(path, &sb), 0);
  /* the lock's temporary file never follows a link planted under its name */
  char tmp[4300], victim[4300];
  snprintf(victim, sizeof victim, "%s/victim", dir);
  snprintf(tmp, sizeof tmp, "%s/woven.lock.%ld.tmp", dir, (long)getpid());
  FILE *vf = fopen(victim, "w");
  assert_non_null(vf);
  fputs("keep", vf), fclose(vf);
  assert_int_equal(symlink(victim, tmp), 0);
  assert_int_equal(wv_dir_lock_acquire(dir, &a, note, sizeof note, &err), WV_OK);
  wv_dir_lock_release(&a);
  vf = fopen(victim, "r");
  char kept[8] = {0};
  assert_non_null(vf);
  assert_int_equal(fread(kept, 1, sizeof kept - 1, vf), 4), fclose(vf);
  assert_string_equal(kept, "keep");
  assert_int_not_equal(lstat(tmp, &sb), 0);
  unlink(victim);
  /* the lock of a process that is gone is taken over, with a note */
  gethostname(host, sizeof host);
  host[sizeof host - 1] = 0;
  snprintf(text, sizeof text, "%s %ld\n", host, dead_pid());
  write_text(path, text);
  assert_int_equal(wv_dir_lock_acquire(dir, &a, note, sizeof note, &err), WV_OK);
  assert_non_null(strstr(note, "stale"));
  wv_dir_lock_release(&a);
  /* another host's lock cannot be checked: refused, and the message says what to do */
  write_text(path, "elsewhere.example 12345\n");
  assert_int_equal(wv_dir_lock_acquire(dir, &a, note, sizeof note, &err), WV_ERR_IO);
  assert_non_null(strstr(err.msg, "elsewhere.example"));
  assert_non_null(strstr(err.msg, "remove the lock file"));
  write_text(path, "garbage");
  assert_int_equal(wv_dir_lock_acquire(dir, &a, note, sizeof note, &err), WV_ERR_IO);
  unlink(path);
}

static void test_batch_list(void **state) {
  (void)state;
  const char *dir = tu_tmpdir("dist_list");
  char p[4200], photos[4200];
  snprintf(photos, sizeof photos, "%s/photos", dir);
  mkdir(photos, 0777);
  const char *files[] = {"b.png", "a.JPG", "c.tar.exr", "notes.txt", ".hidden.png"};
  for (int i = 0; i < 5; i++) {
    snprintf(p, sizeof p, "%s/%s", photos, files[i]);
    write_text(p, "x");
  }
  wv_batch_item *it = NULL;
  int n = 0;
  wv_error err = {0};
  assert_int_equal(wv_batch_list(photos, &it, &n, &err), WV_OK);
  assert_int_equal(n, 3); /* images only, by name, hidden files skipped */
  assert_string_equal(it[0].name, "a");
  assert_string_equal(it[1].name, "b");
  assert_string_equal(it[2].name, "c.tar");
  free(it);
  /* a list file: comments and blank lines skipped, relative paths from the file's directory */
  snprintf(p, sizeof p, "%s/list.txt", dir);
  write_text(p, "# photos\n\n  photos/b.png  \r\n/abs/x.jpg\n");
  assert_int_equal(wv_batch_list(p, &it, &n, &err), WV_OK);
  assert_int_equal(n, 2);
  char want[4200];
  snprintf(want, sizeof want, "%s/photos/b.png", dir);
  assert_string_equal(it[0].photo, want);
  assert_string_equal(it[1].photo, "/abs/x.jpg");
  assert_string_equal(it[1].name, "x");
  free(it);
  /* two photos with one name would share an output directory */
  write_text(p, "photos/b.png\nother/b.jpg\n");
  assert_int_equal(wv_batch_list(p, &it, &n, &err), WV_ERR_INVALID);
  assert_non_null(strstr(err.msg, "rename one"));
  assert_null(it);
  write_text(p, "# nothing\n");
  assert_int_equal(wv_batch_list(p, &it, &n, &err), WV_ERR_INVALID);
  assert_non_null(strstr(err.msg, "no photos"));
  write_text(p, "photos/.png\n");
  assert_int_equal(wv_batch_list(p, &it, &n, &err), WV_ERR_INVALID);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_share_one_process),
      cmocka_unit_test(test_lock),
      cmocka_unit_test(test_batch_list),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
