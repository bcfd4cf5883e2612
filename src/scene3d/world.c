/* Loads what a scene file names: meshes (files or built-in shapes, transformed,
 * with tangent frames where a fabric needs them), the ray tracer over them,
 * fabric parameter files (prepared for shading), edit maps and masks (checked
 * for format, type and size) and the environment. Owns wv_world. */
#include <math.h>
#include <sys/stat.h>
#include <unistd.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene3d/world_internal.h"
#include "util/colour.h"
#include "woven/io.h"

void wv_turn_table_make(wv_turn_table *t) {
  for (int k = 0; k < WV_TURN_STEPS; k++) {
    double a = 2 * 3.14159265358979323846 * k / WV_TURN_STEPS;
    t->cs[k][0] = (float)cos(a), t->cs[k][1] = (float)sin(a);
  }
}

void wv_world_free(wv_world *w) {
  if (!w) return;
  for (int i = 0; i < w->nobjects; i++) wv_mesh_free(&w->meshes[i]);
  for (int i = 0; i < w->nobjects && w->faces; i++) free(w->faces[i]);
  for (int i = 0; i < w->nobjects && w->uv_grad; i++) free(w->uv_grad[i]);
  for (int i = 0; i < w->nobjects && w->face_uv; i++) free(w->face_uv[i]);
  for (int i = 0; i < w->nmats; i++) {
    free(w->mats[i].fab);
    free(w->mats[i].edits);
  }
  for (int i = 0; i < w->nimages; i++) wv_image_free(&w->images[i].img);
  free(w->images);
  wv_tracer_free(w->tracer);
  wv_envmap_free(&w->env);
  free(w->meshes), free(w->faces), free(w->face_uv), free(w->uv_grad), free(w->material), free(w->mats);
  free(w->planar), free(w->others);
  free(w);
}

void wv_world_size(const wv_world *w, long long *tris, long long *verts) {
  *tris = *verts = 0;
  for (int i = 0; i < w->nobjects; i++) *tris += w->meshes[i].nt, *verts += w->meshes[i].nv;
}

void wv_edit_lookup(const wv_image *img, float u, float v, float out[3]) {
  float x = u * (float)img->w - 0.5f, y = (1.0f - v) * (float)img->h - 0.5f;
  float fx = floorf(x), fy = floorf(y), ax = x - fx, ay = y - fy;
  long long x0 = (long long)fx, y0 = (long long)fy;
  out[0] = out[1] = out[2] = 0;
  for (int k = 0; k < 4; k++) {
    long long xi = (x0 + (k & 1)) % img->w, yi = (y0 + (k >> 1)) % img->h;
    if (xi < 0) xi += img->w;
    if (yi < 0) yi += img->h;
    float wgt = ((k & 1) ? ax : 1 - ax) * ((k >> 1) ? ay : 1 - ay);
    const float *p = wv_image_px(img, (int)xi, (int)yi);
    for (int c = 0; c < 3; c++) out[c] += wgt * p[c];
  }
}

/* Memory of one job (meshes, tracer, maps, environment) against its limit. */
typedef struct {
  size_t used, limit;
} budget;

static wv_status spend(budget *b, size_t bytes, const char *what, wv_error *err) {
  if (bytes > b->limit - b->used)
    return wv_fail(err, WV_ERR_NOMEM, "%s: the scene needs more than its memory limit of %zu MB (%zu MB used before "
                   "it, %zu MB for it)", what, b->limit >> 20, b->used >> 20, bytes >> 20);
  b->used += bytes;
  return WV_OK;
}

static size_t image_bytes(const wv_image *img) { return (size_t)img->w * img->h * (size_t)img->c * sizeof(float); }

