/* woven: tileable texture maps of one weave repeat, and their directory on disk. */
#include "woven/maps.h"

#include <errno.h>
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "util/colour.h"
#include "util/hash.h"
#include "woven/io.h"
#include "woven/yarn.h"

void wv_maps_free(wv_maps *m) {
  wv_image *all[] = {&m->normal,    &m->tangent,   &m->yarn_id,      &m->height, &m->diffuse,
                     &m->specular,  &m->roughness, &m->transmission, &m->open};
  for (size_t i = 0; i < sizeof all / sizeof all[0]; i++) wv_image_free(all[i]);
}

void wv_maps_transmission_at(const wv_params *p, const wv_yarn_point *yp, float out[3]) {
  float tr = WV_CLOTH_TRANSMITTANCE((float)p->thickness * yp->thickness);
  for (int c = 0; c < 3; c++) { /* the forward band carries k_f at normal incidence (docs/model.md) */
    float k = yp->through < 0 ? 0.0f : (float)(p->transmission[yp->through][c] + p->transmission_forward[yp->through][c]);
    out[c] = k * tr < 1.0f ? k * tr : 1.0f;
  }
}

wv_status wv_maps_generate(const wv_params *p, int size, wv_maps *m, wv_error *err) {
  memset(m, 0, sizeof *m);
  if (size < 1 || size > 8192) return wv_fail(err, WV_ERR_INVALID, "map size %d is outside 1..8192", size);
  wv_status st = wv_params_validate(p, err);
  if (st) return st;
  wv_yarn_model ym;
  if ((st = wv_params_yarn_model(p, &ym, err))) return st;
  ym.period_rows = ym.weave.rows;
  ym.period_cols = ym.weave.cols;
  wv_image *all[] = {&m->normal,    &m->tangent,   &m->yarn_id,      &m->height, &m->diffuse,
                     &m->specular,  &m->roughness, &m->transmission, &m->open};
  for (size_t i = 0; i < sizeof all / sizeof all[0]; i++)
    if ((st = wv_image_alloc(all[i], size, size, 3, err))) {
      wv_maps_free(m);
      return st;
    }
  double tw = ym.weave.cols * (double)ym.spacing[WV_WARP], th = ym.weave.rows * (double)ym.spacing[WV_WEFT];
  m->tile_mm[0] = tw, m->tile_mm[1] = th;
  double hmax = 0;
#pragma omp parallel for reduction(max : hmax) schedule(static)
  for (int py = 0; py < size; py++)
    for (int px = 0; px < size; px++) {
      /* Pixel centres; image row 0 is the top of the tile (fabric y = 0 going down). */
      float x = (float)((px + 0.5) / size * tw), y = (float)(-(py + 0.5) / size * th);
      wv_yarn_point yp;
      wv_yarn_eval(&ym, x, y, &yp);
      float *n = wv_image_px(&m->normal, px, py), *t = wv_image_px(&m->tangent, px, py);
      float *id = wv_image_px(&m->yarn_id, px, py), *h = wv_image_px(&m->height, px, py);
      float *kd = wv_image_px(&m->diffuse, px, py), *ks = wv_image_px(&m->specular, px, py);
      float *a = wv_image_px(&m->roughness, px, py);
      float *kt = wv_image_px(&m->transmission, px, py), *op = wv_image_px(&m->open, px, py);
      for (int c = 0; c < 3; c++) n[c] = yp.n[c], t[c] = yp.t[c], h[c] = yp.height;
      if (yp.height > hmax) hmax = yp.height;
      wv_maps_transmission_at(p, &yp, kt);
      int ty = yp.type;
      id[0] = ty == WV_WARP, id[1] = ty == WV_WEFT, id[2] = ty < 0 ? 0.0f : wv_u01(yp.segment);
      for (int c = 0; c < 3; c++) {
        /* beside a yarn the crossing yarn underneath shows its diffuse colour; an open gap none */
        kd[c] = ty >= 0 ? (float)p->diffuse[ty][c] : yp.through >= 0 ? (float)p->diffuse[yp.through][c] : 0.0f;
        ks[c] = ty < 0 ? 0.0f : (float)p->specular[ty][c];
        a[c] = ty < 0 ? 1.0f : (float)p->roughness[ty];
        op[c] = (float)yp.open;
      }
    }
  m->height_max = hmax;
  return WV_OK;
}

