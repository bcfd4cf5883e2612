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

typedef struct {
  const char *base;
  wv_error *err;
} ctx;

/* Refuses keys not in the NULL-terminated list; o must be an object. */
static wv_status keys_ok(json_t *o, const char *where, const char *const *allowed, wv_error *err) {
  if (!json_is_object(o)) return wv_fail(err, WV_ERR_INVALID, "'%s' must be an object", where);
  const char *k;
  json_t *v;
  json_object_foreach(o, k, v) {
    int known = 0;
    for (const char *const *a = allowed; *a && !known; a++) known = !strcmp(*a, k);
    if (!known) return wv_fail(err, WV_ERR_INVALID, "unknown key '%s.%s'", where, k);
  }
  return WV_OK;
}

/* A number in [lo, hi] (required, or left alone when absent). */
static wv_status number(json_t *o, const char *where, const char *key, int required, double lo, double hi, double *out,
                        wv_error *err) {
  json_t *v = json_object_get(o, key);
  if (!v) return required ? wv_fail(err, WV_ERR_INVALID, "missing '%s.%s'", where, key) : WV_OK;
  double x = json_is_number(v) ? json_number_value(v) : NAN;
  if (!json_is_number(v) || !(x >= lo && x <= hi))
    return wv_fail(err, WV_ERR_INVALID, "'%s.%s' must be a number in %g..%g", where, key, lo, hi);
  *out = x;
  return WV_OK;
}

static wv_status integer(json_t *o, const char *where, const char *key, long lo, long hi, int *out, wv_error *err) {
  json_t *v = json_object_get(o, key);
  if (!v) return WV_OK;
  json_int_t x = json_is_integer(v) ? json_integer_value(v) : lo - 1;
  if (x < lo || x > hi) return wv_fail(err, WV_ERR_INVALID, "'%s.%s' must be an integer in %ld..%ld", where, key, lo, hi);
  *out = (int)x;
  return WV_OK;
}

/* n finite numbers (a single number is also accepted for a colour when grey_ok). */
static wv_status numbers(json_t *o, const char *where, const char *key, int n, int required, int grey_ok, double lo,
                         double hi, double *out, wv_error *err) {
  json_t *v = json_object_get(o, key);
  if (!v) return required ? wv_fail(err, WV_ERR_INVALID, "missing '%s.%s'", where, key) : WV_OK;
  if (grey_ok && json_is_number(v)) {
    double x = json_number_value(v);
    if (!(x >= lo && x <= hi)) return wv_fail(err, WV_ERR_INVALID, "'%s.%s' must be in %g..%g", where, key, lo, hi);
    for (int i = 0; i < n; i++) out[i] = x;
    return WV_OK;
  }
  if (!json_is_array(v) || (int)json_array_size(v) != n)
    return wv_fail(err, WV_ERR_INVALID, "'%s.%s' must be an array of %d numbers", where, key, n);
  for (int i = 0; i < n; i++) {
    json_t *x = json_array_get(v, (size_t)i);
    double d = json_is_number(x) ? json_number_value(x) : NAN;
    if (!(d >= lo && d <= hi))
      return wv_fail(err, WV_ERR_INVALID, "'%s.%s[%d]' must be a number in %g..%g", where, key, i, lo, hi);
    out[i] = d;
  }
  return WV_OK;
}

static wv_status string(json_t *o, const char *where, const char *key, int required, const char **out, wv_error *err) {
  json_t *v = json_object_get(o, key);
  if (!v) return required ? wv_fail(err, WV_ERR_INVALID, "missing '%s.%s'", where, key) : WV_OK;
  if (!json_is_string(v) || !json_string_length(v))
    return wv_fail(err, WV_ERR_INVALID, "'%s.%s' must be a non-empty string", where, key);
  *out = json_string_value(v);
  return WV_OK;
}

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
  wv_status st = string(o, where, key, 1, &rel, c->err);
  if (st) return st;
  if (!(*out = resolve(c->base, rel))) return wv_fail(c->err, WV_ERR_NOMEM, "out of memory");
  return WV_OK;
}

static double norm3(double v[3]) {
  double l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  if (l > 0) v[0] /= l, v[1] /= l, v[2] /= l;
  return l;
}

#define BIG 1e7 /* coordinates in mm: 10 km */

