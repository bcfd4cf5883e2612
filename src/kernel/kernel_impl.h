/* The shading model, written once: yarn geometry (SPEC section 3), SGGX /
 * SpongeCake specular and blended Lambert diffuse (section 4), light through the
 * cloth (the specular's transmission, a diffuse transmission and the open gaps;
 * docs/model.md), and their derivatives with respect to the continuous parameters. A lane template (see
 * kernel/lanes.h), instantiated by kernel/kernel.h as wv_*_f (float),
 * wv_*_8 (8-wide) and wv_*_d (double shading, float positions).
 *
 * Value lines are in the order and form every renderer has always used (that
 * order is what makes all paths bit-identical). Each derivative sits right
 * under the value it differentiates, in a comment-quoted "d(value = ...)"
 * line: forward mode through the geometry (tangents of the normal and fiber
 * direction with respect to beta, u_max and psi), partial derivatives inside
 * the BRDF (with respect to t.wi, t.wo, t.h, n.wi, alpha and the blend), and
 * the chain rule where the two meet (wv_shade). Derivatives are only computed
 * when the caller asks (a NULL pointer removes them after inlining). */

#if WV_LANE == WV_LANE_D
#define K_PARAMS wv_shade_params_d
#else
#define K_PARAMS wv_shade_params_f
#endif

/* Per-type parameter picked per lane: warp ? a : b. */
WV_INLINE WV_L WV_FN(wv_pick)(WV_M warp, WV_R a, WV_R b) { return wv_sel(warp, WV_B(a), WV_B(b)); }
WV_INLINE WV_P WV_FN(wv_pickp)(WV_M warp, float a, float b) { return wv_sel(warp, WV_PB(a), WV_PB(b)); }

/* ======================= yarn geometry: the cell ======================= */

/* The visible yarn at fabric points (x, y) mm: which float, and where in it.
 * Nothing here depends on a continuous parameter (positions stay in float in
 * every flavour, so all flavours see the same cells). */
typedef struct {
  WV_M ok;           /* 0: a coordinate is beyond the lane type's integer range (8-wide only) */
  WV_M warp;         /* a warp yarn (else weft) */
  WV_M lit;          /* on a yarn (not in a gap between yarns) */
  WV_I row, col;     /* the cell (rows grow toward -y, columns toward +x) */
  WV_I index;        /* the cell's index in its float */
  WV_P a, l;         /* mm across the yarn from its centre line, along it from the float's centre */
  WV_P len;          /* float length L in cells */
  WV_P half_w, half_len; /* half the yarn's width and the float's half length, mm */
  WV_P a_h;          /* mm across the crossing yarn underneath (the other type) from its centre line */
  WV_M cov;          /* the crossing yarn covers the point (|a_h| <= its w/2): not an open gap */
} WV_FN(wv_yarn_cell);

WV_INLINE void WV_FN(wv_yarn_locate)(const wv_yarn_model *m, WV_P x, WV_P y, WV_FN(wv_yarn_cell) * c) {
  const float dx = m->spacing[WV_WARP], dy = m->spacing[WV_WEFT];
  WV_P r = -y * m->inv_spacing[WV_WEFT], cc = x * m->inv_spacing[WV_WARP];
  c->ok = wv_indexable(r) & wv_indexable(cc);
  if (!wv_all(c->ok)) return;
  WV_I I = wv_floori(r), J = wv_floori(cc);
  WV_P fr = r - wv_itof(I), fc = cc - wv_itof(J);
  /* the weave's segment table (wv_weave_at), one packed word per lookup */
  WV_I ci = wv_modn(I, m->weave.rows) * WV_WEAVE_MAX + wv_modn(J, m->weave.cols);
  WV_I pk = (WV_I)wv_gather32(m->cellpack, ci);
  WV_I ty = pk & 0xff, len = (pk >> 8) & 0xff, idx = pk >> 16;
  c->warp = ty == WV_WARP;
  c->row = I, c->col = J, c->index = idx;
  WV_P L = wv_itof(len), kk = wv_itof(idx);
  c->len = L;
  /* Local coordinates (see yarn.h for the frame): warp a = x - x_centre, l toward
   * +y; weft: the same turned by -90 degrees about z. */
  c->a = wv_sel(c->warp, (fc - 0.5f) * dx, (fr - 0.5f) * dy);
  c->l = wv_sel(c->warp, -((kk + fr) - 0.5f * L) * dy, ((kk + fc) - 0.5f * L) * dx);
  c->half_w = WV_FN(wv_pickp)(c->warp, 0.5f * dx * m->width, 0.5f * dy * m->width);
  c->half_len = 0.5f * L * WV_FN(wv_pickp)(c->warp, dy, dx);
  c->lit = wv_not(wv_abs(c->a) > c->half_w); /* |a| > w/2: a gap narrower than the spacing */
  /* the crossing yarn runs the other way, under the visible one: light passes it too */
  c->a_h = wv_sel(c->warp, (fr - 0.5f) * dy, (fc - 0.5f) * dx);
  c->cov = wv_not(wv_abs(c->a_h) > WV_FN(wv_pickp)(c->warp, 0.5f * dy * m->width, 0.5f * dx * m->width));
}

/* An open gap at the cell's points: neither the visible yarn nor the crossing one
 * covers them (light passes straight through the cloth there). */
WV_INLINE WV_M WV_FN(wv_cell_open)(const WV_FN(wv_yarn_cell) * c) { return wv_not(c->lit) & wv_not(c->cov); }

/* v, or v mod period when the identities repeat (tiled maps). */
WV_INLINE WV_I WV_FN(wv_wrap)(WV_I v, int period) { return period > 0 ? wv_modn(v, period) : v; }