/* The 8-bit form of a map: how each kind is encoded into [0,1]. */
static wv_status write_png_map(const char *path, const wv_image *src, int kind, double hmax, wv_error *err) {
  wv_image tmp;
  wv_status st = wv_image_alloc(&tmp, src->w, src->h, 3, err);
  if (st) return st;
  size_t n = (size_t)src->w * src->h * 3;
  for (size_t i = 0; i < n; i++) {
    float v = src->data[i];
    switch (kind) {
      case 0: v = 0.5f * v + 0.5f; break;                        /* vectors */
      case 1: v = wv_srgb_encode_f(v); break;                     /* albedo */
      case 2: v = hmax > 0 ? (float)(v / hmax) : 0.0f; break;     /* height */
      default: break;                                             /* ids, roughness */
    }
    tmp.data[i] = v;
  }
  st = wv_image_write_png(path, &tmp, 8, err);
  wv_image_free(&tmp);
  return st;
}

/* What a maps directory holds: an existing directory with anything else is not replaced. */
static const char *const MAP_FILES[] = {"normal.png",    "normal.exr",  "tangent.png",  "tangent.exr",
                                        "yarn_id.png",   "yarn_id.exr", "height.png",   "height.exr",
                                        "diffuse.png",   "diffuse.exr", "specular.png", "specular.exr",
                                        "roughness.png", "roughness.exr", "transmission.png", "transmission.exr",
                                        "open.png",      "open.exr",    "maps.json",    NULL};

wv_status wv_maps_write(const wv_maps *m, const char *dir, const char *format, wv_error *err) {
  int png = !strcmp(format, "png") || !strcmp(format, "both");
  int exr = !strcmp(format, "exr") || !strcmp(format, "both");
  if (!png && !exr) return wv_fail(err, WV_ERR_INVALID, "map format '%s' must be png, exr or both", format);
  struct {
    const char *name;
    const wv_image *img;
    int kind;
  } maps[] = {{"normal", &m->normal, 0},     {"tangent", &m->tangent, 0},   {"yarn_id", &m->yarn_id, 3},
              {"height", &m->height, 2},     {"diffuse", &m->diffuse, 1},   {"specular", &m->specular, 1},
              {"roughness", &m->roughness, 3}, {"transmission", &m->transmission, 1}, {"open", &m->open, 3}};
  wv_outdir od;
  wv_status st = wv_outdir_begin(&od, dir, MAP_FILES, err);
  if (st) return st;
  char path[4096];
  for (size_t i = 0; i < sizeof maps / sizeof maps[0] && !st; i++) {
    if (png) {
      snprintf(path, sizeof path, "%s/%s.png", od.tmp, maps[i].name);
      st = write_png_map(path, maps[i].img, maps[i].kind, m->height_max, err);
    }
    if (exr && !st) {
      snprintf(path, sizeof path, "%s/%s.exr", od.tmp, maps[i].name);
      st = wv_image_write_exr(path, maps[i].img, err);
    }
  }
  json_t *o = json_pack(
      "{s:i,s:i,s:[f,f],s:f,s:{s:s,s:s,s:s,s:s,s:s,s:s,s:s,s:s,s:s}}", "width", m->normal.w, "height", m->normal.h,
      "tile_mm", m->tile_mm[0], m->tile_mm[1], "height_max_mm", m->height_max, "png_encoding", "normal",
      "0.5*n+0.5, tangent space (x right along the weft, y up along the warp, z out)", "tangent",
      "0.5*t+0.5, same frame, sign arbitrary", "yarn_id", "R warp, G weft, B per-segment random", "height",
      "height / height_max_mm", "diffuse", "sRGB", "specular", "sRGB", "roughness", "SGGX alpha, linear", "transmission",
      "sRGB, k_t times the cloth's diffuse transmittance", "open", "1 in an open gap (light straight through), linear");
  char *text = json_dumps(o, JSON_INDENT(2) | JSON_PRESERVE_ORDER);
  json_decref(o);
  snprintf(path, sizeof path, "%s/maps.json", od.tmp);
  if (!st) st = text ? wv_write_file_atomic(path, text, strlen(text), err)
                     : wv_fail(err, WV_ERR_NOMEM, "%s: cannot format maps.json", dir);
  free(text);
  if (st) {
    wv_outdir_abort(&od, err);
    return st;
  }
  return wv_outdir_commit(&od, err);
}
