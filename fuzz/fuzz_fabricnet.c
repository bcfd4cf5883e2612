/* woven fuzz: the FabricNet model and training checkpoint files (wv_fabricnet_load,
 * wv_fabricnet_checkpoint_load; format in docs/fabricnet.md). The harness rewrites
 * both CRC-32s (payload at byte 496, header at 500) before loading, so mutations get
 * past the checksums to the parser; the checksum checks themselves are a compare.
 * A loaded model runs one prediction on zero features. */
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "fuzz_util.h"
#include "woven/fabricnet.h"
#include "woven/weave.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define HDR 504

static void put32(uint8_t *b, uint32_t v) {
  for (int i = 0; i < 4; i++) b[i] = (uint8_t)(v >> (8 * i));
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  uint8_t *b = malloc(size ? size : 1);
  if (!b) fuzz_fail("out of memory");
  if (size) memcpy(b, data, size);
  if (size >= HDR) {
    put32(b + 496, crc32_z(0, b + HDR, size - HDR));
    put32(b + 500, crc32_z(0, b, 500));
  }
  fuzz_file f;
  fuzz_file_open(&f, b, size);
  free(b);
  wv_fabricnet n;
  wv_error err = {0};
  wv_status s = wv_fabricnet_load(f.path, &n, &err);
  fuzz_check_refusal(s, &err, f.path);
  if (s == WV_OK) {
    float *feat = calloc((size_t)n.n_in, sizeof(float)), y[WV_NET_OUT];
    if (!feat) fuzz_fail("out of memory");
    float probs[WV_WEAVE_BUILTINS];
    s = wv_fabricnet_predict_features(&n, feat, y, probs, &err);
    fuzz_check_refusal(s, &err, NULL);
    double psum = 0;
    for (int k = 0; s == WV_OK && k < wv_weave_builtin_count(); k++) psum += probs[k];
    if (s == WV_OK && psum == psum && !(psum > 0.999 && psum < 1.001)) fuzz_fail("pattern probabilities sum to %g", psum);
    for (int k = 0; s == WV_OK && k < WV_NET_OUT; k++)
      if (!(y[k] >= 0.0f && y[k] <= 1.0f) && y[k] == y[k]) fuzz_fail("output %d = %g outside [0, 1]", k, (double)y[k]);
    free(feat);
    wv_fabricnet_free(&n);
  }
  float *m = NULL, *v = NULL;
  wv_fabricnet_trainstate ts;
  s = wv_fabricnet_checkpoint_load(f.path, &n, &m, &v, &ts, &err);
  fuzz_check_refusal(s, &err, f.path);
  if (s == WV_OK) {
    free(m), free(v);
    wv_fabricnet_free(&n);
  } else if (m || v) {
    fuzz_fail("refused checkpoint left its moments allocated");
  }
  fuzz_file_close(&f);
  return 0;
}
