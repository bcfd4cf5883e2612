/* woven fuzz: mesh files (wv_mesh_load through assimp, then validation and tangent
 * frames). The first byte of the input picks the file's extension (OBJ, PLY, glTF,
 * GLB), which is how assimp chooses its reader; the rest is the file. An accepted
 * mesh must pass wv_mesh_validate by itself. */
#include <stdlib.h>

#include "fuzz_util.h"
#include "woven/mesh.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  if (size < 1) return 0;
  static const char *const names[4] = {"input.obj", "input.ply", "input.gltf", "input.glb"};
  fuzz_dir d;
  fuzz_dir_open(&d, names[data[0] & 3], data + 1, size - 1);
  wv_mesh m = {0};
  wv_error err = {0};
  wv_status st = wv_mesh_load(d.file, (size_t)64 << 20, 1, &m, &err);
  fuzz_check_refusal(st, &err, names[data[0] & 3]);
  if (st == WV_OK) {
    if (wv_mesh_validate(&m, "loaded", 1, &err) != WV_OK) fuzz_fail("a loaded mesh fails validation: %s", err.msg);
    st = wv_mesh_tangents(&m, "loaded", &err);
    fuzz_check_refusal(st, &err, "loaded");
  }
  wv_mesh_free(&m);
  fuzz_dir_remove(&d);
  return 0;
}
