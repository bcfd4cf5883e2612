/* The viewer page: web/viewer/viewer.html with the fabric's data (parameters,
 * weave tables, scene, meshes, photo; JSON built with jansson), three.js
 * (gzip + base64) and the viewer's scripts and shaders inlined. */
#include "woven/view.h"

#include <jansson.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "kernel/kernel.h"
#include "util/base64.h"
#include "util/buf.h"
#include "woven/export.h"
#include "woven/io.h"
#include "woven/photo.h"

/* Generated from web/ by cmake/embed.cmake. */
#define ASSET(n) extern const unsigned char n[]; extern const size_t n##_len;
ASSET(wv_asset_three_core)
ASSET(wv_asset_three_module)
ASSET(wv_asset_three_orbit)
ASSET(wv_asset_viewer_html)
ASSET(wv_asset_viewer_js)
ASSET(wv_asset_fabric_vert)
ASSET(wv_asset_fabric_frag)
ASSET(wv_asset_screen_vert)
ASSET(wv_asset_accumulate_frag)
ASSET(wv_asset_display_frag)

/* Base64 of a number array (the viewer reads it as a typed array). */
static json_t *b64_array(const void *data, size_t bytes) {
  char *s = wv_base64(data, bytes);
  json_t *j = s ? json_string(s) : NULL;
  free(s);
  return j;
}

static json_t *mesh_json(const wv_tri_mesh *m) {
  return json_pack("{s:o*,s:o*,s:o*,s:o*,s:o*,s:f}", "positions", b64_array(m->positions, sizeof(float) * 3 * m->vertex_count),
                   "normals", b64_array(m->normals, sizeof(float) * 3 * m->vertex_count), "tangents",
                   b64_array(m->tangents, sizeof(float) * 4 * m->vertex_count), "uvs",
                   b64_array(m->uvs, sizeof(float) * 2 * m->vertex_count), "indices",
                   b64_array(m->indices, sizeof(uint32_t) * m->index_count), "uv_mm", m->uv_mm);
}

/* The segment table of a weave as the shader reads it: type | len << 8 | index << 16. */
static json_t *weave_json(const wv_weave *w) {
  json_t *cells = json_array();
  for (int r = 0; r < w->rows; r++)
    for (int c = 0; c < w->cols; c++) {
      const wv_weave_cell *ce = &w->cell[r][c];
      json_array_append_new(cells, json_integer(ce->type | ce->len << 8 | ce->index << 16));
    }
  return json_pack("{s:i,s:i,s:o}", "rows", w->rows, "cols", w->cols, "cells", cells);
}

static json_t *ranges_json(void) {
  json_t *a = json_array();
  static const char *yn[2] = {"density.warp", "density.weft"};
  for (int y = 0; y < 2; y++)
    json_array_append_new(a, json_pack("{s:s,s:f,s:f}", "key", yn[y], "lo", WV_DENSITY_MIN, "hi", WV_DENSITY_MAX));
  for (int id = 0; id < WV_P_COUNT; id++) {
    double lo, hi;
    wv_param_range(id, &lo, &hi);
    json_array_append_new(a, json_pack("{s:s,s:f,s:f}", "key", wv_param_name(id), "lo", lo, "hi", hi));
  }
  json_array_append_new(a, json_pack("{s:s,s:i,s:i}", "key", "noise_level", "lo", 0, "hi", 10));
  return a;
}

/* The forward band's mean (wv_forward_band_mean, whose inverse normalises the band) at 96
 * widths over forward_width's range (lo, hi: the viewer's bounds of the width), 0.01 apart:
 * the viewer interpolates it as its width changes (viewer.js forwardNorm), so the mean keeps
 * its one formula, in C. Linear in the mean, not its inverse: near linear in the width,
 * within 0.03% between the nodes. */
static json_t *forward_mean_json(void) {
  enum { N = 96 };
  double lo, hi;
  wv_param_range_forward_width(&lo, &hi);
  json_t *v = json_array();
  for (int i = 0; i < N; i++) json_array_append_new(v, json_real(wv_forward_band_mean(lo + (hi - lo) * i / (N - 1))));
  return json_pack("{s:f,s:f,s:o}", "lo", lo, "hi", hi, "values", v);
}