/* PNG or EXR only (JPEG is lossy and has no linear form): checked by the magic bytes. */
static wv_status read_map(const char *path, int grey, int colour, wv_image *img, wv_error *err) {
  unsigned char magic[4] = {0};
  FILE *f;
  wv_status st = wv_fopen_regular(path, &f, err);
  if (st) return st;
  size_t n = fread(magic, 1, 4, f);
  fclose(f);
  int png = n == 4 && magic[0] == 0x89 && magic[1] == 'P', exr = n == 4 && magic[0] == 0x76 && magic[1] == 0x2f;
  if (!png && !exr) return wv_fail(err, WV_ERR_FORMAT, "%s: an edit map must be a PNG or EXR image", path);
  wv_image_info info;
  st = wv_image_read(path, img, &info, err);
  if (st) return st;
  if (grey && info.channels_in_file > 2) {
    for (size_t i = 0; i < (size_t)img->w * img->h; i++) {
      const float *p = img->data + 3 * i;
      if (p[0] != p[1] || p[1] != p[2]) {
        wv_image_free(img);
        return wv_fail(err, WV_ERR_FORMAT, "%s: must be a grey image (this edit and masks take one value a pixel)",
                       path);
      }
    }
  }
  for (size_t i = 0; i < (size_t)img->w * img->h * 3; i++) {
    float v = img->data[i];
    if (!isfinite(v) || v < 0) {
      wv_image_free(img);
      return wv_fail(err, WV_ERR_FORMAT, "%s: has a negative, NaN or infinite value", path);
    }
    if (v > WV_SCENE3D_MAX_MAP_VALUE) {
      wv_image_free(img);
      return wv_fail(err, WV_ERR_FORMAT, "%s: pixel %zu has the value %g, above %g", path, i / 3, v,
                     WV_SCENE3D_MAX_MAP_VALUE);
    }
    if (colour && png) img->data[i] = wv_srgb_decode_f(v); /* 8/16-bit colour maps are sRGB */
  }
  return WV_OK;
}

/* The map at path, read once per file (by device and inode) and reading (grey, colour). */
static wv_status get_map(wv_world *w, budget *b, const char *path, int grey, int colour, const wv_image **out,
                         wv_error *err) {
  int fd;
  struct stat sb;
  wv_status st = wv_open_regular(path, &fd, &sb, err);
  if (st) return st;
  close(fd);
  for (int i = 0; i < w->nimages; i++) {
    const wv_world_image *im = &w->images[i];
    if (im->dev == (unsigned long long)sb.st_dev && im->ino == (unsigned long long)sb.st_ino && im->grey == grey &&
        im->colour == colour) {
      *out = &im->img;
      return WV_OK;
    }
  }
  wv_world_image *im = &w->images[w->nimages];
  memset(im, 0, sizeof *im);
  if ((st = read_map(path, grey, colour, &im->img, err))) return st;
  if ((st = spend(b, image_bytes(&im->img), path, err))) {
    wv_image_free(&im->img);
    return st;
  }
  im->dev = (unsigned long long)sb.st_dev, im->ino = (unsigned long long)sb.st_ino, im->grey = grey, im->colour = colour;
  w->nimages++;
  *out = &im->img;
  return WV_OK;
}

static wv_status load_edit(wv_world *w, budget *b, const wv_edit3d *e, wv_edit_map *m, wv_error *err) {
  m->op = e->op;
  m->gain = (float)e->gain;
  int colour = e->op == WV_EDIT_DIFFUSE_MULTIPLY || e->op == WV_EDIT_DIFFUSE_REPLACE;
  wv_status st = get_map(w, b, e->map, !colour, colour, &m->map, err);
  if (st || !e->mask) return st;
  if ((st = get_map(w, b, e->mask, 1, 0, &m->mask, err))) return st;
  if (m->mask->w != m->map->w || m->mask->h != m->map->h)
    return wv_fail(err, WV_ERR_FORMAT, "%s: the mask is %d x %d but its map %s is %d x %d", e->mask, m->mask->w,
                   m->mask->h, e->map, m->map->w, m->map->h);
  return WV_OK;
}

static wv_status load_material(const wv_material3d *src, const wv_params *override, wv_world_material *m,
                               wv_error *err) {
  m->kind = src->kind;
  for (int c = 0; c < 3; c++) m->albedo[c] = (float)src->albedo[c];
  if (src->kind != WV_MAT_FABRIC) return WV_OK;
  for (int i = 0; i < 2; i++) m->uv_mm[i] = (float)src->uv_mm[i], m->uv_off[i] = (float)src->uv_offset_mm[i];
  wv_params p;
  wv_status st;
  if (override) p = *override;
  else if ((st = wv_params_read(src->params_path, &p, err))) {
    wv_error_excerpt(err, 0); /* named by the scene, not by the user: none of its text */
    return st;
  }
  if (!(m->fab = malloc(sizeof *m->fab))) return wv_fail(err, WV_ERR_NOMEM, "out of memory for a fabric");
  if ((st = wv_fabric_prepare(&p, m->fab, err)))
    wv_error_prefix(err, "%s", override ? "--params" : src->params_path);
  else m->pback = wv_back_prob(m->fab);
  return st;
}