/* The visible segment's identity (a hash of type, yarn index, float start, seed). */
WV_INLINE WV_U WV_FN(wv_yarn_segment)(const wv_yarn_model *m, const WV_FN(wv_yarn_cell) * c) {
  const int pr = m->period_rows, pc = m->period_cols;
  WV_U ha = wv_selu(c->warp, wv_tou64(WV_FN(wv_wrap)(c->col, pc)) << 1,
                    (wv_tou64(WV_FN(wv_wrap)(c->row, pr)) << 1) | 1);
  WV_U hb = wv_tou64(wv_seli(c->warp, WV_FN(wv_wrap)(c->row - c->index, pr), WV_FN(wv_wrap)(c->col - c->index, pc)));
  return wv_hash2g(ha, hb, m->seed);
}

/* ================== yarn geometry: the bent-cylinder frame ================== */

/* The frame in the yarn's local frame (yarn along +y; for a weft yarn the
 * fabric frame turned by -90 degrees about z: fabric (x, y, z) = local (y, -x, z)). */
typedef struct {
  WV_L n[3], t[3]; /* unit normal and fiber tangent after heightfield scaling, local frame */
  WV_L u, v;       /* inclination along and angle around the yarn (radians) */
  WV_L beta;       /* the segment's heightfield scaling after noise U_n */
} WV_FN(wv_yarn_frame);

/* Tangents of the frame (forward mode, WV_T_*), local frame. */
typedef struct {
  WV_L dn[2][3]; /* d n / d beta, d n / d u_max */
  WV_L dt[3][3]; /* d t / d beta, d t / d u_max, d t / d psi */
} WV_FN(wv_yarn_dframe);

/* d(w = v / |v|) for a change dv of v: (dv - w (w . dv)) / |v|; il = 1 / |v|. */
WV_INLINE void WV_FN(wv_dnormalize)(const WV_L w[3], WV_L il, const WV_L dv[3], WV_L out[3]) {
  WV_L wd = w[0] * dv[0] + w[1] * dv[1] + w[2] * dv[2];
  for (int i = 0; i < 3; i++) out[i] = (dv[i] - w[i] * wd) * il;
}

/* u = m / |m| for m = (x, y, z), or the unit vector (fx, fy, fz) where m vanishes
 * (|m|^2 < 1e-24); with du, d u along each of the np directions dm[p] (0 where u
 * was replaced). */
WV_INLINE void WV_FN(wv_unit_or)(WV_L x, WV_L y, WV_L z, float fx, float fy, float fz, WV_L u[3], int np,
                                 const WV_L dm[][3], WV_L du[][3]) {
  WV_L l2 = x * x + y * y + z * z;
  WV_M gone = l2 < 1e-24f;
  x = wv_sel(gone, WV_B(fx), x), y = wv_sel(gone, WV_B(fy), y), z = wv_sel(gone, WV_B(fz), z);
  l2 = wv_sel(gone, WV_B(1), l2);
  WV_L il = 1.0f / wv_sqrt(l2);
  u[0] = x * il, u[1] = y * il, u[2] = z * il;
  if (du)
    for (int p = 0; p < np; p++) {
      WV_FN(wv_dnormalize)(u, il, dm[p], du[p]);
      for (int i = 0; i < 3; i++) du[p][i] = wv_sel(gone, WV_B(0), du[p][i]);
    }
}

/* The frame at angles u (along the yarn) and v (around it), twist psi, after
 * scaling by the segment's bs; du and dbs: d u / d u_max and d bs / d beta. */
WV_INLINE void WV_FN(wv_yarn_bend)(WV_L u, WV_L du, WV_L v, WV_L bs, WV_L dbs, WV_R sp, WV_R cp,
                                   WV_FN(wv_yarn_frame) * f, WV_FN(wv_yarn_dframe) * df) {
  f->u = u, f->v = v, f->beta = bs;
  /* Bent cylinder along +y, before heightfield scaling. */
  WV_L su = wv_sin(u), cu = wv_cos(u), sv = wv_sin(v), cv = wv_cos(v);
  WV_L dsu = cu * du, dcu = -su * du; /* d(su = sin u), d(cu = cos u) per u_max (exact derivatives) */
  WV_L n0 = sv, n1 = su * cv, n2 = cu * cv;
  WV_L dn1_u = dsu * cv, dn2_u = dcu * cv; /* d(n1 = su cv), d(n2 = cu cv) / d u_max */
  WV_L t0 = -cv * sp, t1 = cu * cp + su * sv * sp, t2 = -su * cp + cu * sv * sp;
  WV_L dt1_u = dcu * cp + dsu * sv * sp, dt2_u = -dsu * cp + dcu * sv * sp; /* d(t1, t2) / d u_max */
  WV_L dt0_p = -cv * cp, dt1_p = -cu * sp + su * sv * cp, dt2_p = su * sp + cu * sv * cp; /* d(t0, t1, t2) / d psi */
  /* Heightfield scaling: n' = normalize(bs n_x, bs n_y, n_z), t' = normalize(t_x, t_y, bs t_z)
   * (SPEC's k = 1/beta rescaling of t, in a form without 0/0 at t_z = 0: docs/model.md). */
  WV_L nx = bs * n0, ny = bs * n1, nz = n2;
  WV_L dmn[2][3] = {{dbs * n0, dbs * n1, WV_B(0)}, /* d(nx = bs n0, ny = bs n1, nz = n2) / d beta */
                    {WV_B(0), bs * dn1_u, dn2_u}}; /*                                  / d u_max */
  /* yarn silhouette flattened completely: face up */
  WV_FN(wv_unit_or)(nx, ny, nz, 0, 0, 1, f->n, 2, dmn, df ? df->dn : NULL);
  WV_L tx = t0, ty = t1, tz = bs * t2;
  WV_L dmt[3][3] = {{WV_B(0), WV_B(0), dbs * t2},        /* d(tx = t0, ty = t1, tz = bs t2) / d beta */
                    {WV_B(0), dt1_u, bs * dt2_u},        /*                                / d u_max */
                    {dt0_p, dt1_p, bs * dt2_p}};         /*                                / d psi */
  /* fiber along z at beta 0: any in-plane tangent is valid */
  WV_FN(wv_unit_or)(tx, ty, tz, 0, 1, 0, f->t, 3, dmt, df ? df->dt : NULL);
}

