/* The mesh renderer's scene file: JSON text -> wv_scene3d (woven/scene3d.h).
 * Parsing reads no file (wv_scene3d_parse is what a fuzzer calls); every key is
 * checked, unknown keys are refused with their path in the file, numbers are
 * range-checked, and file names are resolved against the scene's directory. */
#include "woven/scene3d.h"

#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "woven/emitters.h"
#include "woven/io.h"
#include "woven/mesh.h"
#include "scene/scene_json.h"
#include "io/json_file.h"
#include "util/json.h"

#define BIG 1e7 /* coordinates in mm: 10 km */
#define REQ WV_JSON_REQUIRED
#define RGB (WV_JSON_REQUIRED | WV_JSON_ONE_FOR_ALL) /* a colour: three numbers or one grey */

typedef struct {
  const char *base;
  wv_error *err;
} ctx;

/* base/rel, or rel when absolute or without a base (malloc'ed). */
static char *resolve(const char *base, const char *rel) {
  size_t nb = base && rel[0] != '/' ? strlen(base) : 0, nr = strlen(rel);
  char *p = malloc(nb + nr + 2);
  if (!p) return NULL;
  if (nb) snprintf(p, nb + nr + 2, "%s/%s", base, rel);
  else memcpy(p, rel, nr + 1);
  return p;
}

static wv_status path_of(json_t *o, const char *where, const char *key, const ctx *c, char **out) {
  const char *rel = NULL;
  wv_status st = wv_json_string(o, where, key, REQ | WV_JSON_NONEMPTY, &rel, c->err);
  if (st) return st;
  if (!(*out = resolve(c->base, rel))) return wv_fail(c->err, WV_ERR_NOMEM, "out of memory");
  return WV_OK;
}

static double norm3(double v[3]) {
  double l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  if (l > 0) v[0] /= l, v[1] /= l, v[2] /= l;
  return l;
}

static wv_status parse_camera(json_t *r, wv_scene3d *s, wv_error *err) {
  static const char *const k[] = {"position_mm", "look_at_mm", "up", "vfov_deg", NULL};
  wv_status st;
  json_t *o;
  s->cam_up[1] = 1;
  if ((st = wv_json_object(r, NULL, "camera", k, REQ, &o, err)) ||
      (st = wv_json_numbers(o, "camera", "position_mm", 3, -BIG, BIG, REQ, s->cam_pos, err)) ||
      (st = wv_json_numbers(o, "camera", "look_at_mm", 3, -BIG, BIG, REQ, s->cam_look_at, err)) ||
      (st = wv_json_numbers(o, "camera", "up", 3, -BIG, BIG, 0, s->cam_up, err)) ||
      (st = wv_json_number(o, "camera", "vfov_deg", 0.01, 179, REQ, &s->vfov_deg, err)))
    return st;
  double f[3], u[3] = {s->cam_up[0], s->cam_up[1], s->cam_up[2]}, x[3];
  for (int i = 0; i < 3; i++) f[i] = s->cam_look_at[i] - s->cam_pos[i];
  if (norm3(f) < 1e-9) return wv_fail(err, WV_ERR_INVALID, "'camera.look_at_mm' equals 'camera.position_mm'");
  x[0] = f[1] * u[2] - f[2] * u[1], x[1] = f[2] * u[0] - f[0] * u[2], x[2] = f[0] * u[1] - f[1] * u[0];
  if (norm3(x) < 1e-9 * (norm3(u) + 1e-300)) return wv_fail(err, WV_ERR_INVALID, "'camera.up' is parallel to the view direction");
  return WV_OK;
}

