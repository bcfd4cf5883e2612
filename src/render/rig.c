#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "render/render_internal.h"
#include "kernel/fastmath.h"

static void normalize3(float v[3]) {
  float l = sqrtf(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  v[0] /= l, v[1] /= l, v[2] /= l;
}

void wv_rig_prepare(const wv_scene *s, wv_camera_rig *r) {
  memset(r, 0, sizeof *r);
  r->width = s->width, r->height = s->height;
  float up[3];
  for (int i = 0; i < 3; i++) {
    r->cpos[i] = (float)s->cam_pos[i];
    r->fwd[i] = (float)(s->cam_look_at[i] - s->cam_pos[i]);
    up[i] = (float)s->cam_up[i];
    r->lpos[i] = (float)s->light_pos[i];
  }
  normalize3(r->fwd);
  /* right = fwd x up, true up = right x fwd */
  r->right[0] = r->fwd[1] * up[2] - r->fwd[2] * up[1];
  r->right[1] = r->fwd[2] * up[0] - r->fwd[0] * up[2];
  r->right[2] = r->fwd[0] * up[1] - r->fwd[1] * up[0];
  normalize3(r->right);
  r->up[0] = r->right[1] * r->fwd[2] - r->right[2] * r->fwd[1];
  r->up[1] = r->right[2] * r->fwd[0] - r->right[0] * r->fwd[2];
  r->up[2] = r->right[0] * r->fwd[1] - r->right[1] * r->fwd[0];
  r->tan_half = (float)tan(0.5 * s->vfov_deg * 3.14159265358979323846 / 180.0);
  r->aspect = (float)s->width / (float)s->height;
  r->shape = s->shape;
  r->warp_along_axis = s->warp_along_axis;
  r->radius = (float)s->radius;
  r->rot_c = (float)cos(s->rotation_deg * 3.14159265358979323846 / 180.0);
  r->rot_s = (float)sin(s->rotation_deg * 3.14159265358979323846 / 180.0);
  r->off[0] = (float)s->fabric_offset[0], r->off[1] = (float)s->fabric_offset[1];
  r->scale = (float)s->mm_per_unit;
  r->lint = (float)s->light_intensity;
}

int wv_rig_trace(const wv_camera_rig *r, float x, float y, wv_hit *hit) {
  float ndx = (2.0f * x / (float)r->width - 1.0f) * r->tan_half * r->aspect;
  float ndy = (1.0f - 2.0f * y / (float)r->height) * r->tan_half;
  float d[3];
  for (int i = 0; i < 3; i++) d[i] = r->fwd[i] + ndx * r->right[i] + ndy * r->up[i];
  normalize3(d);
  const float *o = r->cpos;
  float p[3], N[3], T[3], B[3];
  if (r->shape == WV_SHAPE_CYLINDER) {
    /* Cylinder y^2 + z^2 = R^2 around the world x axis; nearest hit in front. */
    float a = d[1] * d[1] + d[2] * d[2];
    float b = o[1] * d[1] + o[2] * d[2];
    float c = o[1] * o[1] + o[2] * o[2] - r->radius * r->radius;
    float disc = b * b - a * c;
    if (a < 1e-12f || disc < 0.0f) return 0;
    float sq = sqrtf(disc);
    float t = (-b - sq) / a;
    if (t <= 0.0f) t = (-b + sq) / a;
    if (t <= 0.0f) return 0;
    for (int i = 0; i < 3; i++) p[i] = o[i] + t * d[i];
    float inv = 1.0f / r->radius;
    float sn = p[1] * inv, cs = p[2] * inv;
    N[0] = 0, N[1] = sn, N[2] = cs;
    float theta = wv_atan2_f(p[1], p[2]);
    if (r->warp_along_axis) { /* fabric y along +x, fabric x runs down the front */
      T[0] = 0, T[1] = -cs, T[2] = sn;
      B[0] = 1, B[1] = 0, B[2] = 0;
      hit->fx = -r->radius * theta * r->scale + r->off[0];
      hit->fy = p[0] * r->scale + r->off[1];
    } else {
      T[0] = 1, T[1] = 0, T[2] = 0;
      B[0] = 0, B[1] = cs, B[2] = -sn;
      hit->fx = p[0] * r->scale + r->off[0];
      hit->fy = r->radius * theta * r->scale + r->off[1];
    }
  } else {
    if (fabsf(d[2]) < 1e-12f) return 0;
    float t = -o[2] / d[2];
    if (t <= 0.0f) return 0;
    for (int i = 0; i < 3; i++) p[i] = o[i] + t * d[i];
    N[0] = 0, N[1] = 0, N[2] = 1;
    T[0] = r->rot_c, T[1] = r->rot_s, T[2] = 0;
    B[0] = -r->rot_s, B[1] = r->rot_c, B[2] = 0;
    hit->fx = (p[0] * T[0] + p[1] * T[1]) * r->scale + r->off[0];
    hit->fy = (p[0] * B[0] + p[1] * B[1]) * r->scale + r->off[1];
  }
  float l[3];
  for (int i = 0; i < 3; i++) l[i] = r->lpos[i] - p[i];
  float r2 = l[0] * l[0] + l[1] * l[1] + l[2] * l[2];
  float il = 1.0f / sqrtf(r2);
  for (int i = 0; i < 3; i++) l[i] *= il;
  hit->wi[0] = l[0] * T[0] + l[1] * T[1] + l[2] * T[2];
  hit->wi[1] = l[0] * B[0] + l[1] * B[1] + l[2] * B[2];
  hit->wi[2] = l[0] * N[0] + l[1] * N[1] + l[2] * N[2];
  hit->wo[0] = -(d[0] * T[0] + d[1] * T[1] + d[2] * T[2]);
  hit->wo[1] = -(d[0] * B[0] + d[1] * B[1] + d[2] * B[2]);
  hit->wo[2] = -(d[0] * N[0] + d[1] * N[1] + d[2] * N[2]);
  if (hit->wi[2] <= 0.0f || hit->wo[2] <= 0.0f) return 0;
  /* A ray grazing the plane meets it absurdly far away: beyond 1000 km of fabric a
   * float cannot place a yarn, and the yarn index would overflow an integer. */
  if (!(fabsf(hit->fx) < 1e9f && fabsf(hit->fy) < 1e9f)) return 0;
  hit->light = r->lint / r2;
  return 1;
}

void wv_footprint_prepare(const wv_camera_rig *rig, int px, int py, wv_footprint *fp) {
  if (rig->cache) {
    *fp = rig->cache[(size_t)py * rig->width + px];
    return;
  }
  wv_hit c, k[4];
  fp->centre_hit = wv_rig_trace(rig, (float)px + 0.5f, (float)py + 0.5f, &c);
  fp->fast = fp->centre_hit;
  for (int i = 0; i < 4 && fp->fast; i++) {
    fp->fast = wv_rig_trace(rig, (float)(px + (i & 1)), (float)(py + (i >> 1)), &k[i]);
    fp->fx[i] = k[i].fx, fp->fy[i] = k[i].fy;
  }
  if (fp->centre_hit) wv_dirs_from_hit(&c, &fp->dirs);
}

int wv_render_fabric_at(const wv_scene *s, double x, double y, double f[2]) {
  wv_camera_rig rig;
  wv_rig_prepare(s, &rig);
  wv_hit hit;
  if (!wv_rig_trace(&rig, (float)x, (float)y, &hit)) return 0;
  f[0] = hit.fx, f[1] = hit.fy;
  return 1;
}

struct wv_footprints {
  wv_camera_rig rig; /* the geometry they were made for (cache NULL) */
  wv_footprint *fp;  /* width x height */
};

wv_status wv_footprints_create(const wv_scene *s, int threads, wv_footprints **out, wv_error *err) {
  *out = NULL;
  wv_status st = wv_scene_validate(s, err);
  if (st) return st;
  wv_footprints *f = calloc(1, sizeof *f);
  if (f) f->fp = malloc(sizeof *f->fp * (size_t)s->width * s->height);
  if (!f || !f->fp) {
    free(f);
    return wv_fail(err, WV_ERR_NOMEM, "out of memory for the footprints of %d x %d pixels", s->width, s->height);
  }
  wv_rig_prepare(s, &f->rig);
  threads = threads > 0 ? threads : omp_get_max_threads();
#pragma omp parallel for schedule(dynamic, 4) num_threads(threads)
  for (int py = 0; py < s->height; py++)
    for (int px = 0; px < s->width; px++) wv_footprint_prepare(&f->rig, px, py, &f->fp[(size_t)py * s->width + px]);
  *out = f;
  return WV_OK;
}

void wv_footprints_free(wv_footprints *f) {
  if (!f) return;
  free(f->fp);
  free(f);
}

wv_status wv_rig_prepare_opts(const wv_scene *s, const wv_render_opts *opt, wv_camera_rig *rig, wv_error *err) {
  wv_rig_prepare(s, rig);
  if (!opt || !opt->footprints) return WV_OK;
  if (memcmp(rig, &opt->footprints->rig, sizeof *rig))
    return wv_fail(err, WV_ERR_INVALID, "render: the footprints were made for another scene geometry");
  rig->cache = opt->footprints->fp;
  return WV_OK;
}
