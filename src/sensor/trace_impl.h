/* A camera ray through image points, its hit on the shape, and the light and
 * view directions there in the fabric's tangent frame (a lane template, see
 * kernel/lanes.h; instantiated by sensor/sensor.h). */
typedef struct {
  WV_M hit;                /* the ray meets the sample, the camera is above its surface and the light above
                            * it (below it when the rig transmits) */
  WV_P fx, fy;             /* fabric coordinates, mm */
  WV_P wi[3], wo[3];       /* to the light, to the camera: fabric tangent frame (z = macro normal) */
  WV_P light;              /* I / r^2 */
} WV_FN(wv_hit);

/* Trace image position (x, y) (pixels, top-left origin). */
WV_INLINE void WV_FN(wv_trace)(const wv_camera_rig *r, WV_P x, WV_P y, WV_FN(wv_hit) * hit) {
  /* the pinhole camera's ray */
  WV_P ndx = (2.0f * x / (float)r->width - 1.0f) * r->tan_half * r->aspect;
  WV_P ndy = (1.0f - 2.0f * y / (float)r->height) * r->tan_half;
  WV_P d[3];
  for (int i = 0; i < 3; i++) d[i] = r->fwd[i] + ndx * r->right[i] + ndy * r->up[i];
  WV_P l = wv_sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  for (int i = 0; i < 3; i++) d[i] /= l;
  WV_FN(wv_surface) s;
  WV_FN(wv_shape_hit)(&r->shape, r->cpos, d, &s);
  /* the point light */
  WV_P lv[3];
  for (int i = 0; i < 3; i++) lv[i] = r->lpos[i] - s.p[i];
  WV_P r2 = lv[0] * lv[0] + lv[1] * lv[1] + lv[2] * lv[2];
  WV_P il = 1.0f / wv_sqrt(r2);
  for (int i = 0; i < 3; i++) lv[i] *= il;
  hit->wi[0] = lv[0] * s.t[0] + lv[1] * s.t[1] + lv[2] * s.t[2];
  hit->wi[1] = lv[0] * s.b[0] + lv[1] * s.b[1] + lv[2] * s.b[2];
  hit->wi[2] = lv[0] * s.n[0] + lv[1] * s.n[1] + lv[2] * s.n[2];
  hit->wo[0] = -(d[0] * s.t[0] + d[1] * s.t[1] + d[2] * s.t[2]);
  hit->wo[1] = -(d[0] * s.b[0] + d[1] * s.b[1] + d[2] * s.b[2]);
  hit->wo[2] = -(d[0] * s.n[0] + d[1] * s.n[1] + d[2] * s.n[2]);
  /* A ray grazing the plane meets it absurdly far away: beyond 1000 km of fabric a
   * float cannot place a yarn, and the yarn index would overflow an integer. */
  /* The light on the sample's side: in front, or behind it when the rig transmits. */
  WV_M lit_side = r->transmit ? (hit->wi[2] < 0.0f) : (hit->wi[2] > 0.0f);
  hit->hit = s.hit & lit_side & (hit->wo[2] > 0.0f) & (s.fx < 1e9f) & (s.fx > -1e9f) & (s.fy < 1e9f) &
             (s.fy > -1e9f);
  hit->light = r->lint / r2;
  hit->fx = s.fx, hit->fy = s.fy;
}

/* A sample's fabric position in a pixel with a footprint: the bilinear map of
 * the corners c[0..3] ((0,0), (1,0), (0,1), (1,1)) at (sx, sy) in the pixel. */
WV_INLINE WV_P WV_FN(wv_footprint_at)(const WV_P c[4], WV_P sx, WV_P sy) {
  WV_P w00 = (1 - sx) * (1 - sy), w10 = sx * (1 - sy), w01 = (1 - sx) * sy, w11 = sx * sy;
  return w00 * c[0] + w10 * c[1] + w01 * c[2] + w11 * c[3];
}