static wv_status parse_env(json_t *r, const ctx *c, wv_scene3d *s) {
  static const char *const k[] = {"builtin", "file", "uniform", "strength", "rotation_deg", "width", "visible", NULL};
  wv_error *err = c->err;
  wv_status st;
  json_t *o;
  s->env_strength = 1, s->env_width = 512, s->env_visible = 1;
  if ((st = wv_json_object(r, NULL, "environment", k, 0, &o, err)) || !o) return st;
  int kinds = !!json_object_get(o, "builtin") + !!json_object_get(o, "file") + !!json_object_get(o, "uniform");
  if (kinds != 1)
    return wv_fail(err, WV_ERR_INVALID, "'environment' needs exactly one of 'builtin', 'file' or 'uniform'");
  if (json_object_get(o, "builtin")) {
    const char *n = NULL;
    if ((st = wv_json_string(o, "environment", "builtin", REQ | WV_JSON_NONEMPTY, &n, err))) return st;
    if (!wv_env_is_builtin(n))
      return wv_fail(err, WV_ERR_INVALID, "'environment.builtin' = '%s': expected studio, sky or white", n);
    s->env = WV_ENV_BUILTIN;
    snprintf(s->env_name, sizeof s->env_name, "%s", n);
  } else if (json_object_get(o, "file")) {
    s->env = WV_ENV_FILE;
    if ((st = path_of(o, "environment", "file", c, &s->env_path))) return st;
  } else {
    s->env = WV_ENV_UNIFORM;
    if ((st = wv_json_numbers(o, "environment", "uniform", 3, 0, 1e6, RGB, s->env_color, err))) return st;
  }
  if ((st = wv_json_bool(o, "environment", "visible", 0, &s->env_visible, err)) ||
      (st = wv_json_number(o, "environment", "strength", 0, 1e6, 0, &s->env_strength, err)) ||
      (st = wv_json_number(o, "environment", "rotation_deg", -3600, 3600, 0, &s->env_rotation_deg, err)) ||
      (st = wv_json_int(o, "environment", "width", 16, 8192, 0, &s->env_width, err)))
    return st;
  return WV_OK;
}

static wv_status parse_light(json_t *o, const char *where, wv_light3d *l, wv_error *err) {
  static const char *const kp[] = {"type", "position_mm", "intensity", NULL};
  static const char *const ks[] = {"type", "position_mm", "look_at_mm", "intensity", "cone_deg", "blend_deg", NULL};
  static const char *const kd[] = {"type", "direction", "irradiance", NULL};
  static const char *const ka[] = {"type", "position_mm", "look_at_mm", "size_mm", "radiance", NULL};
  static const wv_json_enum types[] = {{"point", WV_LIGHT_POINT},
                                       {"spot", WV_LIGHT_SPOT},
                                       {"directional", WV_LIGHT_DIRECTIONAL},
                                       {"area", WV_LIGHT_AREA},
                                       {0}};
  int type = 0;
  wv_status st;
  if (!json_is_object(o)) return wv_fail(err, WV_ERR_INVALID, "'%s' must be an object", where);
  if ((st = wv_json_enum_of(o, where, "type", types, REQ, &type, err))) return st;
  l->type = (wv_light_type)type;
  double at[3];
  if (l->type == WV_LIGHT_POINT) {
    if ((st = wv_json_only_keys(o, where, kp, err)) ||
        (st = wv_json_numbers(o, where, "position_mm", 3, -BIG, BIG, REQ, l->pos, err)) ||
        (st = wv_json_numbers(o, where, "intensity", 3, 0, 1e12, RGB, l->color, err)))
      return st;
  } else if (l->type == WV_LIGHT_SPOT) {
    l->cone_deg = 30, l->blend_deg = 5;
    if ((st = wv_json_only_keys(o, where, ks, err)) ||
        (st = wv_json_numbers(o, where, "position_mm", 3, -BIG, BIG, REQ, l->pos, err)) ||
        (st = wv_json_numbers(o, where, "look_at_mm", 3, -BIG, BIG, REQ, at, err)) ||
        (st = wv_json_numbers(o, where, "intensity", 3, 0, 1e12, RGB, l->color, err)) ||
        (st = wv_json_number(o, where, "cone_deg", 0.1, 89.9, 0, &l->cone_deg, err)) ||
        (st = wv_json_number(o, where, "blend_deg", 0, 89.9, 0, &l->blend_deg, err)))
      return st;
    if (l->blend_deg > l->cone_deg) l->blend_deg = l->cone_deg;
  } else if (l->type == WV_LIGHT_DIRECTIONAL) {
    if ((st = wv_json_only_keys(o, where, kd, err)) ||
        (st = wv_json_numbers(o, where, "direction", 3, -BIG, BIG, REQ, l->dir, err)) ||
        (st = wv_json_numbers(o, where, "irradiance", 3, 0, 1e9, RGB, l->color, err)))
      return st;
    if (norm3(l->dir) < 1e-12) return wv_fail(err, WV_ERR_INVALID, "'%s.direction' is zero", where);
  } else {
    if ((st = wv_json_only_keys(o, where, ka, err)) ||
        (st = wv_json_numbers(o, where, "position_mm", 3, -BIG, BIG, REQ, l->pos, err)) ||
        (st = wv_json_numbers(o, where, "look_at_mm", 3, -BIG, BIG, REQ, at, err)) ||
        (st = wv_json_numbers(o, where, "size_mm", 2, 1e-3, 1e6, REQ, l->size, err)) ||
        (st = wv_json_numbers(o, where, "radiance", 3, 0, 1e9, RGB, l->color, err)))
      return st;
  }
  if (l->type == WV_LIGHT_SPOT || l->type == WV_LIGHT_AREA) {
    for (int i = 0; i < 3; i++) l->dir[i] = at[i] - l->pos[i];
    if (norm3(l->dir) < 1e-9) return wv_fail(err, WV_ERR_INVALID, "'%s.look_at_mm' equals its position", where);
  }
  return WV_OK;
}

