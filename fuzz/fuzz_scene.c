/* woven fuzz: the scene file (wv_scene_parse). An accepted scene must survive a round
 * trip through wv_scene_to_json unchanged, and render: the fuzzed camera, sample and
 * light with the image shrunk to a few pixels at one sample each, so an execution
 * stays fast, followed by the sensor response. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "fuzz_util.h"
#include "woven/params.h"
#include "woven/render.h"
#include "woven/scene.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  char *text = fuzz_cstr(data, size);
  wv_scene s;
  wv_error err = {0};
  wv_status st = wv_scene_parse(text, "input.json", &s, &err);
  free(text);
  fuzz_check_refusal(st, &err, "input.json");
  if (st != WV_OK) return 0;
  char *j1 = wv_scene_to_json(&s);
  if (!j1) fuzz_fail("wv_scene_to_json failed on an accepted scene");
  wv_scene t;
  if (wv_scene_parse(j1, "round trip", &t, &err) != WV_OK) fuzz_fail("written scene refused: %s", err.msg);
  char *j2 = wv_scene_to_json(&t);
  if (!j2 || strcmp(j1, j2)) fuzz_fail("round trip changed the scene:\n%s\n%s", j1, j2 ? j2 : "(null)");
  free(j1), free(j2);
  /* Only scenes within 1 km of the origin (and offsets within 10 m) are rendered: the
   * renderer works in single precision, and refusing larger coordinates is the scene
   * validation's job, not the renderer's. */
  const double *v[4] = {s.cam_pos, s.cam_look_at, s.cam_up, s.light_pos};
  for (int i = 0; i < 4; i++)
    for (int k = 0; k < 3; k++)
      if (!(fabs(v[i][k]) <= 1e6)) return 0;
  if (!(fabs(s.fabric_offset[0]) <= 1e4 && fabs(s.fabric_offset[1]) <= 1e4)) return 0;
  /* A few pixels keep the field of view's sampling of the sample; the size check
   * itself is exercised by the parse above. */
  s.width = s.width < 6 ? s.width : 6;
  s.height = s.height < 4 ? s.height : 4;
  s.spp = 1;
  wv_params p;
  if (wv_params_default("twill", &p, &err) != WV_OK) fuzz_fail("%s", err.msg);
  wv_render_opts ro = {.spp = 1, .threads = 1};
  wv_image img = {0};
  st = wv_render(&s, &p, &ro, &img, NULL, &err);
  fuzz_check_refusal(st, &err, NULL);
  wv_image_free(&img);
  return 0;
}
