/* woven fuzz: the parameter file (wv_params_parse). An accepted file must survive a
 * round trip through wv_params_to_json unchanged, and its weave and texture maps
 * (a small tile: the yarn geometry every renderer uses) must build. */
#include <stdlib.h>
#include <string.h>

#include "fuzz_util.h"
#include "woven/maps.h"
#include "woven/params.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  char *text = fuzz_cstr(data, size);
  wv_params p;
  wv_error err = {0};
  wv_status st = wv_params_parse(text, "input.json", &p, &err);
  free(text);
  fuzz_check_refusal(st, &err, "input.json");
  if (st != WV_OK) return 0;
  char *j1 = wv_params_to_json(&p);
  if (!j1) fuzz_fail("wv_params_to_json failed on accepted parameters");
  wv_params q;
  if (wv_params_parse(j1, "round trip", &q, &err) != WV_OK) fuzz_fail("written parameters refused: %s", err.msg);
  char *j2 = wv_params_to_json(&q);
  if (!j2 || strcmp(j1, j2)) fuzz_fail("round trip changed the parameters:\n%s\n%s", j1, j2 ? j2 : "(null)");
  free(j1), free(j2);
  wv_maps m;
  if (wv_maps_generate(&p, 8, &m, &err) != WV_OK) fuzz_fail("maps of accepted parameters failed: %s", err.msg);
  wv_maps_free(&m);
  return 0;
}