static wv_status parse_camera(json_t *o, wv_scene3d *s, wv_error *err) {
  static const char *const k[] = {"position_mm", "look_at_mm", "up", "vfov_deg", NULL};
  wv_status st;
  if (!o) return wv_fail(err, WV_ERR_INVALID, "missing 'camera'");
  s->cam_up[1] = 1;
  if ((st = keys_ok(o, "camera", k, err)) || (st = numbers(o, "camera", "position_mm", 3, 1, 0, -BIG, BIG, s->cam_pos, err)) ||
      (st = numbers(o, "camera", "look_at_mm", 3, 1, 0, -BIG, BIG, s->cam_look_at, err)) ||
      (st = numbers(o, "camera", "up", 3, 0, 0, -BIG, BIG, s->cam_up, err)) ||
      (st = number(o, "camera", "vfov_deg", 1, 0.01, 179, &s->vfov_deg, err)))
    return st;
  double f[3], u[3] = {s->cam_up[0], s->cam_up[1], s->cam_up[2]}, x[3];
  for (int i = 0; i < 3; i++) f[i] = s->cam_look_at[i] - s->cam_pos[i];
  if (norm3(f) < 1e-9) return wv_fail(err, WV_ERR_INVALID, "'camera.look_at_mm' equals 'camera.position_mm'");
  x[0] = f[1] * u[2] - f[2] * u[1], x[1] = f[2] * u[0] - f[0] * u[2], x[2] = f[0] * u[1] - f[1] * u[0];
  if (norm3(x) < 1e-9 * (norm3(u) + 1e-300)) return wv_fail(err, WV_ERR_INVALID, "'camera.up' is parallel to the view direction");
  return WV_OK;
}

static wv_status parse_env(json_t *o, const ctx *c, wv_scene3d *s) {
  static const char *const k[] = {"builtin", "file", "uniform", "strength", "rotation_deg", "width", "visible", NULL};
  wv_error *err = c->err;
  wv_status st;
  s->env_strength = 1, s->env_width = 512, s->env_visible = 1;
  if (!o) return WV_OK;
  if ((st = keys_ok(o, "environment", k, err))) return st;
  int kinds = !!json_object_get(o, "builtin") + !!json_object_get(o, "file") + !!json_object_get(o, "uniform");
  if (kinds != 1)
    return wv_fail(err, WV_ERR_INVALID, "'environment' needs exactly one of 'builtin', 'file' or 'uniform'");
  if (json_object_get(o, "builtin")) {
    const char *n = NULL;
    if ((st = string(o, "environment", "builtin", 1, &n, err))) return st;
    if (!wv_env_is_builtin(n))
      return wv_fail(err, WV_ERR_INVALID, "'environment.builtin' = '%s': expected studio, sky or white", n);
    s->env = WV_ENV_BUILTIN;
    snprintf(s->env_name, sizeof s->env_name, "%s", n);
  } else if (json_object_get(o, "file")) {
    s->env = WV_ENV_FILE;
    if ((st = path_of(o, "environment", "file", c, &s->env_path))) return st;
  } else {
    s->env = WV_ENV_UNIFORM;
    if ((st = numbers(o, "environment", "uniform", 3, 1, 1, 0, 1e6, s->env_color, err))) return st;
  }
  json_t *vis = json_object_get(o, "visible");
  if (vis && !json_is_boolean(vis)) return wv_fail(err, WV_ERR_INVALID, "'environment.visible' must be true or false");
  if (vis) s->env_visible = json_is_true(vis);
  if ((st = number(o, "environment", "strength", 0, 0, 1e6, &s->env_strength, err)) ||
      (st = number(o, "environment", "rotation_deg", 0, -3600, 3600, &s->env_rotation_deg, err)) ||
      (st = integer(o, "environment", "width", 16, 8192, &s->env_width, err)))
    return st;
  return WV_OK;
}

