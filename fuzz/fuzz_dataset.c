/* woven fuzz: a dataset's description (wv_dataset_info_read on DIR/dataset.json). An
 * accepted description must name a valid scene, and its sample names, paths and prior
 * draws must work for the first and the last sample. */
#include <stdio.h>
#include <string.h>

#include "fuzz_util.h"
#include "woven/dataset.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  fuzz_dir d;
  fuzz_dir_open(&d, "dataset.json", data, size);
  wv_dataset_info info;
  wv_error err = {0};
  wv_status s = wv_dataset_info_read(d.dir, &info, &err);
  fuzz_check_refusal(s, &err, d.dir);
  if (s == WV_OK) {
    if (wv_scene_validate(&info.scene, &err) != WV_OK) fuzz_fail("accepted dataset with a bad scene: %s", err.msg);
    long long last = (long long)wv_dataset_pattern_count(&info) * info.per_pattern - 1;
    int ks[2] = {0, last > 2147483646 ? 2147483646 : (int)last};
    for (int i = 0; i < 2; i++) {
      char path[4096];
      wv_dataset_path(d.dir, &info, ks[i], "json", path, sizeof path);
      wv_params p;
      if (wv_dataset_sample_params(&info, ks[i], &p, &err) != WV_OK) fuzz_fail("prior draw failed: %s", err.msg);
    }
  }
  fuzz_dir_remove(&d);
  return 0;
}
