/* A fabric on a mesh scene in one call (wv_scene3d_render_file): what the capture's
 * report uses to show a fit on the bundled draped cloth. Reads the scene, replaces
 * every fabric's parameters, renders at the size and spp asked, frees the rest. */
#include "woven/scene3d.h"

wv_status wv_scene3d_render_file(const char *scene_path, const wv_params *params, const wv_scene3d_preview *o,
                                 wv_image *capture, wv_error *err) {
  wv_scene3d s;
  wv_status st = wv_scene3d_read(scene_path, &s, err);
  if (st) return st;
  if (o->width > 0 && o->height > 0) s.width = s.response.width = o->width, s.height = s.response.height = o->height;
  wv_world *w = NULL;
  st = wv_world_load(&s, params, o->threads, &w, err);
  if (!st) {
    wv_scene3d_opts ro = {.spp = o->spp, .threads = o->threads};
    st = wv_scene3d_render(&s, w, &ro, capture, NULL, NULL, err);
  }
  wv_world_free(w);
  wv_scene3d_free(&s);
  return st;
}
