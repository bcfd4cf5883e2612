#include "woven/render.h"

#include <math.h>
#include <omp.h>
#include <string.h>

#include "render/render_internal.h"

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
  for (int i = 0; i < 2; i++) f->inv_glint_cell[i] = 1.0f / f->glint_cell[i];
  for (int i = 0; i < 4096; i++) {
    float u = (float)-log(1.0 - (i + 0.5) / 4096.0);
    f->glint_table[i] = u < 10.0f ? u : 10.0f;
  }
  for (int r = 0; r < WV_WEAVE_MAX; r++)
    for (int c = 0; c < WV_WEAVE_MAX; c++) {
      const wv_weave_cell *ce = &f->ym.weave.cell[r][c];
      f->cellpack[r * WV_WEAVE_MAX + c] = ce->type | ce->len << 8 | ce->index << 16;
    }
  f->seed = (uint64_t)p->seed;
  return WV_OK;
}

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

/* Average radiance of pixel (px, py). */
static void render_pixel(const wv_camera_rig *rig, const wv_fabric *fab, int px, int py, int spp, float out[3]) {
  wv_footprint fp;
  wv_footprint_prepare(rig, px, py, &fp);
  float acc[WV_ACC_ROWS][3] = {{0}};
  if (fp.fast) wv_render_fast_pixel(fab, &fp, px, py, spp, rig->width, acc);
  else wv_render_traced_pixel(rig, fab, px, py, spp, acc); /* silhouette pixel */
  wv_acc_total(acc, out);
  for (int c = 0; c < 3; c++) out[c] /= (float)spp;
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
    for (int px = 0; px < s->width; px++) {
      render_pixel(&rig, &fab, px, py, spp, wv_image_px(&rad, px, py));
    }
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