static wv_status build_data(const wv_view_opts *o, char **out, wv_error *err) {
  *out = NULL;
  const wv_params *p = o->params;
  wv_status st = wv_params_validate(p, err);
  if (st) return st;
  if ((st = wv_scene_validate(o->scene, err))) return st;
  json_t *root = json_object();
  char *pj = wv_params_to_json(p), *sj = wv_scene_to_json(o->scene);
  json_object_set_new(root, "params", pj ? json_loads(pj, 0, NULL) : json_null());
  json_object_set_new(root, "scene", sj ? json_loads(sj, 0, NULL) : json_null());
  free(pj), free(sj);
  { /* the back light's placement and gap glow in the rig (viewer.js rigLights) */
    wv_scene back;
    char *bj = NULL;
    if (!(st = wv_scene_preset("flat45-back", &back, err)) && !(bj = wv_scene_to_json(&back)))
      st = wv_fail(err, WV_ERR_NOMEM, "out of memory for the viewer's data");
    json_object_set_new(root, "back_scene", bj ? json_loads(bj, 0, NULL) : json_null());
    free(bj);
  }
  uint64_t seed = (uint64_t)p->seed; /* exact, beyond JavaScript's 2^53 */
  json_object_set_new(root, "seed_words", json_pack("[I,I]", (json_int_t)(seed >> 32), (json_int_t)(seed & 0xffffffffu)));
  json_object_set_new(root, "ranges", ranges_json());
  json_object_set_new(root, "forward_band_mean", forward_mean_json());
  json_t *weaves = json_object();
  static const char *builtin[] = {"plain", "twill", "satin", "twill90", "satin90"};
  for (size_t i = 0; i < sizeof builtin / sizeof builtin[0] && !st; i++) {
    wv_weave w;
    if (!(st = wv_weave_builtin(builtin[i], &w, err))) json_object_set_new(weaves, builtin[i], weave_json(&w));
  }
  if (!st && !strcmp(p->pattern, "custom")) {
    wv_weave w;
    if (!(st = wv_params_weave(p, &w, err))) json_object_set_new(weaves, "custom", weave_json(&w));
  }
  json_object_set_new(root, "weaves", weaves);
  wv_tri_mesh quad = {0}, drape = {0};
  if (!st) st = wv_tri_mesh_quad(20.0, &quad, err); /* small enough that the weave shows */
  if (!st) st = wv_tri_mesh_drape(600.0, 150.0, 96, &drape, err);
  if (!st) json_object_set_new(root, "meshes", json_pack("{s:o,s:o}", "swatch", mesh_json(&quad), "drape", mesh_json(&drape)));
  wv_tri_mesh_free(&quad), wv_tri_mesh_free(&drape);
  json_t *photo = json_null();
  if (!st && o->photo) {
    wv_image img;
    unsigned char *png = NULL;
    size_t n = 0;
    if (!(st = wv_photo_load(o->photo, o->scene, NULL, &img, NULL, err))) {
      st = wv_image_encode_png(&img, &png, &n, err);
      wv_image_free(&img);
    }
    char *b = st ? NULL : wv_base64(png, n);
    free(png);
    if (!st && !b) st = wv_fail(err, WV_ERR_NOMEM, "out of memory for the photo");
    if (!st) {
      size_t bl = strlen(b);
      char *url = malloc(bl + 32);
      if (url) {
        memcpy(url, "data:image/png;base64,", 22);
        memcpy(url + 22, b, bl + 1);
        json_decref(photo);
        photo = json_string(url);
      } else {
        st = wv_fail(err, WV_ERR_NOMEM, "out of memory for the photo");
      }
      free(url);
    }
    free(b);
  }
  json_object_set_new(root, "photo", photo);
  char title[256];
  snprintf(title, sizeof title, "%s", o->title ? o->title : "woven viewer");
  json_object_set_new(root, "title", json_string(title));
  /* Escaped slashes: no "</script>" can appear inside the page's data block. */
  *out = st ? NULL : json_dumps(root, JSON_COMPACT | JSON_ESCAPE_SLASH | JSON_REAL_PRECISION(17));
  json_decref(root);
  if (!st && !*out) st = wv_fail(err, WV_ERR_NOMEM, "out of memory for the viewer's data");
  return st;
}

