/* Triangle meshes for the glTF export and the viewer: a flat quad, a sheet
 * draped procedurally over a sphere, tangents from UVs, and the checks a mesh
 * must pass before it is written. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "woven/export.h"

#define PI_D 3.14159265358979323846

void wv_tri_mesh_free(wv_tri_mesh *m) {
  if (!m) return;
  free(m->positions), free(m->normals), free(m->uvs), free(m->tangents), free(m->indices);
  memset(m, 0, sizeof *m);
}

static wv_status mesh_alloc(wv_tri_mesh *m, int nv, int ni, wv_error *err) {
  memset(m, 0, sizeof *m);
  m->vertex_count = nv, m->index_count = ni;
  m->positions = malloc(sizeof(float) * 3 * (size_t)nv);
  m->normals = malloc(sizeof(float) * 3 * (size_t)nv);
  m->uvs = malloc(sizeof(float) * 2 * (size_t)nv);
  m->tangents = malloc(sizeof(float) * 4 * (size_t)nv);
  m->indices = malloc(sizeof(uint32_t) * (size_t)ni);
  if (!m->positions || !m->normals || !m->uvs || !m->tangents || !m->indices) {
    wv_tri_mesh_free(m);
    return wv_fail(err, WV_ERR_NOMEM, "out of memory for a mesh of %d vertices", nv);
  }
  return WV_OK;
}

static int size_ok(double mm) { return isfinite(mm) && mm >= 0.1 && mm <= 1e5; }

/* Two triangles per grid cell, counter-clockwise seen from the normal's side
 * (vertex (i, j) at index j (n + 1) + i, i along u, j along v). */
static void grid_indices(int n, uint32_t *idx) {
  size_t k = 0;
  for (int j = 0; j < n; j++)
    for (int i = 0; i < n; i++) {
      uint32_t a = (uint32_t)(j * (n + 1) + i), b = a + 1, c = a + (uint32_t)(n + 1), d = c + 1;
      idx[k++] = a, idx[k++] = c, idx[k++] = b;
      idx[k++] = b, idx[k++] = c, idx[k++] = d;
    }
}

wv_status wv_tri_mesh_quad(double side_mm, wv_tri_mesh *m, wv_error *err) {
  memset(m, 0, sizeof *m);
  if (!size_ok(side_mm)) return wv_fail(err, WV_ERR_INVALID, "quad side %g mm is outside 0.1..100000", side_mm);
  wv_status st = mesh_alloc(m, 4, 6, err);
  if (st) return st;
  float h = (float)(side_mm / 2000.0); /* half side in metres */
  for (int v = 0; v < 4; v++) {
    int i = v & 1, j = v >> 1;
    float *p = m->positions + 3 * v, *n = m->normals + 3 * v, *t = m->tangents + 4 * v, *uv = m->uvs + 2 * v;
    p[0] = i ? h : -h, p[1] = 0, p[2] = j ? h : -h;
    n[0] = 0, n[1] = 1, n[2] = 0;
    t[0] = 1, t[1] = 0, t[2] = 0, t[3] = 1;
    uv[0] = (float)i, uv[1] = (float)j;
  }
  grid_indices(1, m->indices);
  m->uv_mm = side_mm;
  return WV_OK;
}

/* Height and horizontal radius of the hanging part, s mm past the contact
 * circle: the direction turns from the sphere's tangent (theta0 below the
 * horizontal) toward vertical over a length L, integrated by the midpoint rule. */
static void hang(double R, double theta0, double s, double *q, double *y) {
  const double L = 0.35 * R;
  int steps = 1 + (int)(s / (0.01 * R));
  double ds = s / steps, qq = R * sin(theta0), yy = R * cos(theta0);
  for (int k = 0; k < steps; k++) {
    double b = 0.5 * PI_D - (0.5 * PI_D - theta0) * exp(-(k + 0.5) * ds / L);
    qq += ds * cos(b), yy -= ds * sin(b);
  }
  *q = qq, *y = yy;
}

