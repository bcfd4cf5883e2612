/* woven fuzz: the mesh renderer's scene file (wv_scene3d_parse). An accepted scene
 * whose objects are all built-in shapes (no mesh file, edit map or environment file
 * to read) is loaded and rendered at a few pixels, one camera ray each, so the fuzzed
 * camera, lights, shapes, materials and integrator settings reach the path tracer. */
#include <math.h>
#include <stdlib.h>

#include "fuzz_util.h"
#include "woven/params.h"
#include "woven/scene3d.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static int within(const double *v, int n, double lim) {
  for (int i = 0; i < n; i++)
    if (!(fabs(v[i]) <= lim)) return 0;
  return 1;
}

/* Only scenes that read no file and stay within 1 km of the origin are rendered
 * (the path tracer works in single precision; refusing larger coordinates is the
 * scene validation's job). */
static int renderable(const wv_scene3d *s) {
  if (s->env == WV_ENV_FILE || s->nedits > 0) return 0;
  if (!within(s->cam_pos, 3, 1e6) || !within(s->cam_look_at, 3, 1e6)) return 0;
  for (int i = 0; i < s->nobjects; i++) {
    const wv_object3d *o = &s->objects[i];
    if (o->kind == WV_OBJ_MESH || !within(o->centre, 3, 1e6) || !within(o->b, 3, 1e6) || !within(o->A, 9, 1e3))
      return 0;
    if (!(o->radius <= 1e6 && o->length <= 1e6 && o->size[0] <= 1e6 && o->size[1] <= 1e6)) return 0;
    if (o->resolution > 64) return 0; /* the shapes' tessellation is bounded by the limits, but slowly */
  }
  for (int i = 0; i < s->nlights; i++)
    if (!within(s->lights[i].pos, 3, 1e6)) return 0;
  return 1;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  char *text = fuzz_cstr(data, size);
  wv_scene3d s;
  wv_error err = {0};
  wv_status st = wv_scene3d_parse(text, "input.json", "/nonexistent", &s, &err);
  free(text);
  fuzz_check_refusal(st, &err, "input.json");
  if (st != WV_OK) return 0;
  if (renderable(&s)) {
    s.width = s.response.width = s.width < 6 ? s.width : 6;
    s.height = s.response.height = s.height < 4 ? s.height : 4;
    s.env_width = s.env_width < 64 ? s.env_width : 64;
    wv_params p;
    if (wv_params_default("twill", &p, &err) != WV_OK) fuzz_fail("%s", err.msg);
    wv_world *w = NULL;
    st = wv_world_load(&s, &p, 1, &w, &err);
    fuzz_check_refusal(st, &err, NULL);
    if (st == WV_OK) {
      wv_scene3d_opts o = {.spp = 1, .threads = 1};
      wv_image img = {0};
      st = wv_scene3d_render(&s, w, &o, &img, NULL, NULL, &err);
      fuzz_check_refusal(st, &err, NULL);
      wv_image_free(&img);
    }
    wv_world_free(w);
  }
  wv_scene3d_free(&s);
  return 0;
}