/* The frame of the yarn in cell c: the segment's noise, the angles u and v, the bent cylinder. */
WV_INLINE void WV_FN(wv_yarn_shape)(const wv_yarn_model *m, const K_PARAMS *P, const WV_FN(wv_yarn_cell) * c,
                                    WV_FN(wv_yarn_frame) * f, WV_FN(wv_yarn_dframe) * df) {
  const WV_M warp = c->warp;
  /* Segment noise U_n: beta_s = max(0, beta (1 + 0.1 Q (2 xi - 1))), xi per segment. */
  WV_L bs = WV_FN(wv_pick)(warp, P->beta[WV_WARP], P->beta[WV_WEFT]);
  WV_L dbs = WV_B(1); /* d bs / d beta */
  if (m->noise_level > 0) {
    WV_L xi = WV_LP(wv_u01g(wv_mix64g(WV_FN(wv_yarn_segment)(m, c) ^ 0x5851f42d4c957f2dULL)));
    WV_L fn = 1.0f + P->noise * (2.0f * xi - 1.0f);
    bs = bs * fn;
    dbs = fn; /* d(bs = beta fn) */
    bs = wv_sel(bs > 0.0f, bs, WV_B(0));
    dbs = wv_sel(dbs > 0.0f, dbs, WV_B(0)); /* d(bs = max(0, bs)): fn >= 0, one-sided at beta = 0 */
  }
  /* u = l / (L spacing_along / 2) u_max, v = a / (w/2) pi/2, without divisions */
  WV_L l2 = WV_LP(c->l) * (2.0f * (1.0f / WV_LP(c->len)));
  WV_L u = l2 * WV_FN(wv_pick)(warp, P->uos[WV_WEFT], P->uos[WV_WARP]);
  WV_L du = l2 * WV_FN(wv_pick)(warp, P->ispc[WV_WEFT], P->ispc[WV_WARP]); /* d(u = l2 u_max / spacing) / d u_max */
  WV_L v = WV_LP(c->a) * WV_FN(wv_pick)(warp, P->vsc[WV_WARP], P->vsc[WV_WEFT]);
  WV_FN(wv_yarn_bend)(u, du, v, bs, dbs, P->sin_psi, P->cos_psi, f, df);
}

/* A direction in the fabric frame seen in the yarn's local frame: weft
 * (x, y, z) -> (-y, x, z). Dot products with it equal, bit for bit, those of
 * the frame turned into the fabric frame (the same two products are added
 * first, in the other order). */
WV_INLINE void WV_FN(wv_to_local)(WV_M warp, const WV_L w[3], WV_L out[3]) {
  out[0] = wv_sel(warp, w[0], -w[1]);
  out[1] = wv_sel(warp, w[1], w[0]);
  out[2] = w[2];
}
/* The other way: a local vector in the fabric frame, weft (x, y, z) -> (y, -x, z). */
WV_INLINE void WV_FN(wv_to_fabric)(WV_M warp, const WV_L v[3], WV_L out[3]) {
  WV_L v0 = v[0];
  out[0] = wv_sel(warp, v0, v[1]);
  out[1] = wv_sel(warp, v[1], -v0);
  out[2] = v[2];
}

/* ======================= BRDF: SGGX / SpongeCake ======================= */

/* SGGX projected area for fiber-like flakes around t, wt = w.t, k = 1 - alpha^2:
 * sigma(w) = sqrt(w_b^2 + w_n^2 + alpha^2 w_t^2) = sqrt(1 - (1 - alpha^2)(w.t)^2). */
WV_INLINE WV_L WV_FN(wv_sggx_sigma)(WV_L k, WV_L wt) {
  WV_L s2 = 1.0f - k * wt * wt;
  return wv_sqrt(wv_sel(s2 > 0.0f, s2, WV_B(0)));
}
/* SGGX flake normal density at unit h, ht = h.t:
 * D(h) = 1 / (pi alpha (h_b^2 + h_n^2 + h_t^2/alpha^2)^2) = 1 / (pi alpha q^2),
 * q = 1 + (1/alpha^2 - 1) ht^2; pia = pi alpha, ia2m1 = 1/alpha^2 - 1. */
WV_INLINE WV_L WV_FN(wv_sggx_q)(WV_L ia2m1, WV_L ht) { return 1.0f + ia2m1 * ht * ht; }
WV_INLINE WV_L WV_FN(wv_sggx_D)(WV_L pia, WV_L q) { return 1.0f / (pia * q * q); }

/* Partial derivatives of the specular factor. */
typedef struct {
  WV_L ti, to, th, alpha;
} WV_FN(wv_spec_partials);

/* SpongeCake single scattering times mu_i, without k_s, times the glint g:
 *   spec = g D(h) (1 - exp(-T A)) / (4 mu_o A),  A = sigma(wi) / mu_i + sigma(wo) / mu_o,
 * from ti = t.wi, to = t.wo, th = t.h (h the unit half vector), mi = mu_i > 0,
 * mo = mu_o > 0. Per type: k = 1 - alpha^2, ia2m1 = 1/alpha^2 - 1, pia = pi alpha,
 * ia = 1/alpha (for the derivative). Partials in S when non-NULL. */
