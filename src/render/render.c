#include "woven/render.h"

#include <math.h>
#include <omp.h>
#include <string.h>

#include "render/render_internal.h"
#include "woven/brdf.h"

wv_status wv_fabric_prepare(const wv_params *p, wv_fabric *f, wv_error *err) {
  memset(f, 0, sizeof *f);
  wv_status st = wv_params_validate(p, err);
  if (st) return st;
  if ((st = wv_params_yarn_model(p, &f->ym, err))) return st;
  for (int y = 0; y < 2; y++) {
    for (int c = 0; c < 3; c++) {
      f->kd[y][c] = (float)p->diffuse[y][c];
      f->ks[y][c] = (float)p->specular[y][c];
    }
    f->alpha[y] = (float)p->roughness[y];
  }
  f->blend = (float)p->diffuse_blend;
  f->thickness = (float)p->thickness;
  f->glints = p->specular_noise;
  f->glint_cell[0] = f->ym.spacing[WV_WARP] / 8.0f;
  f->glint_cell[1] = f->ym.spacing[WV_WEFT] / 8.0f;
  f->seed = (uint64_t)p->seed;
  return WV_OK;
}

/* Radiance of one sample (RGB added to acc). */
static inline void shade(const wv_fabric *f, const wv_hit *h, float acc[3]) {
  wv_yarn_point yp;
  wv_yarn_eval(&f->ym, h->fx, h->fy, &yp);
  if (yp.type < 0) return; /* gap: nothing reflects */
  int ty = yp.type;
  float mi = h->wi[2], mo = h->wo[2];
  float spec = wv_brdf_specular(yp.t, f->alpha[ty], f->thickness, h->wi, h->wo, (const float[3]){0, 0, 1});
  spec *= wv_glint(f, h->fx, h->fy) * mi;
  float ni = wv_dot3(h->wi, yp.n);
  float diff = (f->blend * (ni > 0.0f ? ni : 0.0f) + (1.0f - f->blend) * mi) * (1.0f / 3.14159265358979f);
  (void)mo;
  for (int c = 0; c < 3; c++) acc[c] += h->light * (f->ks[ty][c] * spec + f->kd[ty][c] * diff);
}

wv_status wv_render(const wv_scene *s, const wv_params *p, const wv_render_opts *opt, wv_image *capture,
                    wv_image *radiance, wv_error *err) {
  wv_status st = wv_scene_validate(s, err);
  if (st) return st;
  wv_fabric fab;
  if ((st = wv_fabric_prepare(p, &fab, err))) return st;
  int spp = opt && opt->spp > 0 ? opt->spp : s->spp;
  if (spp > WV_SCENE_MAX_SPP)
    return wv_fail(err, WV_ERR_INVALID, "spp %d is above the limit %d", spp, WV_SCENE_MAX_SPP);
  if ((long long)s->width * s->height * spp > WV_SCENE_MAX_SAMPLES)
    return wv_fail(err, WV_ERR_NOMEM, "%d x %d pixels x %d spp is too many samples (limit %lld)", s->width,
                   s->height, spp, (long long)WV_SCENE_MAX_SAMPLES);
  int threads = opt && opt->threads > 0 ? opt->threads : omp_get_max_threads();
  wv_camera_rig rig;
  wv_rig_prepare(s, &rig);
  wv_image rad;
  if ((st = wv_image_alloc(&rad, s->width, s->height, 3, err))) return st;
  if ((st = wv_image_alloc(capture, s->width, s->height, 3, err))) {
    wv_image_free(&rad);
    return st;
  }
  const float inv = 1.0f / (float)spp;
  int rows_done = 0;
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
  for (int py = 0; py < s->height; py++) {
    if (opt && opt->progress && omp_get_thread_num() == 0) {
      int d;
#pragma omp atomic read
      d = rows_done;
      opt->progress(opt->progress_user, (double)d / s->height);
    }
    for (int px = 0; px < s->width; px++) {
      float acc[3] = {0, 0, 0};
      for (int k = 0; k < spp; k++) {
        float sx, sy;
        wv_pixel_sample(px, py, k, spp, s->width, fab.seed, &sx, &sy);
        wv_hit hit;
        if (wv_rig_trace(&rig, (float)px + sx, (float)py + sy, &hit)) shade(&fab, &hit, acc);
      }
      float *o = wv_image_px(&rad, px, py);
      for (int c = 0; c < 3; c++) o[c] = acc[c] * inv;
    }
#pragma omp atomic update
    rows_done++;
  }
  if (opt && opt->progress) opt->progress(opt->progress_user, 1.0);
  wv_scene_response(s, &rad, capture);
  if (radiance) *radiance = rad;
  else wv_image_free(&rad);
  return WV_OK;
}