static int find_material(const wv_scene3d *s, const char *name) {
  for (int i = 0; i < s->nmaterials; i++)
    if (!strcmp(s->materials[i].name, name)) return i;
  return -1;
}

static wv_status parse_material(json_t *o, const char *name, const ctx *c, wv_material3d *m) {
  static const char *const kf[] = {"fabric", "uv_mm", "uv_offset_mm", NULL};
  static const char *const kl[] = {"lambert", NULL};
  char where[96];
  snprintf(where, sizeof where, "materials.%s", name);
  wv_error *err = c->err;
  wv_status st;
  if (strlen(name) >= sizeof m->name || !name[0])
    return wv_fail(err, WV_ERR_INVALID, "material name '%.40s...' is empty or longer than 63 characters", name);
  snprintf(m->name, sizeof m->name, "%s", name);
  if (!json_is_object(o)) return wv_fail(err, WV_ERR_INVALID, "'%s' must be an object", where);
  if (json_object_get(o, "fabric")) {
    m->kind = WV_MAT_FABRIC;
    m->uv_mm[0] = m->uv_mm[1] = 1;
    if ((st = wv_json_only_keys(o, where, kf, err)) || (st = path_of(o, where, "fabric", c, &m->params_path)) ||
        (st = wv_json_numbers(o, where, "uv_mm", 2, 1e-6, 1e7, WV_JSON_ONE_FOR_ALL, m->uv_mm, err)) ||
        (st = wv_json_numbers(o, where, "uv_offset_mm", 2, -BIG, BIG, 0, m->uv_offset_mm, err)))
      return st;
  } else if (json_object_get(o, "lambert")) {
    m->kind = WV_MAT_LAMBERT;
    if ((st = wv_json_only_keys(o, where, kl, err)) ||
        (st = wv_json_numbers(o, where, "lambert", 3, 0, 1, RGB, m->albedo, err)))
      return st;
  } else {
    return wv_fail(err, WV_ERR_INVALID, "'%s' needs 'fabric' (a parameter file) or 'lambert' (a colour)", where);
  }
  return WV_OK;
}