WV_INLINE WV_L WV_FN(wv_spongecake)(WV_L ti, WV_L to, WV_L th, WV_L mi, WV_L mo, WV_L alpha, WV_L k, WV_L ia2m1,
                                    WV_L pia, WV_L ia, WV_R thickness, WV_L g, WV_FN(wv_spec_partials) * S) {
  /* (Partials nobody asks for are dropped by the compiler after inlining.) */
  WV_L si = WV_FN(wv_sggx_sigma)(k, ti), so = WV_FN(wv_sggx_sigma)(k, to);
  /* d(si = sqrt(1 - k ti^2)) = (-k ti dti + alpha ti^2 dalpha) / si, as k = 1 - alpha^2; 0 where si = 0 */
  WV_L isi = wv_sel(si > 0.0f, 1.0f / si, WV_B(0)), iso = wv_sel(so > 0.0f, 1.0f / so, WV_B(0));
  WV_L si_ti = -k * ti * isi, si_al = alpha * ti * ti * isi, so_to = -k * to * iso, so_al = alpha * to * to * iso;
  WV_L A = si / mi + so / mo;
  /* d(A = si / mi + so / mo) */
  WV_L A_ti = si_ti / mi, A_to = so_to / mo, A_al = si_al / mi + so_al / mo;
  WV_L q = WV_FN(wv_sggx_q)(ia2m1, th);
  /* d(q = 1 + (1/alpha^2 - 1) th^2) = 2 (1/alpha^2 - 1) th dth - 2 th^2 / alpha^3 dalpha */
  WV_L q_th = 2.0f * ia2m1 * th, q_al = -2.0f * th * th * ia * ia * ia;
  WV_L D = WV_FN(wv_sggx_D)(pia, q);
  /* d(D = 1 / (pi alpha q^2)) / D = -2 dq / q - dalpha / alpha */
  WV_L lD_q = -2.0f / q, lD_al = -ia;
  WV_L E = wv_exp(-thickness * A);
  /* d(E = exp(-T A)) / (1 - E) = -T E / (1 - E) dA; 0 where E = 1 (A = 0) */
  WV_L lE_A = wv_sel(E < 1.0f, -thickness * E / (1.0f - E), WV_B(0));
  WV_L spec = wv_sel(A > 0.0f, D * (1.0f - E) / (4.0f * mo * A), WV_B(0)) * g;
  /* d(spec = g D (1 - E) / (4 mo A)) = spec (dD / D - dE / (1 - E) - dA / A) */
  WV_L s_A = wv_sel(A > 0.0f, spec * (-lE_A - 1.0f / A), WV_B(0)), s_q = spec * lD_q;
  if (S) {
    S->ti = s_A * A_ti, S->to = s_A * A_to, S->th = s_q * q_th;
    S->alpha = s_A * A_al + s_q * q_al + spec * lD_al;
  }
  return spec;
}

/* Blended Lambert times mu_i, without k_d: (w max(0, ni) + (1 - w) mu_i) / pi,
 * ni = n.wi; with its partials d / d ni and d / d w when asked. */
WV_INLINE WV_L WV_FN(wv_diffuse)(WV_L ni, WV_L mi, WV_R blend, WV_L *d_ni, WV_L *d_blend) {
  const WV_R inv_pi = (WV_R)1 / (WV_R)3.14159265358979323846;
  WV_L nip = wv_sel(ni > 0.0f, ni, WV_B(0));
  WV_L diff = (blend * nip + (1.0f - blend) * mi) * inv_pi;
  /* d(diff = (w nip + (1 - w) mi) / pi), nip = max(0, ni): w / pi d ni where ni > 0, (nip - mi) / pi d w */
  if (d_ni) *d_ni = wv_sel(ni > 0.0f, WV_B(blend * inv_pi), WV_B(0));
  if (d_blend) *d_blend = (nip - mi) * inv_pi;
  return diff;
}

/* phi(y) = (1 - e^-y) / y and, when asked, phi'(y) = (e^-y (1 + y) - 1) / y^2, for
 * y >= 0: their Taylor series below 0.5 (where the closed forms cancel), which
 * stop below 1e-9 of the value there. */
WV_INLINE WV_L WV_FN(wv_phi)(WV_L y, WV_L *dphi) {
  const WV_R c2 = (WV_R)1 / 2, c3 = (WV_R)1 / 6, c4 = (WV_R)1 / 24, c5 = (WV_R)1 / 120, c6 = (WV_R)1 / 720,
             c7 = (WV_R)1 / 5040, c8 = (WV_R)1 / 40320, c9 = (WV_R)1 / 362880, c10 = (WV_R)1 / 3628800;
  WV_M small = y < 0.5f;
  WV_L yb = wv_sel(small, WV_B(1), y), ey = wv_exp(-yb);
  WV_L ps = 1.0f - y * (c2 - y * (c3 - y * (c4 - y * (c5 - y * (c6 - y * (c7 - y * (c8 - y * (c9 - y * c10))))))));
  /* d(phi = sum_k (-y)^k / (k + 1)!) = sum_k>=1 (-1)^k k y^(k-1) / (k + 1)! */
  if (dphi) {
    WV_L dps = -c2 + y * (2 * c3 - y * (3 * c4 - y * (4 * c5 - y * (5 * c6 - y * (6 * c7 - y * (7 * c8 -
               y * (8 * c9 - y * 9 * c10)))))));
    *dphi = wv_sel(small, dps, (ey * (1.0f + yb) - 1.0f) / (yb * yb));
  }
  return wv_sel(small, ps, (1.0f - ey) / yb);
}

/* SpongeCake single scattering through the slab (light entering its far side and
 * leaving toward the viewer; the transmission of Tang et al. 2024), times |mu_i|,
 * without k_s, times g, for a slab of optical thickness tl:
 *   spec_t = g D(h) E / (4 mo),  E = (e^(-tl b) - e^(-tl a)) / (a - b),
 *   a = sigma(wi) / |mu_i|, b = sigma(wo) / mu_o,
 * written E = tl e^(-tl m) phi(tl |a - b|), m = min(a, b): no cancellation, and
 * tl e^(-tl a) at a = b. ami = |mu_i|; the rest as wv_spongecake. */
