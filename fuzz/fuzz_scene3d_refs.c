/* woven fuzz: a scene file that refers to files (wv_scene3d_read, then wv_world_load):
 * the scene is written into a directory that holds a quad mesh (quad.obj), a fabric
 * (fab.json), an edit map (map.exr), an environment map (env.exr), a FIFO (fifo), a
 * symbolic link to the mesh (link.obj) and a subdirectory (sub), so that fuzzed
 * references reach the readers, the regular-file checks, the shared edit maps and the
 * memory budget (64 MB here). A loaded world's inputs are listed (wv_scene3d_inputs). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "fuzz_util.h"
#include "woven/io.h"
#include "woven/scene3d.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void put(const char *dir, const char *name, const char *text) {
  char p[4200];
  snprintf(p, sizeof p, "%s/%s", dir, name);
  FILE *f = fopen(p, "wb");
  if (!f || fputs(text, f) < 0 || fclose(f) != 0) fuzz_fail("cannot write %s", p);
}

static void image(const char *dir, const char *name, int w, int h, float v) {
  char p[4200];
  snprintf(p, sizeof p, "%s/%s", dir, name);
  wv_image img;
  wv_error err = {0};
  if (wv_image_alloc(&img, w, h, 3, &err)) fuzz_fail("%s", err.msg);
  for (size_t i = 0; i < (size_t)w * h * 3; i++) img.data[i] = v;
  if (wv_image_write_exr(p, &img, &err)) fuzz_fail("%s", err.msg);
  wv_image_free(&img);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  fuzz_dir d;
  fuzz_dir_open(&d, "scene.json", data, size);
  put(d.dir, "quad.obj", "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 1 0\n"
                         "f 1/1/1 4/4/1 3/3/1\nf 1/1/1 3/3/1 2/2/1\n");
  put(d.dir, "fab.json", "{\"pattern\": \"twill\"}");
  image(d.dir, "map.exr", 8, 4, 0.5f);
  image(d.dir, "env.exr", 8, 4, 1.0f);
  char p[4200], q[4200];
  snprintf(p, sizeof p, "%s/fifo", d.dir);
  if (mkfifo(p, 0600) != 0) fuzz_fail("cannot make %s", p);
  snprintf(q, sizeof q, "%s/link.obj", d.dir);
  if (symlink("quad.obj", q) != 0) fuzz_fail("cannot link %s", q);
  snprintf(q, sizeof q, "%s/sub", d.dir);
  if (mkdir(q, 0700) != 0) fuzz_fail("cannot make %s", q);
  wv_scene3d s;
  wv_error err = {0};
  wv_status st = wv_scene3d_read(d.file, &s, &err);
  fuzz_check_refusal(st, &err, "scene.json");
  if (st == WV_OK) {
    const char *in[4 * WV_SCENE3D_MAX_ITEMS];
    int n = wv_scene3d_inputs(&s, in, 4 * WV_SCENE3D_MAX_ITEMS);
    for (int i = 0; i < n && i < 4 * WV_SCENE3D_MAX_ITEMS; i++)
      if (!in[i] || !in[i][0]) fuzz_fail("an empty input name");
    s.mesh_limit_bytes = (size_t)64 << 20;
    s.env_width = s.env_width < 64 ? s.env_width : 64;
    wv_world *w = NULL;
    st = wv_world_load(&s, NULL, 1, &w, &err);
    fuzz_check_refusal(st, &err, NULL);
    wv_world_free(w);
    wv_scene3d_free(&s);
  }
  remove(p);
  snprintf(q, sizeof q, "%s/link.obj", d.dir);
  remove(q);
  static const char *const own[] = {"quad.obj", "fab.json", "map.exr", "env.exr"};
  for (int i = 0; i < 4; i++) {
    snprintf(q, sizeof q, "%s/%s", d.dir, own[i]);
    remove(q);
  }
  snprintf(q, sizeof q, "%s/sub", d.dir);
  rmdir(q);
  fuzz_dir_remove(&d);
  return 0;
}