/* transform: scale (number or 3), rotate_deg (x, then y, then z), translate_mm. */
static wv_status parse_transform(json_t *o, const char *where, wv_object3d *ob, wv_error *err) {
  static const char *const k[] = {"scale", "rotate_deg", "translate_mm", NULL};
  double sc[3] = {1, 1, 1}, r[3] = {0, 0, 0};
  wv_status st;
  memset(ob->A, 0, sizeof ob->A);
  ob->A[0] = ob->A[4] = ob->A[8] = 1;
  memset(ob->b, 0, sizeof ob->b);
  if (!o) return WV_OK;
  if ((st = wv_json_only_keys(o, where, k, err)) ||
      (st = wv_json_numbers(o, where, "scale", 3, -1e6, 1e6, WV_JSON_ONE_FOR_ALL, sc, err)) ||
      (st = wv_json_numbers(o, where, "rotate_deg", 3, -3600, 3600, 0, r, err)) ||
      (st = wv_json_numbers(o, where, "translate_mm", 3, -BIG, BIG, 0, ob->b, err)))
    return st;
  if (!(fabs(sc[0] * sc[1] * sc[2]) > 1e-12)) return wv_fail(err, WV_ERR_INVALID, "'%s.scale' must not be zero", where);
  double M[9] = {sc[0], 0, 0, 0, sc[1], 0, 0, 0, sc[2]};
  for (int ax = 0; ax < 3; ax++) { /* M = R_ax M */
    double a = r[ax] * 3.14159265358979323846 / 180, cs = cos(a), sn = sin(a), R[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    int p = (ax + 1) % 3, q = (ax + 2) % 3;
    R[3 * p + p] = cs, R[3 * p + q] = -sn, R[3 * q + p] = sn, R[3 * q + q] = cs;
    double T[9];
    for (int i = 0; i < 3; i++)
      for (int j = 0; j < 3; j++) T[3 * i + j] = R[3 * i] * M[j] + R[3 * i + 1] * M[3 + j] + R[3 * i + 2] * M[6 + j];
    memcpy(M, T, sizeof M);
  }
  memcpy(ob->A, M, sizeof M);
  return WV_OK;
}

static wv_status parse_object(json_t *o, const char *where, const ctx *c, wv_scene3d *s, wv_object3d *ob) {
  static const char *const k[] = {"mesh", "quad", "sphere", "cylinder", "material", "transform", NULL};
  static const char *const kq[] = {"centre_mm", "u_axis", "v_axis", "size_mm", "cells", NULL};
  static const char *const ksph[] = {"centre_mm", "radius_mm", "segments", NULL};
  static const char *const kc[] = {"centre_mm", "radius_mm", "length_mm", "segments", NULL};
  wv_error *err = c->err;
  wv_status st;
  if ((st = wv_json_only_keys(o, where, k, err))) return st;
  int kinds = !!json_object_get(o, "mesh") + !!json_object_get(o, "quad") + !!json_object_get(o, "sphere") +
              !!json_object_get(o, "cylinder");
  if (kinds != 1) return wv_fail(err, WV_ERR_INVALID, "'%s' needs exactly one of mesh, quad, sphere, cylinder", where);
  const char *mat = NULL;
  if ((st = wv_json_string(o, where, "material", REQ | WV_JSON_NONEMPTY, &mat, err))) return st;
  if ((ob->material = find_material(s, mat)) < 0)
    return wv_fail(err, WV_ERR_INVALID, "'%s.material': no material named '%s'", where, mat);
  char sub[96];
  json_t *g;
  if (json_object_get(o, "mesh")) {
    ob->kind = WV_OBJ_MESH;
    if ((st = path_of(o, where, "mesh", c, &ob->path))) return st;
  } else if ((g = json_object_get(o, "quad"))) {
    ob->kind = WV_OBJ_QUAD;
    snprintf(sub, sizeof sub, "%s.quad", where);
    ob->eu[0] = 1, ob->ev[1] = 1, ob->resolution = 1;
    if ((st = wv_json_only_keys(g, sub, kq, err)) ||
        (st = wv_json_numbers(g, sub, "centre_mm", 3, -BIG, BIG, REQ, ob->centre, err)) ||
        (st = wv_json_numbers(g, sub, "u_axis", 3, -BIG, BIG, 0, ob->eu, err)) ||
        (st = wv_json_numbers(g, sub, "v_axis", 3, -BIG, BIG, 0, ob->ev, err)) ||
        (st = wv_json_numbers(g, sub, "size_mm", 2, 1e-6, BIG, REQ, ob->size, err)) ||
        (st = wv_json_int(g, sub, "cells", 1, 1024, 0, &ob->resolution, err)))
      return st;
  } else if ((g = json_object_get(o, "sphere"))) {
    ob->kind = WV_OBJ_SPHERE;
    snprintf(sub, sizeof sub, "%s.sphere", where);
    ob->resolution = 96;
    if ((st = wv_json_only_keys(g, sub, ksph, err)) ||
        (st = wv_json_numbers(g, sub, "centre_mm", 3, -BIG, BIG, REQ, ob->centre, err)) ||
        (st = wv_json_number(g, sub, "radius_mm", 1e-6, BIG, REQ, &ob->radius, err)) ||
        (st = wv_json_int(g, sub, "segments", 3, 4096, 0, &ob->resolution, err)))
      return st;
  } else {
    g = json_object_get(o, "cylinder");
    ob->kind = WV_OBJ_CYLINDER;
    snprintf(sub, sizeof sub, "%s.cylinder", where);
    ob->resolution = 1024;
    if ((st = wv_json_only_keys(g, sub, kc, err)) ||
        (st = wv_json_numbers(g, sub, "centre_mm", 3, -BIG, BIG, REQ, ob->centre, err)) ||
        (st = wv_json_number(g, sub, "radius_mm", 1e-6, BIG, REQ, &ob->radius, err)) ||
        (st = wv_json_number(g, sub, "length_mm", 1e-6, BIG, REQ, &ob->length, err)) ||
        (st = wv_json_int(g, sub, "segments", 3, 8192, 0, &ob->resolution, err)))
      return st;
  }
  snprintf(sub, sizeof sub, "%s.transform", where);
  return parse_transform(json_object_get(o, "transform"), sub, ob, err);
}

static wv_status parse_edit(json_t *o, const char *where, const ctx *c, wv_scene3d *s, wv_edit3d *e) {
  static const char *const k[] = {"material", "apply", "map", "mask", "gain", NULL};
  static const wv_json_enum ops[] = {{"diffuse_multiply", WV_EDIT_DIFFUSE_MULTIPLY},
                                     {"diffuse_replace", WV_EDIT_DIFFUSE_REPLACE},
                                     {"heightfield", WV_EDIT_HEIGHTFIELD},
                                     {"roughness", WV_EDIT_ROUGHNESS},
                                     {0}};
  wv_error *err = c->err;
  const char *mat = NULL;
  int op = 0;
  wv_status st;
  if ((st = wv_json_only_keys(o, where, k, err)) ||
      (st = wv_json_string(o, where, "material", REQ | WV_JSON_NONEMPTY, &mat, err)) ||
      (st = wv_json_enum_of(o, where, "apply", ops, REQ, &op, err)))
    return st;
  e->op = (wv_edit_op)op;
  e->material = find_material(s, mat);
  if (e->material < 0) return wv_fail(err, WV_ERR_INVALID, "'%s.material': no material named '%s'", where, mat);
  if (s->materials[e->material].kind != WV_MAT_FABRIC)
    return wv_fail(err, WV_ERR_INVALID, "'%s.material': '%s' is not a fabric", where, mat);
  e->gain = 1;
  if ((st = path_of(o, where, "map", c, &e->map)) || (st = wv_json_number(o, where, "gain", 0, 1e3, 0, &e->gain, err)))
    return st;
  if (json_object_get(o, "mask") && (st = path_of(o, where, "mask", c, &e->mask))) return st;
  return WV_OK;
}

/* An array of at most WV_SCENE3D_MAX_ITEMS entries, allocated as n items of size sz. */
static wv_status array_of(json_t *a, const char *where, size_t sz, void **items, int *n, wv_error *err) {
  *n = 0;
  if (!a) return WV_OK;
  if (!json_is_array(a)) return wv_fail(err, WV_ERR_INVALID, "'%s' must be an array", where);
  size_t k = json_array_size(a);
  if (k > WV_SCENE3D_MAX_ITEMS)
    return wv_fail(err, WV_ERR_INVALID, "'%s' has %zu entries (at most %d)", where, k, WV_SCENE3D_MAX_ITEMS);
  if (k && !(*items = calloc(k, sz))) return wv_fail(err, WV_ERR_NOMEM, "out of memory");
  *n = (int)k;
  return WV_OK;
}

static wv_status parse_root(json_t *r, const ctx *c, wv_scene3d *s) {
  static const char *const top[] = {"name",  "comment", "image",  "camera",   "environment", "lights", "materials",
                                    "objects", "edits", "render", "response", "falloff",     "limits", NULL};
  static const char *const ki[] = {"width", "height", "spp", NULL};
  static const char *const kr[] = {"max_bounces", "yarn_samples", "seed", "transmission", NULL};
  static const char *const kl[] = {"mesh_mb", NULL};
  wv_error *err = c->err;
  wv_status st;
  const char *nm = "scene";
  json_t *o;
  if ((st = wv_json_only_keys(r, "", top, err)) || (st = wv_json_string(r, NULL, "name", WV_JSON_NONEMPTY, &nm, err)))
    return st;
  snprintf(s->name, sizeof s->name, "%s", nm);
  s->spp = WV_SCENE3D_DEFAULT_SPP;
  if ((st = wv_json_object(r, NULL, "image", ki, REQ, &o, err)) ||
      (st = wv_json_int(o, "image", "width", 1, WV_SCENE_MAX_SIDE, REQ, &s->width, err)) ||
      (st = wv_json_int(o, "image", "height", 1, WV_SCENE_MAX_SIDE, REQ, &s->height, err)) ||
      (st = wv_json_int(o, "image", "spp", 1, WV_SCENE_MAX_SPP, 0, &s->spp, err)))
    return st;
  if ((st = parse_camera(r, s, err))) return st;
  if ((st = parse_env(r, c, s))) return st;

  json_t *a = json_object_get(r, "lights");
  if ((st = array_of(a, "lights", sizeof *s->lights, (void **)&s->lights, &s->nlights, err))) return st;
  for (int i = 0; i < s->nlights; i++) {
    char w[32];
    snprintf(w, sizeof w, "lights[%d]", i);
    if ((st = parse_light(json_array_get(a, (size_t)i), w, &s->lights[i], err))) return st;
  }
  o = json_object_get(r, "materials");
  if (!o || !json_is_object(o) || !json_object_size(o))
    return wv_fail(err, WV_ERR_INVALID, "'materials' must be an object with at least one material");
  if (json_object_size(o) > WV_SCENE3D_MAX_ITEMS)
    return wv_fail(err, WV_ERR_INVALID, "'materials' has more than %d entries", WV_SCENE3D_MAX_ITEMS);
  if (!(s->materials = calloc(json_object_size(o), sizeof *s->materials)))
    return wv_fail(err, WV_ERR_NOMEM, "out of memory");
  const char *key;
  json_t *val;
  json_object_foreach(o, key, val) {
    st = parse_material(val, key, c, &s->materials[s->nmaterials]);
    s->nmaterials++; /* counted even when refused: wv_scene3d_free frees what it holds */
    if (st) return st;
  }
  a = json_object_get(r, "objects");
  if ((st = array_of(a, "objects", sizeof *s->objects, (void **)&s->objects, &s->nobjects, err))) return st;
  if (!s->nobjects) return wv_fail(err, WV_ERR_INVALID, "'objects' must list at least one object");
  for (int i = 0; i < s->nobjects; i++) {
    char w[32];
    snprintf(w, sizeof w, "objects[%d]", i);
    if ((st = parse_object(json_array_get(a, (size_t)i), w, c, s, &s->objects[i]))) return st;
  }
  a = json_object_get(r, "edits");
  if ((st = array_of(a, "edits", sizeof *s->edits, (void **)&s->edits, &s->nedits, err))) return st;
  for (int i = 0; i < s->nedits; i++) {
    char w[32];
    snprintf(w, sizeof w, "edits[%d]", i);
    json_t *e = json_array_get(a, (size_t)i);
    if (!json_is_object(e)) return wv_fail(err, WV_ERR_INVALID, "'%s' must be an object", w);
    if ((st = parse_edit(e, w, c, s, &s->edits[i]))) return st;
  }
  s->max_bounces = 3, s->yarn_samples = WV_SCENE3D_DEFAULT_YARN_SAMPLES, s->seed = 1;
  double seed = 1;
  int transmits = 1;
  if ((st = wv_json_object(r, NULL, "render", kr, 0, &o, err)) ||
      (st = wv_json_int(o, "render", "max_bounces", 0, 64, 0, &s->max_bounces, err)) ||
      (st = wv_json_int(o, "render", "yarn_samples", 1, 64, 0, &s->yarn_samples, err)) ||
      (st = wv_json_number(o, "render", "seed", 0, 2147483647.0, 0, &seed, err)) ||
      (st = wv_json_bool(o, "render", "transmission", 0, &transmits, err)))
    return st;
  s->seed = (uint64_t)seed;
  s->opaque = !transmits;
  /* the capture scenes' response, without the camera blur (this renderer applies none) */
  if ((st = wv_scene_read_response(r, 0, &s->response, err)) || (st = wv_scene_check_response(&s->response, err)))
    return st;
  double mb = WV_MESH_DEFAULT_LIMIT_MB;
  if ((st = wv_json_object(r, NULL, "limits", kl, 0, &o, err)) ||
      (o && (st = wv_json_number(o, "limits", "mesh_mb", 1, 1 << 20, REQ, &mb, err))))
    return st;
  s->mesh_limit_bytes = (size_t)(mb * 1048576.0);
  /* the response's capture scene: only the image size, exposure, clip, encoding and falloff are used */
  s->response.width = s->width, s->response.height = s->height, s->response.spp = s->spp;
  if ((long long)s->width * s->height * s->spp > WV_SCENE_MAX_SAMPLES)
    return wv_fail(err, WV_ERR_NOMEM, "'image': %d x %d pixels x %d spp is too many samples", s->width, s->height,
                   s->spp);
  return WV_OK;
}

void wv_scene3d_free(wv_scene3d *s) {
  if (!s) return;
  for (int i = 0; i < s->nmaterials; i++) free(s->materials[i].params_path);
  for (int i = 0; i < s->nobjects; i++) free(s->objects[i].path);
  for (int i = 0; i < s->nedits; i++) free(s->edits[i].map), free(s->edits[i].mask);
  free(s->materials), free(s->objects), free(s->edits), free(s->lights), free(s->env_path);
  memset(s, 0, sizeof *s);
}

wv_status wv_scene3d_parse(const char *text, const char *source, const char *base_dir, wv_scene3d *s,
                           wv_error *err) {
  memset(s, 0, sizeof *s);
  json_t *root;
  wv_status st = wv_json_parse_object(text, source, &root, err);
  if (st) return st;
  ctx c = {base_dir, err};
  st = parse_root(root, &c, s);
  json_decref(root);
  if (st) {
    wv_error_prefix(err, "%s", source);
    wv_scene3d_free(s);
  }
  return st;
}

wv_status wv_scene3d_read(const char *path, wv_scene3d *s, wv_error *err) {
  memset(s, 0, sizeof *s);
  char *text;
  wv_status st = wv_json_read_text(path, &text, err);
  if (st) return st;
  char *base = strdup(path);
  if (!base) {
    free(text);
    return wv_fail(err, WV_ERR_NOMEM, "out of memory");
  }
  char *slash = strrchr(base, '/');
  if (slash) *(slash == base ? slash + 1 : slash) = '\0';
  st = wv_scene3d_parse(text, path, slash ? base : NULL, s, err);
  if (st) wv_error_excerpt(err, WV_EXCERPT_CHARS); /* the user named it as a scene: a short excerpt at most */
  free(base);
  free(text);
  return st;
}

int wv_scene3d_inputs(const wv_scene3d *s, const char **paths, int cap) {
  int n = 0;
#define ADD(p) \
  do { \
    if (p) { \
      if (n < cap) paths[n] = (p); \
      n++; \
    } \
  } while (0)
  for (int i = 0; i < s->nmaterials; i++) ADD(s->materials[i].params_path);
  for (int i = 0; i < s->nobjects; i++) ADD(s->objects[i].path);
  for (int i = 0; i < s->nedits; i++) {
    ADD(s->edits[i].map);
    ADD(s->edits[i].mask);
  }
  if (s->env == WV_ENV_FILE) ADD(s->env_path);
#undef ADD
  return n;
}
