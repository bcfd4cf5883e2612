/* The renderer's side of the camera rig: per-pixel footprints made once for many
 * renders of one geometry (wv_footprints), the rig prepared with them for a render,
 * and wv_render_fabric_at with the scale at the image centre. */
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "render/render_internal.h"

int wv_render_fabric_at(const wv_scene *s, double x, double y, double f[2]) {
  wv_camera_rig rig;
  wv_rig_prepare(s, &rig);
  wv_hit_f hit;
  wv_trace_f(&rig, (float)x, (float)y, &hit);
  if (!hit.hit) return 0;
  f[0] = hit.fx, f[1] = hit.fy;
  return 1;
}

int wv_render_centre_scale(const wv_scene *s, double jt[2][2], double *mm_per_px) {
  double f0[2], fx[2], fy[2], cx = 0.5 * s->width, cy = 0.5 * s->height;
  *mm_per_px = 0;
  if (!wv_render_fabric_at(s, cx, cy, f0) || !wv_render_fabric_at(s, cx + 1, cy, fx) ||
      !wv_render_fabric_at(s, cx, cy + 1, fy))
    return 0;
  for (int i = 0; i < 2; i++) jt[0][i] = fx[i] - f0[i], jt[1][i] = fy[i] - f0[i];
  double det = fabs(jt[0][0] * jt[1][1] - jt[0][1] * jt[1][0]);
  *mm_per_px = sqrt(det);
  return det > 0;
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