WV_INLINE WV_L WV_FN(wv_spongecake_t)(WV_L ti, WV_L to, WV_L th, WV_L ami, WV_L mo, WV_L alpha, WV_L k, WV_L ia2m1,
                                      WV_L pia, WV_L ia, WV_L tl, WV_L g, WV_FN(wv_spec_partials) * S) {
  WV_L si = WV_FN(wv_sggx_sigma)(k, ti), so = WV_FN(wv_sggx_sigma)(k, to);
  /* d(si = sqrt(1 - k ti^2)) as in wv_spongecake */
  WV_L isi = wv_sel(si > 0.0f, 1.0f / si, WV_B(0)), iso = wv_sel(so > 0.0f, 1.0f / so, WV_B(0));
  WV_L si_ti = -k * ti * isi, si_al = alpha * ti * ti * isi, so_to = -k * to * iso, so_al = alpha * to * to * iso;
  WV_L a = si / ami, b = so / mo;
  /* d(a = si / |mu_i|), d(b = so / mo) */
  WV_L a_ti = si_ti / ami, a_al = si_al / ami, b_to = so_to / mo, b_al = so_al / mo;
  WV_M ab = a >= b;
  WV_L mn = wv_sel(ab, b, a), dl = wv_sel(ab, a - b, b - a);
  WV_L em = wv_exp(-tl * mn), dphi = WV_B(0);
  WV_L E = tl * em * WV_FN(wv_phi)(tl * dl, S ? &dphi : NULL);
  WV_L q = WV_FN(wv_sggx_q)(ia2m1, th);
  /* d(q = 1 + (1/alpha^2 - 1) th^2) as in wv_spongecake */
  WV_L q_th = 2.0f * ia2m1 * th, q_al = -2.0f * th * th * ia * ia * ia;
  WV_L D = WV_FN(wv_sggx_D)(pia, q);
  /* d(D = 1 / (pi alpha q^2)) / D = -2 dq / q - dalpha / alpha */
  WV_L lD_q = -2.0f / q, lD_al = -ia;
  WV_L K = g * D / (4.0f * mo);
  WV_L spec = K * E;
  if (S) {
    /* d(E = tl e^(-tl m) phi(tl |a - b|)): by the larger of a, b tl^2 e^(-tl m) phi',
     * by the smaller -tl E minus that */
    WV_L EL = tl * tl * em * dphi, ES = -tl * E - EL;
    WV_L E_a = wv_sel(ab, EL, ES), E_b = wv_sel(ab, ES, EL);
    /* d(spec = K E), K = g D / (4 mo) */
    S->ti = K * E_a * a_ti, S->to = K * E_b * b_to, S->th = spec * lD_q * q_th;
    S->alpha = K * (E_a * a_al + E_b * b_al) + spec * (lD_q * q_al + lD_al);
  }
  return spec;
}

/* ============================ the sample ============================ */

/* Light and view at the shaded points, fabric tangent frame (z = macro normal):
 * unit wi (to light), wo (to camera), h = normalize(wi + wo); mi = wi.z,
 * mo = wo.z (both > 0); light = I / r^2. */
typedef struct {
  WV_L wi[3], wo[3], h[3];
  WV_L mi, mo, light;
} WV_FN(wv_dirs);

WV_INLINE void WV_FN(wv_dirs_make)(const WV_L wi[3], const WV_L wo[3], WV_L light, WV_FN(wv_dirs) * d) {
  WV_L h[3], l2 = WV_B(0);
  for (int i = 0; i < 3; i++) {
    d->wi[i] = wi[i], d->wo[i] = wo[i];
    h[i] = wi[i] + wo[i];
    l2 += h[i] * h[i];
  }
  WV_L il = wv_sel(l2 > 0.0f, 1.0f / wv_sqrt(wv_sel(l2 > 0.0f, l2, WV_B(1))), WV_B(0));
  for (int i = 0; i < 3; i++) d->h[i] = h[i] * il;
  d->mi = wi[2], d->mo = wo[2], d->light = light;
}

/* Per lane, what the gradient renderer sums (already times the light): the
 * specular and diffuse factors radiance is linear in (radiance of channel c =
 * ks[type][c] S + kd[type][c] DF) and their derivatives with respect to the
 * non-linear parameters of the lane's yarn type (WV_J_* in kernel/kernel.h).
 * 0 in a gap. */
typedef struct {
  WV_M warp;
  WV_L J[WV_J_COUNT];
} WV_FN(wv_shade_grad);

/* Glint factor U_s = min(-ln xi, 10), xi hashed on a grid of 1/8 of the yarn spacing. */
WV_INLINE WV_L WV_FN(wv_glint)(const wv_fabric *fab, WV_P x, WV_P y) {
  if (!fab->glints) return WV_B(1);
  WV_U g = wv_hash2g(wv_tou64(wv_floori(x * fab->inv_glint_cell[0])), wv_tou64(wv_floori(y * fab->inv_glint_cell[1])),
                     fab->seed ^ 0x676c696eULL);
  return WV_LP(wv_gatherf(fab->glint_table, g >> 52));
}

#if WV_LANE == WV_LANE_8
WV_INLINE void wv_shade_lanewise_8(const wv_fabric *fab, const wv_shade_params_f *P, const wv_dirs_8 *d, wv_f8 x,
                                   wv_f8 y, wv_f8 rad[3], wv_shade_grad_8 *G, wv_f8 *open);
#endif

/* Light reflected by the yarn in cell c (the light in front: d->mi > 0): per
 * channel in rad (0 in an open gap). On the visible yarn its specular and diffuse
 * lobes; in a gap beside it, over the crossing yarn, that yarn's diffuse lobe with the
 * macro normal, k_d mu_i / pi (as the light through the cloth takes it there). With G,
 * also what the gradient sums, for the yarn type seen (G->warp). */
