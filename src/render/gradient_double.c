/* The gradient renderer's pixel loop in double, one sample at a time, for
 * gradient checks: float rounding (~1e-7 of a pixel) divided by a
 * finite-difference step swamps a 1e-3 comparison. The same sampler, tracer
 * and shading kernel as the float path, in their scalar and double flavours. */
#include <string.h>

#include "render/render_internal.h"

void wv_grad_pixel_d(const wv_camera_rig *rig, const wv_fabric *fab, const wv_shade_params_d *P, int px, int py,
                     int spp, wv_grad_pixel *out) {
  double acc[WV_ACC_ROWS][3], J[2][WV_J_COUNT], open[WV_ACC_ROWS]; /* rows as the float path's */
  memset(acc, 0, sizeof acc);
  memset(open, 0, sizeof open);
  memset(J, 0, sizeof J);
  wv_footprint fp;
  wv_footprint_prepare(rig, px, py, &fp);
  wv_pixel_sampler_f ps = wv_pixel_sampler_make(px, py, rig->width, fab->seed);
  int nx, ny;
  wv_pixel_grid(spp, &nx, &ny);
  for (int s = 0; s < spp; s++) {
    float sx, sy, fx, fy;
    wv_sample_at_f(&ps, nx, ny, s, &sx, &sy);
    wv_dirs_f d = fp.dirs;
    if (fp.fast) {
      fx = wv_footprint_at_f(fp.fx, sx, sy), fy = wv_footprint_at_f(fp.fy, sx, sy);
    } else { /* silhouette pixel: trace each sample */
      wv_hit_f hit;
      wv_trace_f(rig, (float)px + sx, (float)py + sy, &hit);
      if (!hit.hit) continue;
      wv_dirs_make_f(hit.wi, hit.wo, hit.light, &d);
      fx = hit.fx, fy = hit.fy;
    }
    wv_dirs_d dd;
    for (int i = 0; i < 3; i++) dd.wi[i] = d.wi[i], dd.wo[i] = d.wo[i], dd.h[i] = d.h[i];
    dd.mi = d.mi, dd.mo = d.mo, dd.light = d.light;
    double rad[3], op = 0;
    wv_shade_grad_d g;
    wv_shade_ex_d(fab, P, &dd, fx, fy, rad, &g, &op);
    for (int c = 0; c < 3; c++) acc[s % WV_ACC_ROWS][c] += rad[c];
    open[s % WV_ACC_ROWS] += op;
    for (int j = 0; j < WV_J_COUNT; j++) J[g.warp ? WV_WARP : WV_WEFT][j] += g.J[j];
  }
  for (int c = 0; c < 3; c++) out->rad[c] = WV_ACC_TREE(acc, c) / spp;
  if (rig->transmit) { /* the gap glow: its radiance per open area times the open area (render/rows.c) */
    double o = ((open[0] + open[1]) + (open[2] + open[3])) + ((open[4] + open[5]) + (open[6] + open[7]));
    for (int c = 0; c < 3; c++) out->rad[c] += wv_gap_glow(rig, px, py) * (o / spp);
  }
  for (int y = 0; y < 2; y++)
    for (int j = 0; j < WV_J_COUNT; j++) out->J[y][j] = J[y][j];
}
