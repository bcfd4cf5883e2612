/* woven fuzz: the fit's checkpoint (wv_fit_checkpoint_read: options, start and current
 * parameters, Adam moments, RNG, registration and the iteration log). An accepted
 * checkpoint must hold a consistent state: its log as long as its iteration count,
 * valid parameters. */
#include <stdlib.h>
#include <string.h>

#include "fuzz_util.h"
#include "woven/fit.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  fuzz_file f;
  fuzz_file_open(&f, data, size);
  wv_fit_state st;
  wv_fit_opts o;
  char name[64];
  wv_error err = {0};
  wv_status s = wv_fit_checkpoint_read(f.path, &st, &o, name, sizeof name, &err);
  fuzz_check_refusal(s, &err, f.path);
  fuzz_file_close(&f);
  if (s != WV_OK) return 0;
  if (st.iter < 0 || st.iter > o.iters || (st.iter > 0 && (!st.log || st.log_cap < st.iter)))
    fuzz_fail("accepted checkpoint with iter %d of %d, log capacity %d", st.iter, o.iters, st.log_cap);
  if (wv_params_validate(&st.params, &err) || wv_params_validate(&st.start, &err))
    fuzz_fail("accepted checkpoint with invalid parameters: %s", err.msg);
  wv_fit_state_free(&st);
  return 0;
}