static wv_status parse_light(json_t *o, const char *where, wv_light3d *l, wv_error *err) {
  static const char *const kp[] = {"type", "position_mm", "intensity", NULL};
  static const char *const ks[] = {"type", "position_mm", "look_at_mm", "intensity", "cone_deg", "blend_deg", NULL};
  static const char *const kd[] = {"type", "direction", "irradiance", NULL};
  static const char *const ka[] = {"type", "position_mm", "look_at_mm", "size_mm", "radiance", NULL};
  const char *type = NULL;
  wv_status st;
  if (!json_is_object(o)) return wv_fail(err, WV_ERR_INVALID, "'%s' must be an object", where);
  if ((st = string(o, where, "type", 1, &type, err))) return st;
  double at[3];
  if (!strcmp(type, "point")) {
    l->type = WV_LIGHT_POINT;
    if ((st = keys_ok(o, where, kp, err)) || (st = numbers(o, where, "position_mm", 3, 1, 0, -BIG, BIG, l->pos, err)) ||
        (st = numbers(o, where, "intensity", 3, 1, 1, 0, 1e12, l->color, err)))
      return st;
  } else if (!strcmp(type, "spot")) {
    l->type = WV_LIGHT_SPOT;
    l->cone_deg = 30, l->blend_deg = 5;
    if ((st = keys_ok(o, where, ks, err)) || (st = numbers(o, where, "position_mm", 3, 1, 0, -BIG, BIG, l->pos, err)) ||
        (st = numbers(o, where, "look_at_mm", 3, 1, 0, -BIG, BIG, at, err)) ||
        (st = numbers(o, where, "intensity", 3, 1, 1, 0, 1e12, l->color, err)) ||
        (st = number(o, where, "cone_deg", 0, 0.1, 89.9, &l->cone_deg, err)) ||
        (st = number(o, where, "blend_deg", 0, 0, 89.9, &l->blend_deg, err)))
      return st;
    if (l->blend_deg > l->cone_deg) l->blend_deg = l->cone_deg;
  } else if (!strcmp(type, "directional")) {
    l->type = WV_LIGHT_DIRECTIONAL;
    if ((st = keys_ok(o, where, kd, err)) || (st = numbers(o, where, "direction", 3, 1, 0, -BIG, BIG, l->dir, err)) ||
        (st = numbers(o, where, "irradiance", 3, 1, 1, 0, 1e9, l->color, err)))
      return st;
    if (norm3(l->dir) < 1e-12) return wv_fail(err, WV_ERR_INVALID, "'%s.direction' is zero", where);
  } else if (!strcmp(type, "area")) {
    l->type = WV_LIGHT_AREA;
    if ((st = keys_ok(o, where, ka, err)) || (st = numbers(o, where, "position_mm", 3, 1, 0, -BIG, BIG, l->pos, err)) ||
        (st = numbers(o, where, "look_at_mm", 3, 1, 0, -BIG, BIG, at, err)) ||
        (st = numbers(o, where, "size_mm", 2, 1, 0, 1e-3, 1e6, l->size, err)) ||
        (st = numbers(o, where, "radiance", 3, 1, 1, 0, 1e9, l->color, err)))
      return st;
  } else {
    return wv_fail(err, WV_ERR_INVALID, "'%s.type' = '%s': expected point, spot, directional or area", where, type);
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
    if ((st = keys_ok(o, where, kf, err)) || (st = path_of(o, where, "fabric", c, &m->params_path)) ||
        (st = numbers(o, where, "uv_mm", 2, 0, 1, 1e-6, 1e7, m->uv_mm, err)) ||
        (st = numbers(o, where, "uv_offset_mm", 2, 0, 0, -BIG, BIG, m->uv_offset_mm, err)))
      return st;
  } else if (json_object_get(o, "lambert")) {
    m->kind = WV_MAT_LAMBERT;
    if ((st = keys_ok(o, where, kl, err)) || (st = numbers(o, where, "lambert", 3, 1, 1, 0, 1, m->albedo, err)))
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
  if ((st = keys_ok(o, where, k, err)) || (st = numbers(o, where, "scale", 3, 0, 1, -1e6, 1e6, sc, err)) ||
      (st = numbers(o, where, "rotate_deg", 3, 0, 0, -3600, 3600, r, err)) ||
      (st = numbers(o, where, "translate_mm", 3, 0, 0, -BIG, BIG, ob->b, err)))
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
  if ((st = keys_ok(o, where, k, err))) return st;
  int kinds = !!json_object_get(o, "mesh") + !!json_object_get(o, "quad") + !!json_object_get(o, "sphere") +
              !!json_object_get(o, "cylinder");
  if (kinds != 1) return wv_fail(err, WV_ERR_INVALID, "'%s' needs exactly one of mesh, quad, sphere, cylinder", where);
  const char *mat = NULL;
  if ((st = string(o, where, "material", 1, &mat, err))) return st;
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
    if ((st = keys_ok(g, sub, kq, err)) || (st = numbers(g, sub, "centre_mm", 3, 1, 0, -BIG, BIG, ob->centre, err)) ||
        (st = numbers(g, sub, "u_axis", 3, 0, 0, -BIG, BIG, ob->eu, err)) ||
        (st = numbers(g, sub, "v_axis", 3, 0, 0, -BIG, BIG, ob->ev, err)) ||
        (st = numbers(g, sub, "size_mm", 2, 1, 0, 1e-6, BIG, ob->size, err)) ||
        (st = integer(g, sub, "cells", 1, 1024, &ob->resolution, err)))
      return st;
  } else if ((g = json_object_get(o, "sphere"))) {
    ob->kind = WV_OBJ_SPHERE;
    snprintf(sub, sizeof sub, "%s.sphere", where);
    ob->resolution = 96;
    if ((st = keys_ok(g, sub, ksph, err)) || (st = numbers(g, sub, "centre_mm", 3, 1, 0, -BIG, BIG, ob->centre, err)) ||
        (st = number(g, sub, "radius_mm", 1, 1e-6, BIG, &ob->radius, err)) ||
        (st = integer(g, sub, "segments", 3, 4096, &ob->resolution, err)))
      return st;
  } else {
    g = json_object_get(o, "cylinder");
    ob->kind = WV_OBJ_CYLINDER;
    snprintf(sub, sizeof sub, "%s.cylinder", where);
    ob->resolution = 1024;
    if ((st = keys_ok(g, sub, kc, err)) || (st = numbers(g, sub, "centre_mm", 3, 1, 0, -BIG, BIG, ob->centre, err)) ||
        (st = number(g, sub, "radius_mm", 1, 1e-6, BIG, &ob->radius, err)) ||
        (st = number(g, sub, "length_mm", 1, 1e-6, BIG, &ob->length, err)) ||
        (st = integer(g, sub, "segments", 3, 8192, &ob->resolution, err)))
      return st;
  }
  snprintf(sub, sizeof sub, "%s.transform", where);
  return parse_transform(json_object_get(o, "transform"), sub, ob, err);
}