/* A text asset inside a <script> element: it must not close the element early. */
static int script_safe(const unsigned char *s, size_t n) {
  for (size_t i = 0; i + 8 <= n; i++)
    if (s[i] == '<' && s[i + 1] == '/' && !strncasecmp((const char *)s + i + 2, "script", 6)) return 0;
  return 1;
}

static void script(wv_buf *t, const char *id, const char *type, const unsigned char *data, size_t n, int gz,
                   int *unsafe) {
  wv_buf_puts(t, "<script id=\"");
  wv_buf_puts(t, id);
  wv_buf_puts(t, "\" type=\"");
  wv_buf_puts(t, type);
  wv_buf_puts(t, "\">");
  if (gz) { /* base64 text of the gzip stream: safe by construction */
    char *b = wv_base64(data, n);
    if (b) wv_buf_puts(t, b);
    else t->failed = 1;
    free(b);
  } else {
    if (!script_safe(data, n)) *unsafe = 1;
    wv_buf_put(t, data, n);
  }
  wv_buf_puts(t, "</script>\n");
}

wv_status wv_view_write(const char *path, const wv_view_opts *o, wv_error *err) {
  char *data;
  wv_status st = build_data(o, &data, err);
  if (st) return st;
  const char *html = (const char *)wv_asset_viewer_html, *mark = strstr(html, "<!-- woven:inline -->");
  if (!mark) {
    free(data);
    return wv_fail(err, WV_ERR_INTERNAL, "the viewer template has no inline marker");
  }
  wv_buf t = {0};
  int unsafe = 0;
  wv_buf_put(&t, html, (size_t)(mark - html));
  wv_buf_puts(&t, "<script id=\"woven-data\" type=\"application/json\">");
  wv_buf_puts(&t, data);
  wv_buf_puts(&t, "</script>\n");
  free(data);
  script(&t, "woven-three-core", "text/plain", wv_asset_three_core, wv_asset_three_core_len, 1, &unsafe);
  script(&t, "woven-three-module", "text/plain", wv_asset_three_module, wv_asset_three_module_len, 1, &unsafe);
  script(&t, "woven-three-orbit", "text/plain", wv_asset_three_orbit, wv_asset_three_orbit_len, 1, &unsafe);
  script(&t, "woven-fabric-vert", "x-shader/x-vertex", wv_asset_fabric_vert, wv_asset_fabric_vert_len, 0, &unsafe);
  script(&t, "woven-fabric-frag", "x-shader/x-fragment", wv_asset_fabric_frag, wv_asset_fabric_frag_len, 0, &unsafe);
  script(&t, "woven-screen-vert", "x-shader/x-vertex", wv_asset_screen_vert, wv_asset_screen_vert_len, 0, &unsafe);
  script(&t, "woven-accumulate-frag", "x-shader/x-fragment", wv_asset_accumulate_frag, wv_asset_accumulate_frag_len, 0,
         &unsafe);
  script(&t, "woven-display-frag", "x-shader/x-fragment", wv_asset_display_frag, wv_asset_display_frag_len, 0, &unsafe);
  script(&t, "woven-viewer", "module", wv_asset_viewer_js, wv_asset_viewer_js_len, 0, &unsafe);
  wv_buf_puts(&t, mark + strlen("<!-- woven:inline -->"));
  if (unsafe) st = wv_fail(err, WV_ERR_INTERNAL, "a viewer script contains </script>");
  else if (t.failed) st = wv_fail(err, WV_ERR_NOMEM, "%s: out of memory writing the viewer", path);
  else st = wv_write_file_atomic(path, t.data, t.len, err);
  free(t.data);
  return st;
}
