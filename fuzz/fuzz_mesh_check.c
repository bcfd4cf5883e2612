/* woven fuzz: the checks of a mesh file before assimp reads it (wv_mesh_check_file):
 * PLY headers, OBJ lines, binary STL counts, GLB chunks and glTF JSON (buffers,
 * accessors, the node tree). The first byte of the input picks the file's extension;
 * the rest is the file. No assimp: thousands of inputs a second. A file beside the
 * input, "b.bin" (16 bytes), lets glTF buffers name an external file. */
#include <stdio.h>
#include <stdlib.h>

#include "fuzz_util.h"
#include "woven/mesh.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  if (size < 1) return 0;
  static const char *const names[8] = {"input.obj", "input.ply", "input.gltf", "input.glb",
                                       "input.stl", "input.ply", "input.gltf", "input.glb"};
  const char *name = names[data[0] & 7];
  fuzz_dir d;
  fuzz_dir_open(&d, name, data + 1, size - 1);
  char bin[4200];
  snprintf(bin, sizeof bin, "%s/b.bin", d.dir);
  FILE *f = fopen(bin, "wb");
  if (f) fwrite("0123456789abcdef", 1, 16, f), fclose(f);
  wv_error err = {0};
  /* a small limit, so that counts just over it are reached by mutation */
  wv_status st = wv_mesh_check_file(d.file, (size_t)1 << 20, &err);
  fuzz_check_refusal(st, &err, name);
  remove(bin);
  fuzz_dir_remove(&d);
  return 0;
}