static wv_status make_mesh(const wv_scene3d *s, const wv_object3d *o, size_t limit, wv_mesh *m, wv_error *err) {
  int fabric = s->materials[o->material].kind == WV_MAT_FABRIC;
  wv_status st;
  switch (o->kind) {
    case WV_OBJ_MESH: st = wv_mesh_load(o->path, limit, fabric, m, err); break;
    case WV_OBJ_QUAD: st = wv_mesh_quad(o->centre, o->eu, o->ev, o->size[0], o->size[1], o->resolution, m, err); break;
    case WV_OBJ_SPHERE: st = wv_mesh_sphere(o->centre, o->radius, o->resolution / 2, o->resolution, m, err); break;
    default: st = wv_mesh_cylinder(o->centre, o->radius, o->length, o->resolution, m, err); break;
  }
  if (st) return st;
  const double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, z[3] = {0, 0, 0};
  if ((memcmp(o->A, I, sizeof I) || memcmp(o->b, z, sizeof z)) && (st = wv_mesh_transform(m, o->A, o->b, err)))
    return st;
  const char *name = o->path ? o->path : "built-in shape";
  if (!fabric) return wv_mesh_validate(m, name, 0, err);
  if ((st = wv_mesh_validate(m, name, 1, err))) return st;
  return wv_mesh_tangents(m, name, err);
}

/* Which objects are planar, and the box around the others of each (wv_world's
 * planar, others, plane_tol): lo..hi bound all the meshes. */
static wv_status find_planes(wv_world *w, const float lo[3], const float hi[3], wv_error *err) {
  int n = w->nobjects;
  w->planar = calloc((size_t)(n ? n : 1), sizeof *w->planar);
  w->others = malloc(sizeof *w->others * (size_t)(n ? n : 1));
  if (!w->planar || !w->others) return wv_fail(err, WV_ERR_NOMEM, "out of memory");
  double ext = 0; /* the largest coordinate: float positions are within 1e-7 of it of their true places */
  for (int k = 0; k < 3; k++) ext = fmax(ext, fmax(fabs((double)lo[k]), fabs((double)hi[k])));
  w->plane_tol = (float)(1e-6 * ext);
  float pad = (float)(1e-5 * ext);
  for (int i = 0; i < n; i++) {
    const wv_mesh *m = &w->meshes[i];
    if (m->nt > 0) { /* the plane of the first triangle, all vertices within plane_tol of it */
      const float *ng = w->faces[i][0].ng, *v0 = m->pos + 3 * m->idx[0];
      double c = (double)ng[0] * v0[0] + (double)ng[1] * v0[1] + (double)ng[2] * v0[2];
      int flat = ng[0] != 0 || ng[1] != 0 || ng[2] != 0;
      for (int v = 0; v < m->nv && flat; v++) {
        const float *p = m->pos + 3 * v;
        flat = fabs((double)ng[0] * p[0] + (double)ng[1] * p[1] + (double)ng[2] * p[2] - c) <= w->plane_tol;
      }
      w->planar[i] = flat;
    }
    float *blo = w->others[i][0], *bhi = w->others[i][1];
    for (int k = 0; k < 3; k++) blo[k] = INFINITY, bhi[k] = -INFINITY;
    for (int j = 0; j < n; j++)
      for (int v = 0; v < w->meshes[j].nv && j != i; v++)
        for (int k = 0; k < 3; k++) {
          float p = w->meshes[j].pos[3 * v + k];
          blo[k] = p < blo[k] ? p : blo[k], bhi[k] = p > bhi[k] ? p : bhi[k];
        }
    for (int k = 0; k < 3; k++) blo[k] -= pad, bhi[k] += pad;
  }
  return WV_OK;
}

