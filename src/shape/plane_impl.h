/* The plane z = 0, fabric x at angle rotation_deg from world x, the yarns turned
 * apart by skew_deg, displaced by the distortion (a lane template, see shape/shape.h). */
WV_INLINE void WV_FN(wv_plane_hit)(const wv_shape *sh, const float o[3], const WV_P d[3], WV_FN(wv_surface) * s) {
  WV_M miss = wv_abs(d[2]) < 1e-12f;
  WV_P t = -o[2] / wv_sel(miss, WV_PB(1.0f), d[2]);
  s->hit = wv_not(miss) & (t > 0.0f);
  for (int i = 0; i < 3; i++) s->p[i] = o[i] + t * d[i];
  s->n[0] = WV_PB(0.0f), s->n[1] = WV_PB(0.0f), s->n[2] = WV_PB(1.0f);
  s->t[0] = WV_PB(sh->rot_c), s->t[1] = WV_PB(sh->rot_s), s->t[2] = WV_PB(0.0f);
  s->b[0] = WV_PB(-sh->rot_s), s->b[1] = WV_PB(sh->rot_c), s->b[2] = WV_PB(0.0f);
  s->fx = (s->p[0] * sh->across[0][0] + s->p[1] * sh->across[0][1]) * sh->scale + sh->off[0];
  s->fy = (s->p[0] * sh->across[1][0] + s->p[1] * sh->across[1][1]) * sh->scale + sh->off[1];
  if (sh->distorted) { /* cloth not laid straight: a smooth displacement (wv_scene.distort) */
    WV_P t[WV_DISTORT_TERMS], a = s->p[0] * sh->dist_k, b = s->p[1] * sh->dist_k;
    WV_DISTORT_EVAL(a, b, t);
    for (int i = 0; i < WV_DISTORT_TERMS; i++) s->fx += t[i] * sh->dist[0][i], s->fy += t[i] * sh->dist[1][i];
  }
}