wv_status wv_tri_mesh_drape(double side_mm, double radius_mm, int n, wv_tri_mesh *m, wv_error *err) {
  memset(m, 0, sizeof *m);
  if (!size_ok(side_mm)) return wv_fail(err, WV_ERR_INVALID, "sheet side %g mm is outside 0.1..100000", side_mm);
  if (!size_ok(radius_mm)) return wv_fail(err, WV_ERR_INVALID, "sphere radius %g mm is outside 0.1..100000", radius_mm);
  if (n < 2 || n > 1024) return wv_fail(err, WV_ERR_INVALID, "sheet resolution %d is outside 2..1024", n);
  int nv = (n + 1) * (n + 1);
  wv_status st = mesh_alloc(m, nv, 6 * n * n, err);
  if (st) return st;
  const double R = radius_mm, theta0 = 50.0 * PI_D / 180.0, s0 = R * theta0;
  const int folds = 7;
  for (int j = 0; j <= n; j++)
    for (int i = 0; i <= n; i++) {
      double u = (double)i / n, v = (double)j / n;
      double X = (u - 0.5) * side_mm, Z = (v - 0.5) * side_mm; /* flat sheet, mm */
      double rho = sqrt(X * X + Z * Z), phi = atan2(Z, X), q, y;
      if (rho <= s0) { /* on the cap: arc length rho along the meridian */
        q = R * sin(rho / R), y = R * cos(rho / R);
      } else {
        hang(R, theta0, rho - s0, &q, &y);
        q += 0.12 * (rho - q) * sin(folds * phi); /* folds take up the spare circumference */
      }
      float *p = m->positions + 3 * (j * (n + 1) + i), *uv = m->uvs + 2 * (j * (n + 1) + i);
      p[0] = (float)(q * cos(phi) / 1000.0), p[1] = (float)(y / 1000.0), p[2] = (float)(q * sin(phi) / 1000.0);
      uv[0] = (float)u, uv[1] = (float)v;
    }
  /* Normals and tangents from the grid's differences (one-sided at the border). */
  for (int j = 0; j <= n; j++)
    for (int i = 0; i <= n; i++) {
      int i0 = i > 0 ? i - 1 : i, i1 = i < n ? i + 1 : i, j0 = j > 0 ? j - 1 : j, j1 = j < n ? j + 1 : j;
      const float *pa = m->positions + 3 * (j * (n + 1) + i0), *pb = m->positions + 3 * (j * (n + 1) + i1);
      const float *pc = m->positions + 3 * (j0 * (n + 1) + i), *pd = m->positions + 3 * (j1 * (n + 1) + i);
      double du[3], dv[3], N[3], T[3];
      for (int k = 0; k < 3; k++) du[k] = pb[k] - pa[k], dv[k] = pd[k] - pc[k];
      N[0] = dv[1] * du[2] - dv[2] * du[1], N[1] = dv[2] * du[0] - dv[0] * du[2], N[2] = dv[0] * du[1] - dv[1] * du[0];
      double ln = sqrt(N[0] * N[0] + N[1] * N[1] + N[2] * N[2]);
      if (!(ln > 0)) N[0] = 0, N[1] = 1, N[2] = 0, ln = 1;
      for (int k = 0; k < 3; k++) N[k] /= ln;
      double d = du[0] * N[0] + du[1] * N[1] + du[2] * N[2];
      for (int k = 0; k < 3; k++) T[k] = du[k] - d * N[k];
      double lt = sqrt(T[0] * T[0] + T[1] * T[1] + T[2] * T[2]);
      if (!(lt > 0)) T[0] = 1, T[1] = 0, T[2] = 0, lt = 1;
      float *nn = m->normals + 3 * (j * (n + 1) + i), *tt = m->tangents + 4 * (j * (n + 1) + i);
      for (int k = 0; k < 3; k++) nn[k] = (float)N[k], tt[k] = (float)(T[k] / lt);
      /* glTF's bitangent cross(N, T) w points up the texture, along -dP/dv */
      double B[3] = {N[1] * T[2] - N[2] * T[1], N[2] * T[0] - N[0] * T[2], N[0] * T[1] - N[1] * T[0]};
      tt[3] = B[0] * dv[0] + B[1] * dv[1] + B[2] * dv[2] > 0 ? -1.0f : 1.0f;
    }
  grid_indices(n, m->indices);
  m->uv_mm = side_mm;
  return WV_OK;
}