WV_INLINE void WV_FN(wv_shade_refl)(const wv_fabric *fab, const K_PARAMS *P, const WV_FN(wv_dirs) * d, WV_P x,
                                    WV_P y, const WV_FN(wv_yarn_cell) * c, WV_L rad[3], WV_FN(wv_shade_grad) * G) {
  const wv_yarn_model *m = &fab->ym;
  const WV_M over = wv_not(c->lit) & c->cov; /* beside the visible yarn, over the crossing one */
  const WV_M seen_warp = (c->lit & c->warp) | (over & wv_not(c->warp));
  if (G) {
    G->warp = seen_warp;
    for (int j = 0; j < WV_J_COUNT; j++) G->J[j] = WV_B(0);
  }
  for (int ch = 0; ch < 3; ch++) rad[ch] = WV_B(0);
  if (wv_any(over)) {
    WV_L under = WV_FN(wv_diffuse)(d->mi, d->mi, P->blend, NULL, NULL);
    for (int ch = 0; ch < 3; ch++) {
      WV_L kd = WV_FN(wv_pick)(seen_warp, P->kd[WV_WARP][ch], P->kd[WV_WEFT][ch]);
      rad[ch] = wv_sel(over, d->light * kd * under, WV_B(0));
    }
    if (G) G->J[WV_J_DF] = wv_sel(over, d->light * under, WV_B(0));
  }
  if (!wv_any(c->lit)) return;
  const WV_M warp = c->warp;
  WV_FN(wv_yarn_frame) f;
  WV_FN(wv_yarn_dframe) df;
  WV_FN(wv_yarn_shape)(m, P, c, &f, G ? &df : NULL);

  /* the directions in the yarn's frame */
  WV_L wi[3], wo[3], h[3];
  WV_FN(wv_to_local)(warp, d->wi, wi);
  WV_FN(wv_to_local)(warp, d->wo, wo);
  WV_FN(wv_to_local)(warp, d->h, h);
  WV_L ti = f.t[0] * wi[0] + f.t[1] * wi[1] + f.t[2] * wi[2];
  WV_L to = f.t[0] * wo[0] + f.t[1] * wo[1] + f.t[2] * wo[2];
  WV_L th = f.t[0] * h[0] + f.t[1] * h[1] + f.t[2] * h[2];
  WV_L ni = wi[0] * f.n[0] + wi[1] * f.n[1] + wi[2] * f.n[2];

  WV_L alpha = WV_FN(wv_pick)(warp, P->alpha[WV_WARP], P->alpha[WV_WEFT]);
  WV_L k = WV_FN(wv_pick)(warp, P->k[WV_WARP], P->k[WV_WEFT]);
  WV_L ia2m1 = WV_FN(wv_pick)(warp, P->ia2m1[WV_WARP], P->ia2m1[WV_WEFT]);
  WV_L pia = WV_FN(wv_pick)(warp, P->pia[WV_WARP], P->pia[WV_WEFT]);
  WV_L ia = WV_FN(wv_pick)(warp, P->ia[WV_WARP], P->ia[WV_WEFT]);
  WV_FN(wv_spec_partials) S;
  WV_L spec = WV_FN(wv_spongecake)(ti, to, th, d->mi, d->mo, alpha, k, ia2m1, pia, ia, P->thickness,
                                   WV_FN(wv_glint)(fab, x, y), G ? &S : NULL);
  WV_L diff_ni, diff_w;
  WV_L diff = WV_FN(wv_diffuse)(ni, d->mi, P->blend, G ? &diff_ni : NULL, G ? &diff_w : NULL);
  for (int ch = 0; ch < 3; ch++) {
    WV_L ks = WV_FN(wv_pick)(warp, P->ks[WV_WARP][ch], P->ks[WV_WEFT][ch]);
    WV_L kd = WV_FN(wv_pick)(warp, P->kd[WV_WARP][ch], P->kd[WV_WEFT][ch]);
    rad[ch] = wv_sel(c->lit, d->light * (ks * spec + kd * diff), rad[ch]);
  }
  if (!G) return;

  /* The chain rule: d(ti = t.wi) = dt.wi and so on, with the frame's tangents. */
  WV_L ds[3], dd[2];
  for (int p = 0; p < 3; p++) {
    const WV_L *dt = df.dt[p];
    WV_L dti = dt[0] * wi[0] + dt[1] * wi[1] + dt[2] * wi[2];
    WV_L dto = dt[0] * wo[0] + dt[1] * wo[1] + dt[2] * wo[2];
    WV_L dth = dt[0] * h[0] + dt[1] * h[1] + dt[2] * h[2];
    ds[p] = S.ti * dti + S.to * dto + S.th * dth; /* d spec */
  }
  for (int p = 0; p < 2; p++) {
    const WV_L *dn = df.dn[p];
    dd[p] = diff_ni * (wi[0] * dn[0] + wi[1] * dn[1] + wi[2] * dn[2]); /* d(diff) through d(ni = n.wi) */
  }
  WV_L J[WV_J_COUNT];
  J[WV_J_S] = spec, J[WV_J_DF] = diff;
  J[WV_J_S_BETA] = ds[WV_T_BETA], J[WV_J_S_ALPHA] = S.alpha, J[WV_J_S_UMAX] = ds[WV_T_UMAX];
  J[WV_J_S_PSI] = ds[WV_T_PSI], J[WV_J_DF_BETA] = dd[WV_T_BETA], J[WV_J_DF_UMAX] = dd[WV_T_UMAX];
  J[WV_J_DF_BLEND] = diff_w;
  J[WV_J_F] = WV_B(0); /* the forward band transmits only */
  for (int j = 0; j < WV_J_COUNT; j++) G->J[j] = wv_sel(c->lit, d->light * J[j], G->J[j]);
}

/* The cloth's local thickness at the point, in yarn diameters: the chord of the
 * visible yarn's circular cross-section (cos v, 0 in a gap beside it) in lv, and
 * of the crossing yarn's underneath in lh (0 where it does not cover the point).
 * Positions only: no continuous parameter moves them. */
WV_INLINE void WV_FN(wv_cloth_chords)(const K_PARAMS *P, const WV_FN(wv_yarn_cell) * c, WV_L *lv, WV_L *lh) {
  const WV_M warp = c->warp;
  WV_L v = WV_LP(c->a) * WV_FN(wv_pick)(warp, P->vsc[WV_WARP], P->vsc[WV_WEFT]);
  WV_L vh = WV_LP(c->a_h) * WV_FN(wv_pick)(warp, P->vsc[WV_WEFT], P->vsc[WV_WARP]);
  WV_L cv = wv_cos(v), ch = wv_cos(vh); /* |v|, |vh| <= pi/2 where used */
  *lv = wv_sel(c->lit & (cv > 0.0f), cv, WV_B(0));
  *lh = wv_sel(c->cov & (ch > 0.0f), ch, WV_B(0));
}

