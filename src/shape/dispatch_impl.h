/* The shape of the scene, by type (a lane template, see shape/shape.h). */
WV_INLINE void WV_FN(wv_shape_hit)(const wv_shape *sh, const float o[3], const WV_P d[3], WV_FN(wv_surface) * s) {
  switch (sh->type) {
    case WV_SHAPE_CYLINDER: WV_FN(wv_cylinder_hit)(sh, o, d, s); break;
    default: WV_FN(wv_plane_hit)(sh, o, d, s); break;
  }
}