wv_status wv_tri_mesh_tangents(wv_tri_mesh *m, wv_error *err) {
  size_t nv = (size_t)m->vertex_count;
  double *acc = calloc(nv * 6, sizeof(double)); /* dP/du and dP/dv per vertex */
  float *t = m->tangents ? m->tangents : malloc(sizeof(float) * 4 * nv);
  if (!acc || !t) {
    free(acc);
    if (t != m->tangents) free(t);
    return wv_fail(err, WV_ERR_NOMEM, "out of memory for the tangents of %zu vertices", nv);
  }
  for (int k = 0; k + 2 < m->index_count; k += 3) {
    const uint32_t *f = m->indices + k;
    const float *p0 = m->positions + 3 * f[0], *p1 = m->positions + 3 * f[1], *p2 = m->positions + 3 * f[2];
    const float *w0 = m->uvs + 2 * f[0], *w1 = m->uvs + 2 * f[1], *w2 = m->uvs + 2 * f[2];
    double du1 = w1[0] - w0[0], dv1 = w1[1] - w0[1], du2 = w2[0] - w0[0], dv2 = w2[1] - w0[1];
    double det = du1 * dv2 - du2 * dv1;
    if (fabs(det) < 1e-20) continue; /* no UV area: no direction to learn */
    double r = 1.0 / det;
    for (int c = 0; c < 3; c++) {
      double e1 = p1[c] - p0[c], e2 = p2[c] - p0[c];
      double su = (e1 * dv2 - e2 * dv1) * r, sv = (e2 * du1 - e1 * du2) * r;
      for (int q = 0; q < 3; q++) acc[6 * f[q] + c] += su, acc[6 * f[q] + 3 + c] += sv;
    }
  }
  for (size_t v = 0; v < nv; v++) {
    const float *N = m->normals + 3 * v;
    double *su = acc + 6 * v, *sv = su + 3;
    double d = su[0] * N[0] + su[1] * N[1] + su[2] * N[2], T[3];
    for (int c = 0; c < 3; c++) T[c] = su[c] - d * N[c];
    double l = sqrt(T[0] * T[0] + T[1] * T[1] + T[2] * T[2]);
    if (!(l > 1e-20)) { /* any direction in the tangent plane */
      double a[3] = {fabs(N[0]) < 0.9 ? 1.0 : 0.0, fabs(N[0]) < 0.9 ? 0.0 : 1.0, 0.0};
      d = a[0] * N[0] + a[1] * N[1];
      for (int c = 0; c < 3; c++) T[c] = a[c] - d * N[c];
      l = sqrt(T[0] * T[0] + T[1] * T[1] + T[2] * T[2]);
    }
    double B[3] = {N[1] * T[2] - N[2] * T[1], N[2] * T[0] - N[0] * T[2], N[0] * T[1] - N[1] * T[0]};
    for (int c = 0; c < 3; c++) t[4 * v + c] = (float)(T[c] / l);
    t[4 * v + 3] = B[0] * sv[0] + B[1] * sv[1] + B[2] * sv[2] > 0 ? -1.0f : 1.0f;
  }
  free(acc);
  m->tangents = t;
  return WV_OK;
}

wv_status wv_tri_mesh_validate(const wv_tri_mesh *m, wv_error *err) {
  if (m->vertex_count < 3 || m->index_count < 3 || m->index_count % 3)
    return wv_fail(err, WV_ERR_INVALID, "mesh: %d vertices and %d indices do not make triangles", m->vertex_count,
                   m->index_count);
  if (!m->positions || !m->normals || !m->uvs || !m->indices)
    return wv_fail(err, WV_ERR_INVALID, "mesh: positions, normals, UVs and indices are all required");
  if (!(m->uv_mm > 0 && isfinite(m->uv_mm)))
    return wv_fail(err, WV_ERR_INVALID, "mesh: the UV scale %g mm per unit is not positive", m->uv_mm);
  for (int k = 0; k < m->index_count; k++)
    if (m->indices[k] >= (uint32_t)m->vertex_count)
      return wv_fail(err, WV_ERR_INVALID, "mesh: index %d refers to vertex %u of %d", k, m->indices[k],
                     m->vertex_count);
  for (int v = 0; v < m->vertex_count; v++) {
    const float *p = m->positions + 3 * v, *n = m->normals + 3 * v, *uv = m->uvs + 2 * v;
    int ok = isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]) && isfinite(uv[0]) && isfinite(uv[1]);
    double l = (double)n[0] * n[0] + (double)n[1] * n[1] + (double)n[2] * n[2];
    if (!ok || !(fabs(l - 1.0) < 1e-3))
      return wv_fail(err, WV_ERR_INVALID, "mesh: vertex %d has a non-finite value or a normal that is not unit", v);
    if (m->tangents && !(isfinite(m->tangents[4 * v]) && fabsf(m->tangents[4 * v + 3]) == 1.0f))
      return wv_fail(err, WV_ERR_INVALID, "mesh: vertex %d has an invalid tangent", v);
  }
  return WV_OK;
}