/* Light from behind the cloth (d->mi < 0) seen through it at the points of cell
 * c: per channel in rad, 1 in open where the line of sight crosses an open gap
 * (no yarn of either kind: the light itself is seen there, which the camera adds
 * as the scene's gap glow), and with G what the gradient sums: the same sums as
 * for reflection (J_S the specular transmission, J_DF the diffuse transmission)
 * for the yarn type the light passes (G->warp). On the visible yarn:
 *   k_st S_t + k_t F_t,  S_t = g D(h) E(T lv) / (4 mu_o) t(T lh),
 *   F_t = (w max(0, n_back.wi) + (1 - w) |mu_i|) / pi t(T (lv + lh)),
 * t(tau) = 1 / (1 + tau / 2) the diffuse transmittance of a slab of optical
 * thickness tau; in a gap beside it, over the crossing yarn: k_t F_t with the
 * macro normal. */
WV_INLINE void WV_FN(wv_shade_trans)(const wv_fabric *fab, const K_PARAMS *P, const WV_FN(wv_dirs) * d, WV_P x,
                                     WV_P y, const WV_FN(wv_yarn_cell) * c, WV_L rad[3], WV_L *open,
                                     WV_FN(wv_shade_grad) * G) {
  const wv_yarn_model *m = &fab->ym;
  const WV_M warp = c->warp, lit = c->lit;
  const WV_M tw = (lit & warp) | (wv_not(lit) & wv_not(warp)); /* the yarn the light passes is warp */
  const WV_M opn = WV_FN(wv_cell_open)(c);
  if (open) *open = wv_sel(opn, WV_B(1), WV_B(0));
  if (G) {
    G->warp = tw;
    for (int j = 0; j < WV_J_COUNT; j++) G->J[j] = WV_B(0);
  }
  for (int ch = 0; ch < 3; ch++) rad[ch] = WV_B(0);
  if (wv_all(opn)) return;
  WV_L lv, lh;
  WV_FN(wv_cloth_chords)(P, c, &lv, &lh);
  WV_L tl = P->thickness * lv, th_all = P->thickness * (lv + lh);
  WV_L Ah = WV_CLOTH_TRANSMITTANCE(P->thickness * lh), A = WV_CLOTH_TRANSMITTANCE(th_all);
  WV_L ami = -d->mi; /* |mu_i| */

  /* on the visible yarn: its frame, the specular transmission and the underside's normal */
  WV_L spec = WV_B(0), ni = ami; /* in a gap beside the visible yarn: the macro normal */
  WV_L ds[3] = {WV_B(0), WV_B(0), WV_B(0)}, dn_wi[2] = {WV_B(0), WV_B(0)}, s_al = WV_B(0);
  if (wv_any(lit)) {
    WV_FN(wv_yarn_frame) f;
    WV_FN(wv_yarn_dframe) df;
    WV_FN(wv_yarn_shape)(m, P, c, &f, G ? &df : NULL);
    WV_L wi[3], wo[3], h[3];
    WV_FN(wv_to_local)(warp, d->wi, wi);
    WV_FN(wv_to_local)(warp, d->wo, wo);
    WV_FN(wv_to_local)(warp, d->h, h);
    WV_L ti = f.t[0] * wi[0] + f.t[1] * wi[1] + f.t[2] * wi[2];
    WV_L to = f.t[0] * wo[0] + f.t[1] * wo[1] + f.t[2] * wo[2];
    WV_L th = f.t[0] * h[0] + f.t[1] * h[1] + f.t[2] * h[2];
    /* the yarn's underside, where the light enters: n_back = (n_x, -n_y, -n_z) in the yarn's frame */
    ni = wv_sel(lit, wi[0] * f.n[0] - wi[1] * f.n[1] - wi[2] * f.n[2], ami);
    WV_L alpha = WV_FN(wv_pick)(warp, P->alpha[WV_WARP], P->alpha[WV_WEFT]);
    WV_L k = WV_FN(wv_pick)(warp, P->k[WV_WARP], P->k[WV_WEFT]);
    WV_L ia2m1 = WV_FN(wv_pick)(warp, P->ia2m1[WV_WARP], P->ia2m1[WV_WEFT]);
    WV_L pia = WV_FN(wv_pick)(warp, P->pia[WV_WARP], P->pia[WV_WEFT]);
    WV_L ia = WV_FN(wv_pick)(warp, P->ia[WV_WARP], P->ia[WV_WEFT]);
    WV_FN(wv_spec_partials) S;
    spec = WV_FN(wv_spongecake_t)(ti, to, th, ami, d->mo, alpha, k, ia2m1, pia, ia, tl,
                                  WV_FN(wv_glint)(fab, x, y) * Ah, G ? &S : NULL);
    spec = wv_sel(lit, spec, WV_B(0));
    if (G) { /* the chain rule, as for reflection; the underside's normal through ni */
      for (int p = 0; p < 3; p++) {
        const WV_L *dt = df.dt[p];
        WV_L dti = dt[0] * wi[0] + dt[1] * wi[1] + dt[2] * wi[2];
        WV_L dto = dt[0] * wo[0] + dt[1] * wo[1] + dt[2] * wo[2];
        WV_L dth = dt[0] * h[0] + dt[1] * h[1] + dt[2] * h[2];
        ds[p] = wv_sel(lit, S.ti * dti + S.to * dto + S.th * dth, WV_B(0)); /* d spec */
      }
      for (int p = 0; p < 2; p++) { /* d(ni = wi.n_back) */
        const WV_L *dn = df.dn[p];
        dn_wi[p] = wv_sel(lit, wi[0] * dn[0] - wi[1] * dn[1] - wi[2] * dn[2], WV_B(0));
      }
      s_al = wv_sel(lit, S.alpha, WV_B(0));
    }
  }
  WV_L diff_ni = WV_B(0), diff_w = WV_B(0);
  WV_L diff = WV_FN(wv_diffuse)(ni, ami, P->blend, G ? &diff_ni : NULL, G ? &diff_w : NULL) * A;
  /* the forward band: light scattered on near the cone of directions that leave the yarn the
   * light passes at the angle to its axis they came in at, s = a.(omega_i + omega_o) / 2 = 0 with
   * a the yarn's axis in the plane (fabric y for warp, x for weft); after many scatterings
   * the light follows the yarn, not the tilt of the fibres at its surface (docs/model.md) */
  WV_L sf = 0.5f * wv_sel(tw, d->wi[1] + d->wo[1], d->wi[0] + d->wo[0]);
  WV_L fq = WV_B(1) + (sf * sf) * P->fw_k;
  WV_L fwd = (ami * A * P->fw_norm * WV_B(0.3183098861837907)) / (fq * fq);
  for (int ch = 0; ch < 3; ch++) {
    WV_L kst = WV_FN(wv_pick)(warp, P->kst[WV_WARP][ch], P->kst[WV_WEFT][ch]);
    WV_L kt = WV_FN(wv_pick)(tw, P->kt[WV_WARP][ch], P->kt[WV_WEFT][ch]);
    WV_L kf = WV_FN(wv_pick)(tw, P->kf[WV_WARP][ch], P->kf[WV_WEFT][ch]);
    rad[ch] = wv_sel(opn, WV_B(0), d->light * (kst * spec + kt * diff + kf * fwd));
  }
  if (!G) return;
  WV_L dd[2]; /* d(diff = diffuse(ni) A) */
  for (int p = 0; p < 2; p++) dd[p] = diff_ni * dn_wi[p] * A;
  WV_L J[WV_J_COUNT];
  J[WV_J_S] = spec, J[WV_J_DF] = diff;
  J[WV_J_S_BETA] = ds[WV_T_BETA], J[WV_J_S_ALPHA] = s_al, J[WV_J_S_UMAX] = ds[WV_T_UMAX];
  J[WV_J_S_PSI] = ds[WV_T_PSI], J[WV_J_DF_BETA] = dd[WV_T_BETA], J[WV_J_DF_UMAX] = dd[WV_T_UMAX];
  J[WV_J_DF_BLEND] = diff_w * A;
  J[WV_J_F] = fwd;
  for (int j = 0; j < WV_J_COUNT; j++) G->J[j] = wv_sel(opn, WV_B(0), d->light * J[j]);
}

