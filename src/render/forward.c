/* The forward integrator: wv_render (woven/render.h), rows in parallel
 * through the 8-wide row loop (render/rows.c), then the sensor response;
 * and wv_render_setup, which every render starts with. */
#include "woven/render.h"

#include <omp.h>

#include "render/render_internal.h"

wv_status wv_render_setup(const wv_scene *s, const wv_params *p, const wv_render_opts *opt, int w, int h,
                          wv_fabric *fab, int *spp, wv_error *err) {
  wv_status st = wv_scene_validate(s, err);
  if (st) return st;
  if ((st = wv_fabric_prepare(p, fab, err))) return st;
  *spp = opt && opt->spp > 0 ? opt->spp : s->spp;
  if (*spp > WV_SCENE_MAX_SPP)
    return wv_fail(err, WV_ERR_INVALID, "spp %d is above the limit %d", *spp, WV_SCENE_MAX_SPP);
  if ((long long)w * h * *spp > WV_SCENE_MAX_SAMPLES)
    return wv_fail(err, WV_ERR_NOMEM, "%d x %d pixels x %d spp is too many samples (limit %lld)", w, h, *spp,
                   (long long)WV_SCENE_MAX_SAMPLES);
  return WV_OK;
}

wv_status wv_render(const wv_scene *s, const wv_params *p, const wv_render_opts *opt, wv_image *capture,
                    wv_image *radiance, wv_error *err) {
  wv_fabric fab;
  int spp;
  wv_status st = wv_render_setup(s, p, opt, s->width, s->height, &fab, &spp, err);
  if (st) return st;
  int threads = opt && opt->threads > 0 ? opt->threads : omp_get_max_threads();
  wv_camera_rig rig;
  if ((st = wv_rig_prepare_opts(s, opt, &rig, err))) return st;
  wv_image rad;
  if ((st = wv_image_alloc(&rad, s->width, s->height, 3, err))) return st;
  if ((st = wv_image_alloc(capture, s->width, s->height, 3, err))) {
    wv_image_free(&rad);
    return st;
  }
  int rows_done = 0;
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
  for (int py = 0; py < s->height; py++) {
    if (opt && opt->progress && omp_get_thread_num() == 0) {
      int d;
#pragma omp atomic read
      d = rows_done;
      opt->progress(opt->progress_user, (double)d / s->height);
    }
    wv_render_row(&rig, &fab, py, 0, s->width, spp, (float(*)[3])wv_image_px(&rad, 0, py), NULL);
#pragma omp atomic update
    rows_done++;
  }
  if (opt && opt->progress) opt->progress(opt->progress_user, 1.0);
  if ((st = wv_scene_capture(s, &rad, capture, err))) {
    wv_image_free(&rad), wv_image_free(capture);
    return st;
  }
  if (radiance) *radiance = rad;
  else wv_image_free(&rad);
  return WV_OK;
}
