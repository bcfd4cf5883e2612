/* woven fuzz: safetensors (wv_st_open validates the header; wv_st_read_f32 reads each
 * tensor it lists with the shape it declares, then once with a wrong shape). */
#include <stdlib.h>
#include <string.h>

#include "fuzz_util.h"
#include "woven/nn.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  fuzz_file f;
  fuzz_file_open(&f, data, size);
  wv_safetensors st;
  wv_error err = {0};
  wv_status s = wv_st_open(&st, f.path, &err);
  fuzz_check_refusal(s, &err, f.path);
  if (s == WV_OK) {
    for (int i = 0; i < st.n; i++) {
      const wv_st_tensor *t = &st.t[i];
      if (wv_st_find(&st, t->name) != t) fuzz_fail("tensor '%s' not found by its name", t->name);
      /* open() checked that the bytes lie inside the file, so the count is bounded by the input */
      size_t numel = 1;
      for (int d = 0; d < t->ndim; d++) numel *= (size_t)t->shape[d];
      if (numel > size) fuzz_fail("tensor '%s' has %zu values in a %zu-byte file", t->name, numel, size);
      float *out = malloc((numel ? numel : 1) * sizeof(float));
      if (!out) fuzz_fail("out of memory");
      s = wv_st_read_f32(&st, t->name, t->ndim, t->shape, out, &err);
      fuzz_check_refusal(s, &err, f.path);
      int64_t wrong[WV_ST_MAX_DIMS + 1];
      memcpy(wrong, t->shape, sizeof t->shape);
      wrong[t->ndim] = 2;
      s = wv_st_read_f32(&st, t->name, t->ndim + 1, wrong, out, &err);
      if (s == WV_OK) fuzz_fail("tensor '%s' read with a wrong shape", t->name);
      fuzz_check_refusal(s, &err, f.path);
      free(out);
    }
    wv_st_close(&st);
  }
  fuzz_file_close(&f);
  return 0;
}