/* Radiance of the points (x, y) mm under the light and view d: per channel in
 * rad (0 in a gap), reflected where the light is in front (d->mi > 0) and
 * transmitted where it is behind (d->mi < 0). With G, also what the gradient
 * sums; with open, 1 where the line of sight crosses an open gap with the light
 * behind (else 0). */
WV_INLINE void WV_FN(wv_shade_ex)(const wv_fabric *fab, const K_PARAMS *P, const WV_FN(wv_dirs) * d, WV_P x, WV_P y,
                                  WV_L rad[3], WV_FN(wv_shade_grad) * G, WV_L *open) {
  const wv_yarn_model *m = &fab->ym;
  WV_FN(wv_yarn_cell) c;
  WV_FN(wv_yarn_locate)(m, x, y, &c);
#if WV_LANE == WV_LANE_8
  if (!wv_all(c.ok)) { /* beyond 32-bit cell indices: lane by lane in scalar float */
    wv_shade_lanewise_8(fab, P, d, x, y, rad, G, open);
    return;
  }
#endif
  const WV_M back = d->mi < 0.0f;
  if (!wv_any(back)) {
    if (open) *open = WV_B(0);
    WV_FN(wv_shade_refl)(fab, P, d, x, y, &c, rad, G);
    return;
  }
  WV_FN(wv_shade_trans)(fab, P, d, x, y, &c, rad, open, G);
  if (wv_all(back)) return;
  /* light in front of some points and behind others: each lane takes its side */
  WV_L rr[3];
  WV_FN(wv_shade_grad) GR;
  WV_FN(wv_shade_refl)(fab, P, d, x, y, &c, rr, G ? &GR : NULL);
  for (int ch = 0; ch < 3; ch++) rad[ch] = wv_sel(back, rad[ch], rr[ch]);
  if (open) *open = wv_sel(back, *open, WV_B(0));
  if (G) {
    G->warp = wv_seli(back, G->warp, GR.warp);
    for (int j = 0; j < WV_J_COUNT; j++) G->J[j] = wv_sel(back, G->J[j], GR.J[j]);
  }
}

/* wv_shade_ex without the open gaps. */
WV_INLINE void WV_FN(wv_shade)(const wv_fabric *fab, const K_PARAMS *P, const WV_FN(wv_dirs) * d, WV_P x, WV_P y,
                               WV_L rad[3], WV_FN(wv_shade_grad) * G) {
  WV_FN(wv_shade_ex)(fab, P, d, x, y, rad, G, NULL);
}

#if WV_LANE == WV_LANE_8
/* wv_shade_8 one lane at a time with the scalar float kernel (64-bit cells). */
WV_INLINE void wv_shade_lanewise_8(const wv_fabric *fab, const wv_shade_params_f *P, const wv_dirs_8 *d, wv_f8 x,
                                   wv_f8 y, wv_f8 rad[3], wv_shade_grad_8 *G, wv_f8 *open) {
  for (int i = 0; i < WV_LANES; i++) {
    wv_dirs_f di;
    for (int k = 0; k < 3; k++) di.wi[k] = d->wi[k][i], di.wo[k] = d->wo[k][i], di.h[k] = d->h[k][i];
    di.mi = d->mi[i], di.mo = d->mo[i], di.light = d->light[i];
    float r[3], o;
    wv_shade_grad_f g;
    wv_shade_ex_f(fab, P, &di, x[i], y[i], r, G ? &g : NULL, &o);
    for (int k = 0; k < 3; k++) rad[k][i] = r[k];
    if (open) (*open)[i] = o;
    if (G) {
      G->warp[i] = g.warp ? -1 : 0;
      for (int j = 0; j < WV_J_COUNT; j++) G->J[j][i] = g.J[j];
    }
  }
}
#endif

#undef K_PARAMS
