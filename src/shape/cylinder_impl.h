/* The cylinder y^2 + z^2 = R^2 around the world x axis, nearest hit in front
 * of the camera; the warp runs along the axis or around it (a lane template,
 * see shape/shape.h). */
WV_INLINE void WV_FN(wv_cylinder_hit)(const wv_shape *sh, const float o[3], const WV_P d[3],
                                      WV_FN(wv_surface) * s) {
  WV_P a = d[1] * d[1] + d[2] * d[2];
  WV_P b = o[1] * d[1] + o[2] * d[2];
  float c = o[1] * o[1] + o[2] * o[2] - sh->radius * sh->radius;
  WV_P disc = b * b - a * c;
  WV_M miss = (a < 1e-12f) | (disc < 0.0f);
  WV_P sa = wv_sel(miss, WV_PB(1.0f), a), sq = wv_sqrt(wv_sel(miss, WV_PB(0.0f), disc));
  WV_P t = (-b - sq) / sa;
  t = wv_sel(t <= 0.0f, (-b + sq) / sa, t);
  s->hit = wv_not(miss) & (t > 0.0f);
  for (int i = 0; i < 3; i++) s->p[i] = o[i] + t * d[i];
  float inv = 1.0f / sh->radius;
  WV_P sn = s->p[1] * inv, cs = s->p[2] * inv;
  s->n[0] = WV_PB(0.0f), s->n[1] = sn, s->n[2] = cs;
  WV_P theta = wv_atan2g(s->p[1], s->p[2]);
  if (sh->warp_along_axis) { /* fabric y along +x, fabric x runs down the front */
    s->t[0] = WV_PB(0.0f), s->t[1] = -cs, s->t[2] = sn;
    s->b[0] = WV_PB(1.0f), s->b[1] = WV_PB(0.0f), s->b[2] = WV_PB(0.0f);
    s->fx = -sh->radius * theta * sh->scale + sh->off[0];
    s->fy = s->p[0] * sh->scale + sh->off[1];
  } else {
    s->t[0] = WV_PB(1.0f), s->t[1] = WV_PB(0.0f), s->t[2] = WV_PB(0.0f);
    s->b[0] = WV_PB(0.0f), s->b[1] = cs, s->b[2] = -sn;
    s->fx = s->p[0] * sh->scale + sh->off[0];
    s->fy = sh->radius * theta * sh->scale + sh->off[1];
  }
}