static wv_status parse_edit(json_t *o, const char *where, const ctx *c, wv_scene3d *s, wv_edit3d *e) {
  static const char *const k[] = {"material", "apply", "map", "mask", "gain", NULL};
  static const char *const ops[] = {"diffuse_multiply", "diffuse_replace", "heightfield", "roughness"};
  wv_error *err = c->err;
  const char *mat = NULL, *op = NULL;
  wv_status st;
  if ((st = keys_ok(o, where, k, err)) || (st = string(o, where, "material", 1, &mat, err)) ||
      (st = string(o, where, "apply", 1, &op, err)))
    return st;
  e->material = find_material(s, mat);
  if (e->material < 0) return wv_fail(err, WV_ERR_INVALID, "'%s.material': no material named '%s'", where, mat);
  if (s->materials[e->material].kind != WV_MAT_FABRIC)
    return wv_fail(err, WV_ERR_INVALID, "'%s.material': '%s' is not a fabric", where, mat);
  int found = -1;
  for (int i = 0; i < 4; i++)
    if (!strcmp(op, ops[i])) found = i;
  if (found < 0)
    return wv_fail(err, WV_ERR_INVALID,
                   "'%s.apply' = '%s': expected diffuse_multiply, diffuse_replace, heightfield or roughness", where, op);
  e->op = (wv_edit_op)found;
  e->gain = 1;
  if ((st = path_of(o, where, "map", c, &e->map)) || (st = number(o, where, "gain", 0, 0, 1e3, &e->gain, err)))
    return st;
  if (json_object_get(o, "mask") && (st = path_of(o, where, "mask", c, &e->mask))) return st;
  return WV_OK;
}

