/* What a shape returns for a ray (a lane template, see kernel/lanes.h and
 * shape/shape.h). */
typedef struct {
  WV_M hit;            /* the ray meets the shape in front of the camera */
  WV_P p[3];           /* the point, scene units */
  WV_P n[3], t[3], b[3]; /* normal, and the fabric's x and y directions there (unit) */
  WV_P fx, fy;         /* fabric coordinates, mm */
} WV_FN(wv_surface);