wv_status wv_world_load(const wv_scene3d *s, const wv_params *override, int threads, wv_world **out,
                        wv_error *err) {
  *out = NULL;
  wv_world *w = calloc(1, sizeof *w);
  wv_status st = WV_OK;
  if (!w) return wv_fail(err, WV_ERR_NOMEM, "out of memory");
  w->meshes = calloc((size_t)s->nobjects, sizeof *w->meshes);
  w->faces = calloc((size_t)s->nobjects, sizeof *w->faces);
  w->uv_grad = calloc((size_t)s->nobjects, sizeof *w->uv_grad);
  w->face_uv = calloc((size_t)s->nobjects, sizeof *w->face_uv);
  w->material = calloc((size_t)s->nobjects, sizeof *w->material);
  w->mats = calloc((size_t)s->nmaterials, sizeof *w->mats);
  w->images = s->nedits ? calloc(2 * (size_t)s->nedits, sizeof *w->images) : NULL;
  if (!w->meshes || !w->faces || !w->uv_grad || !w->face_uv || !w->material || !w->mats || (s->nedits && !w->images)) st = wv_fail(err, WV_ERR_NOMEM, "out of memory");
  /* one budget for everything the job holds: maps, meshes, the tracer, the environment */
  budget b = {0, s->mesh_limit_bytes ? s->mesh_limit_bytes : (size_t)WV_MESH_DEFAULT_LIMIT_MB << 20};
  for (int i = 0; i < s->nmaterials && !st; i++, w->nmats++)
    st = load_material(&s->materials[i], override, &w->mats[i], err);
  for (int i = 0; i < s->nmaterials && !st; i++) { /* edits, grouped by material */
    wv_world_material *m = &w->mats[i];
    for (int e = 0; e < s->nedits; e++) m->nedits += s->edits[e].material == i;
    if (m->nedits && !(m->edits = calloc((size_t)m->nedits, sizeof *m->edits))) st = wv_fail(err, WV_ERR_NOMEM, "out of memory");
    for (int e = 0, k = 0; e < s->nedits && !st; e++)
      if (s->edits[e].material == i) st = load_edit(w, &b, &s->edits[e], &m->edits[k++], err);
  }
  for (int i = 0; i < s->nobjects && !st; i++, w->nobjects++) {
    w->material[i] = s->objects[i].material;
    st = make_mesh(s, &s->objects[i], b.limit - b.used, &w->meshes[i], err);
    const char *what = s->objects[i].path ? s->objects[i].path : "a built-in shape";
    if (!st) st = spend(&b, wv_mesh_bytes(w->meshes[i].nv, w->meshes[i].nt), what, err);
    /* what the path tracer reads per triangle (wv_face; a fabric's UVs, tangents and
     * UV gradients), each triangle's records on cache lines of their own */
    const wv_mesh *m = &w->meshes[i];
    int fabric = w->mats[w->material[i]].kind == WV_MAT_FABRIC;
    size_t nt = (size_t)m->nt;
    if (!st) st = spend(&b, (sizeof(wv_face) + (fabric ? sizeof(wv_face_uv) + sizeof(wv_uv_grad) : 0)) * nt, what, err);
    if (!st && (!(w->faces[i] = aligned_alloc(64, sizeof(wv_face) * (nt ? nt : 1))) ||
                (fabric && !(w->face_uv[i] = aligned_alloc(64, sizeof(wv_face_uv) * (nt ? nt : 1)))) ||
                (fabric && !(w->uv_grad[i] = malloc(sizeof(wv_uv_grad) * nt)))))
      st = wv_fail(err, WV_ERR_NOMEM, "out of memory");
    if (!st) wv_faces_make(m, w->faces[i], w->face_uv[i], w->uv_grad[i]);
  }
  if (!st) {
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    const wv_mesh **list = malloc(sizeof *list * (size_t)s->nobjects);
    if (!list) st = wv_fail(err, WV_ERR_NOMEM, "out of memory");
    for (int i = 0; i < s->nobjects && list; i++) {
      list[i] = &w->meshes[i];
      for (int v = 0; v < w->meshes[i].nv; v++)
        for (int k = 0; k < 3; k++) {
          float p = w->meshes[i].pos[3 * v + k];
          lo[k] = p < lo[k] ? p : lo[k], hi[k] = p > hi[k] ? p : hi[k];
        }
    }
    w->scene_radius = 0.5f * sqrtf((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                                   (hi[2] - lo[2]) * (hi[2] - lo[2]));
    if (!st) st = find_planes(w, lo, hi, err);
    if (list) st = wv_tracer_create(list, s->nobjects, threads, b.limit - b.used, &w->tracer, err);
    free(list);
  }
  if (!st && s->env != WV_ENV_NONE) {
    wv_image img = {0};
    const char *name = s->env == WV_ENV_FILE ? s->env_path : s->env_name;
    wv_image_info info = {0};
    if (s->env == WV_ENV_FILE) {
      if (!(st = wv_image_read(s->env_path, &img, &info, err)) && !info.is_float)
        st = wv_fail(err, WV_ERR_FORMAT, "%s: an environment map must be an EXR file (linear radiance)", s->env_path);
    } else if (s->env == WV_ENV_BUILTIN) {
      st = wv_env_builtin(s->env_name, s->env_width, &img, err);
    } else if (!(st = wv_image_alloc(&img, 4, 2, 3, err))) {
      for (int i = 0; i < 24; i++) img.data[i] = (float)s->env_color[i % 3];
    }
    /* the image while read, then the map's radiance and its two sampling tables */
    if (!st) st = spend(&b, image_bytes(&img) + wv_envmap_bytes(img.w, img.h), name, err);
    if (!st) st = wv_envmap_init(&w->env, &img, s->env_strength, s->env_rotation_deg, name, err);
    w->has_env = !st;
    wv_image_free(&img);
  }
  if (st) {
    wv_world_free(w);
    return st;
  }
  *out = w;
  return WV_OK;
}
