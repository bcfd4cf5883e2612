/* The camera rig of a capture scene (camera, shape, light) prepared for
 * tracing, and each pixel's footprint on the fabric. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sensor/sensor.h"

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
  wv_shape_prepare(s, &r->shape);
  r->lint = (float)s->light_intensity;
  r->transmit = wv_scene_transmits(s);
  if (r->transmit && s->glow_radiance > 0) r->glow = (float)s->glow_radiance, r->glow_sigma = (float)s->glow_sigma;
}

float wv_gap_glow(const wv_camera_rig *rig, int x, int y) {
  if (!(rig->glow > 0)) return 0.0f;
  return (float)(rig->glow * wv_pixel_gaussian(rig->width, rig->height, x, y, rig->glow_sigma));
}

WV_SIMD_CLONES
void wv_footprint_prepare(const wv_camera_rig *rig, int px, int py, wv_footprint *fp) {
  if (rig->cache) {
    *fp = rig->cache[(size_t)py * rig->width + px];
    return;
  }
  /* one 8-wide trace: the centre, then the corners (0,0), (1,0), (0,1), (1,1) */
  wv_f8 x = (float)px + (wv_f8){0.5f, 0, 1, 0, 1, 0.5f, 0.5f, 0.5f};
  wv_f8 y = (float)py + (wv_f8){0.5f, 0, 0, 1, 1, 0.5f, 0.5f, 0.5f};
  wv_hit_8 h;
  wv_trace_8(rig, x, y, &h);
  fp->fast = (wv_bits_8(h.hit) & 0x1f) == 0x1f;
  for (int i = 0; i < 4; i++) fp->fx[i] = h.fx[i + 1], fp->fy[i] = h.fy[i + 1];
  if (h.hit[0]) {
    float wi[3] = {h.wi[0][0], h.wi[1][0], h.wi[2][0]}, wo[3] = {h.wo[0][0], h.wo[1][0], h.wo[2][0]};
    wv_dirs_make_f(wi, wo, h.light[0], &fp->dirs);
  } else {
    memset(&fp->dirs, 0, sizeof fp->dirs);
  }
}
