/* woven capture-batch: woven capture over a list of photos, shared over the processes
 * of an MPI job, resumable, with a summary table. The batch is the library's
 * (wv_batch_run); each photo is the library's capture (wv_capture_run). */
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "woven/batch.h"
#include "woven/dist.h"
#include "woven/photo.h"
#include "woven/scene.h"

/* The list is the positional argument; -o names the batch's directory, and --force is
 * implied (an unfinished capture is redone). */
typedef struct {
  capture_args cap;
  const char *list;
} batch_args;

static const cli_cmd CMD = {
    "capture-batch",
    "usage: woven capture-batch LIST -o DIR --scene S.json|cylinder|flat45 [capture options] [--quiet] [--json]\n"
    "\n"
    "Runs 'woven capture' on every photo of LIST: a directory (its .png, .jpg, .jpeg and .exr\n"
    "files) or a text file of photo paths, one a line (# starts a comment; relative paths are\n"
    "relative to the list file). The capture options mean what 'woven capture --help' says and\n"
    "apply to every photo.\n",
    "Writes DIR/<name>/ per photo (name: the file name without its extension; the files of\n"
    "'woven capture'), each appearing whole when its capture is done, and DIR/summary.json and\n"
    "DIR/summary.html: every photo with its status, pattern, SSIM, WSC, time.\n"
    "A photo that fails (unreadable, wrong size) is recorded and the others go on; the exit\n"
    "code is then 2. Run the same command again to resume: finished photos are not redone.\n"
    "Under 'mpirun -n N' the processes share the photos (docs/mpi.md). One job at a time per DIR.\n",
    {{CLI_PHOTO_OPTS, 0}, {CLI_MODEL_OPTS, 0}, {CLI_FIT_OPTS, 0}}, 1, {offsetof(batch_args, list)}};

typedef struct {
  cli_ctx *c;
  int quiet, rank, size;
  wv_scene scene;
  capture_args cap; /* the capture's options, photo and directory set per photo */
} batch_ctx;

static int capture_one(void *user, const char *photo, const char *dir, wv_batch_result *res) {
  batch_ctx *b = user;
  /* the photo is checked first so that the summary can say why it failed */
  wv_image img = {0};
  wv_photo_info info;
  wv_error e = {0};
  if (wv_photo_load(photo, &b->scene, &b->cap.crop, &img, &info, &e)) {
    snprintf(res->error, sizeof res->error, "%s", e.msg);
    return e.code ? (int)e.code : WV_ERR_INVALID;
  }
  wv_image_free(&img);
  b->cap.photo = photo, b->cap.out = dir;
  wv_capture_opts co;
  cli_capture_opts(&b->cap, &co);
  wv_estimate est;
  wv_fit_outcome out;
  if (wv_capture_run(&co, &est, &out, &e)) {
    int rc = e.code ? (int)e.code : WV_ERR_INVALID;
    fprintf(stderr, "woven capture: error: %s\n", e.msg); /* the log keeps each photo's message */
    snprintf(res->error, sizeof res->error, "woven capture failed (exit %d; its message is in the log)", rc);
    return rc;
  }
  res->ssim_start = out.ssim_start, res->ssim_fit = out.ssim_fit, res->wsc = out.views.wsc[1];
  res->iterations = out.state.iter;
  snprintf(res->pattern, sizeof res->pattern, "%s", out.state.params.pattern);
  wv_fit_state_free(&out.state);
  wv_estimate_free(&est);
  return 0;
}

static void on_photo(void *user, const wv_batch_item *it, const wv_batch_result *r, double secs, int done, int todo) {
  const batch_ctx *b = user;
  if (b->quiet) return;
  char who[32] = "";
  if (b->size > 1) snprintf(who, sizeof who, "rank %d: ", b->rank);
  if (r->status)
    fprintf(stderr, "%s%s (%d/%d): FAILED: %s\n", who, it->name, done, todo, r->error);
  else
    fprintf(stderr, "%s%s (%d/%d): %s, SSIM network %.4f -> fit %.4f, %.1f s\n", who, it->name, done, todo,
            r->pattern, r->ssim_start, r->ssim_fit, secs);
}

int cmd_capture_batch(int argc, char **argv) {
  cli_ctx c = {0, 0, "capture-batch"};
  batch_args ba;
  cli_capture_args_init(&ba.cap);
  ba.list = NULL;
  CLI_PARSE(&CMD, argc, argv, &ba, &c);
  const char *list = ba.list, *dir = ba.cap.out, *scene_name = ba.cap.scene;
  int rc = 0;
  if (!list) rc = cli_usage_error(c.cmd, "a LIST of photos (a file or a directory) is required");
  if (!rc && !dir) rc = cli_usage_error(c.cmd, "-o DIR is required");
  if (!rc && !scene_name) rc = cli_usage_error(c.cmd, "--scene is required");
  batch_ctx b;
  memset(&b, 0, sizeof b);
  b.c = &c, b.quiet = c.quiet, b.cap = ba.cap, b.cap.force = 1;
  wv_error err = {0};
  if (!rc && wv_scene_load(scene_name, &b.scene, &err)) rc = cli_fail(&c, &err);
  wv_dist dist;
  if (!rc && wv_dist_begin(&dist, &err)) rc = cli_fail(&c, &err);
  if (!rc) {
    b.rank = dist.rank, b.size = dist.size;
    if (dist.rank > 0) c.quiet = 1, c.json = 0;
    wv_batch_opts bo = {.list = list, .dir = dir, .capture = capture_one, .user = &b, .on_photo = on_photo};
    wv_batch_summary sum;
    char note[4400];
    wv_status st = wv_batch_run(&dist, &bo, &sum, note, sizeof note, &err);
    if (note[0]) cli_info(&c, "%s\n", note);
    if (st) {
      rc = dist.rank == 0 || err.msg[0] ? cli_fail(&c, &err) : (int)st;
    } else {
      cli_info(&c, "%s: %d photos, %d done before, %d captured, %d failed in %.1f s over %d process(es); summary in "
                   "%s/summary.html\n", dir, sum.photos, sum.done_before, sum.captured, sum.failed, sum.seconds,
               dist.size, dir);
      if (c.json)
        cli_print_json(json_pack("{s:o,s:i,s:i,s:i,s:i,s:o,s:i,s:o}", "dir", cli_str(dir), "photos", sum.photos,
                                 "done_before", sum.done_before, "captured", sum.captured, "failed", sum.failed,
                                 "seconds", cli_real(sum.seconds, 3), "processes", dist.size, "summary",
                                 cli_str("summary.json")));
      if (sum.failed) rc = WV_ERR_INVALID;
    }
    wv_dist_end(&dist);
  }
  return rc;
}