/* The capture scenes' response and falloff blocks, into s->response. */
static wv_status parse_response(json_t *r, json_t *f, wv_scene *out, wv_error *err) {
  static const char *const kr[] = {"exposure", "clip", "encoding", "gamma", NULL};
  static const char *const kf[] = {"type", "sigma_px", NULL};
  static const char *const enc[] = {"linear", "srgb", "gamma"};
  wv_status st;
  out->exposure = 1, out->clip = 1, out->encoding = WV_ENC_SRGB, out->gamma = 2.2;
  if (r) {
    const char *e = NULL;
    if ((st = keys_ok(r, "response", kr, err)) || (st = number(r, "response", "exposure", 0, 1e-9, 1e9, &out->exposure, err)) ||
        (st = number(r, "response", "clip", 0, -1e9, 1e9, &out->clip, err)) ||
        (st = number(r, "response", "gamma", 0, 0.1, 10, &out->gamma, err)) ||
        (st = string(r, "response", "encoding", 0, &e, err)))
      return st;
    if (e) {
      int k = -1;
      for (int i = 0; i < 3; i++)
        if (!strcmp(e, enc[i])) k = i;
      if (k < 0) return wv_fail(err, WV_ERR_INVALID, "'response.encoding' must be \"srgb\", \"gamma\" or \"linear\"");
      out->encoding = (wv_encoding)k;
    }
  }
  if (f) {
    const char *t = NULL;
    if ((st = keys_ok(f, "falloff", kf, err)) || (st = string(f, "falloff", "type", 1, &t, err))) return st;
    if (!strcmp(t, "gaussian")) {
      out->falloff = 1;
      if ((st = number(f, "falloff", "sigma_px", 1, 1e-3, 1e9, &out->falloff_sigma, err))) return st;
    } else if (strcmp(t, "none")) {
      return wv_fail(err, WV_ERR_INVALID, "'falloff.type' must be \"gaussian\" or \"none\"");
    }
  }
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
  static const char *const kr[] = {"max_bounces", "yarn_samples", "seed", NULL};
  static const char *const kl[] = {"mesh_mb", NULL};
  wv_error *err = c->err;
  wv_status st;
  if ((st = keys_ok(r, "", top, err))) return st;
  const char *nm = "scene";
  if ((st = string(r, "", "name", 0, &nm, err))) return st;
  snprintf(s->name, sizeof s->name, "%s", nm);
  json_t *o = json_object_get(r, "image");
  if (!o) return wv_fail(err, WV_ERR_INVALID, "missing 'image'");
  s->spp = WV_SCENE3D_DEFAULT_SPP;
  if ((st = keys_ok(o, "image", ki, err)) || (st = integer(o, "image", "width", 1, WV_SCENE_MAX_SIDE, &s->width, err)) ||
      (st = integer(o, "image", "height", 1, WV_SCENE_MAX_SIDE, &s->height, err)) ||
      (st = integer(o, "image", "spp", 1, WV_SCENE_MAX_SPP, &s->spp, err)))
    return st;
  if (!s->width || !s->height) return wv_fail(err, WV_ERR_INVALID, "'image' needs 'width' and 'height'");
  if ((st = parse_camera(json_object_get(r, "camera"), s, err))) return st;
  if ((st = parse_env(json_object_get(r, "environment"), c, s))) return st;

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
  if ((o = json_object_get(r, "render"))) {
    double seed = 1;
    if ((st = keys_ok(o, "render", kr, err)) || (st = integer(o, "render", "max_bounces", 0, 64, &s->max_bounces, err)) ||
        (st = integer(o, "render", "yarn_samples", 1, 64, &s->yarn_samples, err)) ||
        (st = number(o, "render", "seed", 0, 0, 2147483647.0, &seed, err)))
      return st;
    s->seed = (uint64_t)seed;
  }
  if ((st = parse_response(json_object_get(r, "response"), json_object_get(r, "falloff"), &s->response, err)))
    return st;
  double mb = WV_MESH_DEFAULT_LIMIT_MB;
  if ((o = json_object_get(r, "limits")) &&
      ((st = keys_ok(o, "limits", kl, err)) || (st = number(o, "limits", "mesh_mb", 1, 1, 1 << 20, &mb, err))))
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
  json_error_t je;
  json_t *root = json_loads(text, JSON_REJECT_DUPLICATES, &je);
  if (!root) return wv_fail(err, WV_ERR_FORMAT, "%s:%d:%d: malformed JSON: %s", source, je.line, je.column, je.text);
  ctx c = {base_dir, err};
  wv_status st = json_is_object(root) ? parse_root(root, &c, s)
                                      : wv_fail(err, WV_ERR_INVALID, "the top level must be a JSON object");
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
  size_t len;
  wv_status st = wv_read_file_max(path, WV_JSON_MAX_BYTES, &text, &len, err);
  if (st) return st;
  char *base = strdup(path);
  if (!base) {
    free(text);
    return wv_fail(err, WV_ERR_NOMEM, "out of memory");
  }
  char *slash = strrchr(base, '/');
  if (slash) *(slash == base ? slash + 1 : slash) = '\0';
  if (strlen(text) != len) st = wv_fail(err, WV_ERR_FORMAT, "%s: file contains a NUL byte; not a JSON text", path);
  else st = wv_scene3d_parse(text, path, slash ? base : NULL, s, err);
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
