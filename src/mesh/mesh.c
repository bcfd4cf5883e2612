/* Triangle meshes: assimp import (C API), validation, tangent frames from UVs,
 * transforms, built-in shapes and the OBJ writer. Owns wv_mesh (woven/mesh.h). */
#include "woven/mesh.h"

#include <assimp/cimport.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "woven/io.h"

#define PI 3.14159265358979323846

size_t wv_mesh_bytes(long long nv, long long nt) {
  if (nv < 0 || nt < 0) return (size_t)-1;
  return (size_t)nv * (3 + 3 + 2 + 4) * sizeof(float) + (size_t)nt * (3 * sizeof(uint32_t) + 96);
}

void wv_mesh_free(wv_mesh *m) {
  if (!m) return;
  free(m->pos), free(m->nrm), free(m->uv), free(m->tan), free(m->idx);
  memset(m, 0, sizeof *m);
}

wv_status wv_mesh_alloc(wv_mesh *m, int nv, int nt, int with_uv, size_t limit, wv_error *err) {
  memset(m, 0, sizeof *m);
  if (nv < 3 || nt < 1) return wv_fail(err, WV_ERR_INVALID, "a mesh needs at least one triangle");
  if (!limit) limit = (size_t)WV_MESH_DEFAULT_LIMIT_MB << 20;
  size_t need = wv_mesh_bytes(nv, nt);
  if (need > limit)
    return wv_fail(err, WV_ERR_NOMEM, "%d vertices and %d triangles need %zu MB, above the memory limit of %zu MB", nv,
                   nt, need >> 20, limit >> 20);
  m->pos = calloc((size_t)nv * 3, sizeof(float));
  m->nrm = calloc((size_t)nv * 3, sizeof(float));
  m->uv = with_uv ? calloc((size_t)nv * 2, sizeof(float)) : NULL;
  m->idx = calloc((size_t)nt * 3, sizeof(uint32_t));
  if (!m->pos || !m->nrm || (with_uv && !m->uv) || !m->idx) {
    wv_mesh_free(m);
    return wv_fail(err, WV_ERR_NOMEM, "out of memory for a mesh of %d vertices", nv);
  }
  m->nv = nv, m->nt = nt;
  return WV_OK;
}

static void sub3(const float *a, const float *b, double o[3]) {
  for (int i = 0; i < 3; i++) o[i] = (double)a[i] - b[i];
}
static void cross3(const double a[3], const double b[3], double o[3]) {
  o[0] = a[1] * b[2] - a[2] * b[1], o[1] = a[2] * b[0] - a[0] * b[2], o[2] = a[0] * b[1] - a[1] * b[0];
}
static double dot3d(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

wv_status wv_mesh_validate(const wv_mesh *m, const char *name, int need_uv, wv_error *err) {
  if (m->nv < 3 || m->nt < 1) return wv_fail(err, WV_ERR_FORMAT, "%s: the mesh has no triangles", name);
  if (need_uv && !m->uv)
    return wv_fail(err, WV_ERR_FORMAT, "%s: the mesh has no UV coordinates (a fabric needs them for its weave)", name);
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (int v = 0; v < m->nv; v++) {
    for (int i = 0; i < 3; i++) {
      float p = m->pos[3 * v + i], n = m->nrm[3 * v + i];
      if (!isfinite(p) || !isfinite(n))
        return wv_fail(err, WV_ERR_FORMAT, "%s: vertex %d has a NaN or infinite position or normal", name, v);
      if (fabsf(p) > WV_MESH_MAX_COORD)
        return wv_fail(err, WV_ERR_FORMAT, "%s: vertex %d has a coordinate of %g mm, outside -%g..%g", name, v, p,
                       WV_MESH_MAX_COORD, WV_MESH_MAX_COORD);
      if (p < lo[i]) lo[i] = p;
      if (p > hi[i]) hi[i] = p;
    }
    if (m->uv && (!isfinite(m->uv[2 * v]) || !isfinite(m->uv[2 * v + 1])))
      return wv_fail(err, WV_ERR_FORMAT, "%s: vertex %d has a NaN or infinite UV", name, v);
    if (m->uv && (fabsf(m->uv[2 * v]) > WV_MESH_MAX_UV || fabsf(m->uv[2 * v + 1]) > WV_MESH_MAX_UV))
      return wv_fail(err, WV_ERR_FORMAT, "%s: vertex %d has a UV of (%g, %g), outside -%g..%g", name, v,
                     m->uv[2 * v], m->uv[2 * v + 1], WV_MESH_MAX_UV, WV_MESH_MAX_UV);
  }
  double diag2 = 0;
  for (int i = 0; i < 3; i++) diag2 += (hi[i] - lo[i]) * (hi[i] - lo[i]);
  for (int t = 0; t < m->nt; t++) {
    const uint32_t *ix = m->idx + 3 * t;
    for (int k = 0; k < 3; k++)
      if (ix[k] >= (uint32_t)m->nv)
        return wv_fail(err, WV_ERR_FORMAT, "%s: triangle %d refers to vertex %u of %d", name, t, ix[k], m->nv);
    double e1[3], e2[3], c[3];
    sub3(m->pos + 3 * ix[1], m->pos + 3 * ix[0], e1);
    sub3(m->pos + 3 * ix[2], m->pos + 3 * ix[0], e2);
    cross3(e1, e2, c);
    /* zero area up to float rounding of the coordinates, relative to the mesh's size */
    if (!(sqrt(dot3d(c, c)) > 1e-12 * diag2))
      return wv_fail(err, WV_ERR_FORMAT, "%s: triangle %d (vertices %u %u %u) is degenerate (zero area)", name, t,
                     ix[0], ix[1], ix[2]);
    if (need_uv) {
      const float *a = m->uv + 2 * ix[0], *b = m->uv + 2 * ix[1], *d = m->uv + 2 * ix[2];
      double det = ((double)b[0] - a[0]) * ((double)d[1] - a[1]) - ((double)d[0] - a[0]) * ((double)b[1] - a[1]);
      double s = fabs(b[0] - a[0]) + fabs(b[1] - a[1]) + fabs(d[0] - a[0]) + fabs(d[1] - a[1]);
      if (!(fabs(det) > 1e-9 * s * s))
        return wv_fail(err, WV_ERR_FORMAT,
                       "%s: triangle %d has degenerate UVs (zero UV area): no tangent frame for the weave", name, t);
    }
  }
  return WV_OK;
}

/* Some unit vector orthogonal to n. */
static void any_perp(const double n[3], double t[3]) {
  double a[3] = {1, 0, 0};
  if (fabs(n[0]) > 0.9) a[0] = 0, a[1] = 1;
  double d = dot3d(a, n);
  for (int i = 0; i < 3; i++) t[i] = a[i] - d * n[i];
  double l = sqrt(dot3d(t, t));
  for (int i = 0; i < 3; i++) t[i] /= l;
}

wv_status wv_mesh_tangents(wv_mesh *m, const char *name, wv_error *err) {
  if (!m->uv) return wv_fail(err, WV_ERR_FORMAT, "%s: the mesh has no UV coordinates", name);
  double *acc = calloc((size_t)m->nv * 6, sizeof(double)); /* sum of dP/du, dP/dv */
  float *tan = malloc((size_t)m->nv * 4 * sizeof(float));
  if (!acc || !tan) {
    free(acc), free(tan);
    return wv_fail(err, WV_ERR_NOMEM, "%s: out of memory for tangents", name);
  }
  for (int t = 0; t < m->nt; t++) {
    const uint32_t *ix = m->idx + 3 * t;
    double e1[3], e2[3];
    sub3(m->pos + 3 * ix[1], m->pos + 3 * ix[0], e1);
    sub3(m->pos + 3 * ix[2], m->pos + 3 * ix[0], e2);
    const float *a = m->uv + 2 * ix[0], *b = m->uv + 2 * ix[1], *c = m->uv + 2 * ix[2];
    double du1 = (double)b[0] - a[0], dv1 = (double)b[1] - a[1], du2 = (double)c[0] - a[0], dv2 = (double)c[1] - a[1];
    double det = du1 * dv2 - du2 * dv1;
    if (det == 0.0) continue;
    /* dP/du and dP/dv of the triangle's linear map, weighted by its UV area (|det|). */
    double s = det > 0 ? 1.0 : -1.0;
    for (int k = 0; k < 3; k++)
      for (int i = 0; i < 3; i++) {
        acc[6 * ix[k] + i] += s * (e1[i] * dv2 - e2[i] * dv1);
        acc[6 * ix[k] + 3 + i] += s * (e2[i] * du1 - e1[i] * du2);
      }
  }
  for (int v = 0; v < m->nv; v++) {
    double n[3] = {m->nrm[3 * v], m->nrm[3 * v + 1], m->nrm[3 * v + 2]}, t[3], *du = acc + 6 * v, *dv = du + 3;
    double d = dot3d(du, n);
    for (int i = 0; i < 3; i++) t[i] = du[i] - d * n[i];
    double l = sqrt(dot3d(t, t));
    if (!(l > 1e-20)) any_perp(n, t); /* u direction undefined here (opposite UV flows cancel) */
    else
      for (int i = 0; i < 3; i++) t[i] /= l;
    double b[3];
    cross3(n, t, b);
    for (int i = 0; i < 3; i++) tan[4 * v + i] = (float)t[i];
    tan[4 * v + 3] = dot3d(b, dv) < 0 ? -1.0f : 1.0f;
  }
  free(acc);
  free(m->tan);
  m->tan = tan;
  return WV_OK;
}

wv_status wv_mesh_transform(wv_mesh *m, const double A[9], const double b[3], wv_error *err) {
  /* cofactor matrix = det * inverse transpose: maps normals, up to a scale removed below */
  double C[9] = {A[4] * A[8] - A[5] * A[7], A[5] * A[6] - A[3] * A[8], A[3] * A[7] - A[4] * A[6],
                 A[2] * A[7] - A[1] * A[8], A[0] * A[8] - A[2] * A[6], A[1] * A[6] - A[0] * A[7],
                 A[1] * A[5] - A[2] * A[4], A[2] * A[3] - A[0] * A[5], A[0] * A[4] - A[1] * A[3]};
  double det = A[0] * C[0] + A[1] * C[1] + A[2] * C[2];
  if (!(fabs(det) > 1e-12) || !isfinite(det)) return wv_fail(err, WV_ERR_INVALID, "the transform is singular");
  double sg = det > 0 ? 1.0 : -1.0;
  for (int v = 0; v < m->nv; v++) {
    float *p = m->pos + 3 * v, *n = m->nrm + 3 * v;
    double q[3], r[3], l = 0;
    for (int i = 0; i < 3; i++) {
      q[i] = A[3 * i] * p[0] + A[3 * i + 1] * p[1] + A[3 * i + 2] * p[2] + b[i];
      r[i] = sg * (C[3 * i] * n[0] + C[3 * i + 1] * n[1] + C[3 * i + 2] * n[2]);
      l += r[i] * r[i];
    }
    l = l > 0 ? 1.0 / sqrt(l) : 0.0;
    for (int i = 0; i < 3; i++) p[i] = (float)q[i], n[i] = (float)(r[i] * l);
  }
  if (det < 0) /* a mirror turns the winding around */
    for (int t = 0; t < m->nt; t++) {
      uint32_t x = m->idx[3 * t + 1];
      m->idx[3 * t + 1] = m->idx[3 * t + 2], m->idx[3 * t + 2] = x;
    }
  free(m->tan);
  m->tan = NULL;
  return WV_OK;
}

/* assimp's message, which may quote the file: printable characters only, cut short. */
static const char *ai_error(char *buf, size_t len) {
  wv_printable_excerpt(aiGetErrorString(), buf, len);
  return buf;
}

wv_status wv_mesh_load(const char *path, size_t limit, int need_uv, wv_mesh *m, wv_error *err) {
  memset(m, 0, sizeof *m);
  if (!limit) limit = (size_t)WV_MESH_DEFAULT_LIMIT_MB << 20;
  wv_status cs = wv_mesh_check_file(path, limit, err);
  if (cs) return cs;
  unsigned flags = aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_GenSmoothNormals |
                   aiProcess_PreTransformVertices | aiProcess_SortByPType | aiProcess_ValidateDataStructure;
  /* The faces are checked on a first reading without post-processing: assimp's
   * post-processing steps trust the readers' vertex indices and abort on some out of
   * range (and a failed aiApplyPostProcessing frees its scene twice, so the file is
   * simply read again with the steps). */
  char why[128];
  const struct aiScene *sc = aiImportFile(path, 0);
  if (!sc) return wv_fail(err, WV_ERR_FORMAT, "%s: not a readable mesh: %s", path, ai_error(why, sizeof why));
  for (unsigned i = 0; i < sc->mNumMeshes; i++) {
    const struct aiMesh *am = sc->mMeshes[i];
    for (unsigned f = 0; f < am->mNumFaces; f++) {
      const struct aiFace *fa = &am->mFaces[f];
      int bad = fa->mNumIndices == 0 || !fa->mIndices;
      for (unsigned k = 0; !bad && k < fa->mNumIndices; k++) bad = fa->mIndices[k] >= am->mNumVertices;
      if (bad) {
        unsigned nv0 = am->mNumVertices;
        aiReleaseImport(sc);
        return wv_fail(err, WV_ERR_FORMAT, "%s: face %u of mesh %u refers to a vertex it does not have (%u vertices)",
                       path, f, i, nv0);
      }
    }
  }
  aiReleaseImport(sc);
  sc = aiImportFile(path, flags);
  if (!sc) return wv_fail(err, WV_ERR_FORMAT, "%s: not a readable mesh: %s", path, ai_error(why, sizeof why));
  long long nv = 0, nt = 0;
  int with_uv = 1;
  for (unsigned i = 0; i < sc->mNumMeshes; i++) {
    const struct aiMesh *am = sc->mMeshes[i];
    long long tris = 0;
    for (unsigned f = 0; f < am->mNumFaces; f++) tris += am->mFaces[f].mNumIndices == 3;
    if (!tris) continue;
    nv += am->mNumVertices, nt += tris;
    if (!am->mTextureCoords[0]) with_uv = 0;
  }
  wv_status st = WV_OK;
  if (nt == 0) st = wv_fail(err, WV_ERR_FORMAT, "%s: the file holds no triangles", path);
  else if (nv > 0x7fffffff || nt > 0x7fffffff || wv_mesh_bytes(nv, nt) > limit)
    st = wv_fail(err, WV_ERR_NOMEM, "%s: %lld vertices and %lld triangles are above the memory limit of %zu MB", path,
                 nv, nt, limit >> 20);
  else if ((st = wv_mesh_alloc(m, (int)nv, (int)nt, with_uv, limit, err)))
    wv_error_prefix(err, "%s", path);
  if (st) {
    aiReleaseImport(sc);
    return st;
  }
  int v0 = 0, t0 = 0;
  for (unsigned i = 0; i < sc->mNumMeshes; i++) {
    const struct aiMesh *am = sc->mMeshes[i];
    int tris = 0;
    for (unsigned f = 0; f < am->mNumFaces; f++) tris += am->mFaces[f].mNumIndices == 3;
    if (!tris) continue;
    for (unsigned v = 0; v < am->mNumVertices; v++) {
      const struct aiVector3D *p = &am->mVertices[v];
      float *q = m->pos + 3 * (size_t)(v0 + v), *n = m->nrm + 3 * (size_t)(v0 + v);
      q[0] = p->x, q[1] = p->y, q[2] = p->z;
      if (am->mNormals) n[0] = am->mNormals[v].x, n[1] = am->mNormals[v].y, n[2] = am->mNormals[v].z;
      float l = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
      if (l > 0) n[0] /= l, n[1] /= l, n[2] /= l;
      if (with_uv) {
        m->uv[2 * (size_t)(v0 + v)] = am->mTextureCoords[0][v].x;
        m->uv[2 * (size_t)(v0 + v) + 1] = am->mTextureCoords[0][v].y;
      }
    }
    for (unsigned f = 0; f < am->mNumFaces; f++) {
      if (am->mFaces[f].mNumIndices != 3) continue;
      for (int k = 0; k < 3; k++) m->idx[3 * (size_t)t0 + k] = (uint32_t)v0 + am->mFaces[f].mIndices[k];
      t0++;
    }
    v0 += (int)am->mNumVertices;
  }
  aiReleaseImport(sc);
  if ((st = wv_mesh_validate(m, path, need_uv, err))) wv_mesh_free(m);
  return st;
}

/* Grid of (nu + 1) x (nv + 1) vertices, two triangles a cell; at(i, j) fills vertex (i, j). */
static wv_status grid(int nu, int nv, wv_mesh *m, wv_error *err) {
  if (nu < 1 || nv < 1 || nu > 8192 || nv > 8192)
    return wv_fail(err, WV_ERR_INVALID, "shape resolution %d x %d is outside 1..8192", nu, nv);
  wv_status st = wv_mesh_alloc(m, (nu + 1) * (nv + 1), 2 * nu * nv, 1, 0, err);
  if (st) return st;
  uint32_t *ix = m->idx;
  for (int j = 0; j < nv; j++)
    for (int i = 0; i < nu; i++) {
      uint32_t a = (uint32_t)(j * (nu + 1) + i), b = a + 1, c = a + (uint32_t)nu + 1, d = c + 1;
      *ix++ = a, *ix++ = b, *ix++ = d;
      *ix++ = a, *ix++ = d, *ix++ = c;
    }
  return WV_OK;
}

static void set_vertex(wv_mesh *m, int k, const double p[3], const double n[3], double u, double v) {
  for (int i = 0; i < 3; i++) m->pos[3 * k + i] = (float)p[i], m->nrm[3 * k + i] = (float)n[i];
  m->uv[2 * k] = (float)u, m->uv[2 * k + 1] = (float)v;
}

wv_status wv_mesh_quad(const double c[3], const double eu[3], const double ev[3], double su, double sv, int n,
                       wv_mesh *m, wv_error *err) {
  double a[3], b[3], nn[3];
  double la = sqrt(dot3d(eu, eu)), lb = sqrt(dot3d(ev, ev));
  if (!(la > 0 && lb > 0 && su > 0 && sv > 0)) return wv_fail(err, WV_ERR_INVALID, "quad: zero size or edge");
  for (int i = 0; i < 3; i++) a[i] = eu[i] / la, b[i] = ev[i] / lb;
  cross3(a, b, nn);
  double ln = sqrt(dot3d(nn, nn));
  if (!(ln > 1e-9)) return wv_fail(err, WV_ERR_INVALID, "quad: its two edges are parallel");
  for (int i = 0; i < 3; i++) nn[i] /= ln;
  wv_status st = grid(n, n, m, err);
  if (st) return st;
  for (int j = 0; j <= n; j++)
    for (int i = 0; i <= n; i++) {
      double u = i / (double)n * su, v = j / (double)n * sv, p[3];
      for (int k = 0; k < 3; k++) p[k] = c[k] + (u - 0.5 * su) * a[k] + (v - 0.5 * sv) * b[k];
      set_vertex(m, j * (n + 1) + i, p, nn, u, v);
    }
  return WV_OK;
}

wv_status wv_mesh_sphere(const double c[3], double r, int rings, int segs, wv_mesh *m, wv_error *err) {
  if (!(r > 0)) return wv_fail(err, WV_ERR_INVALID, "sphere: radius must be positive");
  if (rings < 3) rings = 3;
  if (segs < 3) segs = 3;
  /* rows 1..rings-1 on latitude circles; the poles get one vertex a segment (at the
   * segment's middle longitude) so that no triangle has a zero UV area */
  wv_status st = grid(segs, rings, m, err);
  if (st) return st;
  for (int j = 0; j <= rings; j++)
    for (int i = 0; i <= segs; i++) {
      double lat = -PI / 2 + PI * j / rings;
      double lon = 2 * PI * (i + (j == 0 || j == rings ? 0.5 : 0.0)) / segs;
      double n[3] = {cos(lat) * sin(lon), sin(lat), cos(lat) * cos(lon)}, p[3];
      for (int k = 0; k < 3; k++) p[k] = c[k] + r * n[k];
      set_vertex(m, j * (segs + 1) + i, p, n, r * lon, r * lat);
    }
  /* the pole rows' last vertex (i = segs) would sit past the seam: drop its triangles' zero-area twins */
  int nt = 0;
  for (int t = 0; t < m->nt; t++) {
    uint32_t *ix = m->idx + 3 * t;
    double e1[3], e2[3], x[3];
    sub3(m->pos + 3 * ix[1], m->pos + 3 * ix[0], e1);
    sub3(m->pos + 3 * ix[2], m->pos + 3 * ix[0], e2);
    cross3(e1, e2, x);
    if (sqrt(dot3d(x, x)) > 1e-9 * r * r) memmove(m->idx + 3 * nt++, ix, 3 * sizeof *ix);
  }
  m->nt = nt;
  return WV_OK;
}

wv_status wv_mesh_cylinder(const double c[3], double r, double len, int segs, wv_mesh *m, wv_error *err) {
  if (!(r > 0 && len > 0)) return wv_fail(err, WV_ERR_INVALID, "cylinder: radius and length must be positive");
  if (segs < 3) segs = 3;
  /* u grows with -theta, theta = atan2(y, z); v along +x: u x v points outward */
  wv_status st = grid(segs, 1, m, err);
  if (st) return st;
  for (int j = 0; j <= 1; j++)
    for (int i = 0; i <= segs; i++) {
      double th = PI - 2 * PI * i / segs; /* from the back, over the top, down the front */
      double n[3] = {0, sin(th), cos(th)};
      double p[3] = {c[0] + (j - 0.5) * len, c[1] + r * n[1], c[2] + r * n[2]};
      set_vertex(m, j * (segs + 1) + i, p, n, -r * th, (j - 0.5) * len);
    }
  return WV_OK;
}

wv_status wv_mesh_write_obj(const char *path, const wv_mesh *m, const char *comment, wv_error *err) {
  size_t cap = (size_t)m->nv * 128 + (size_t)m->nt * 112 + 4096, n = 0;
  char *buf = malloc(cap);
  if (!buf) return wv_fail(err, WV_ERR_NOMEM, "%s: out of memory", path);
#define PUT(...) (void)(n < cap && (n += (size_t)snprintf(buf + n, cap - n, __VA_ARGS__)))
  if (comment) PUT("# %s\n", comment);
  for (int v = 0; v < m->nv; v++) PUT("v %.6g %.6g %.6g\n", m->pos[3 * v], m->pos[3 * v + 1], m->pos[3 * v + 2]);
  if (m->uv)
    for (int v = 0; v < m->nv; v++) PUT("vt %.6g %.6g\n", m->uv[2 * v], m->uv[2 * v + 1]);
  for (int v = 0; v < m->nv; v++) PUT("vn %.4f %.4f %.4f\n", m->nrm[3 * v], m->nrm[3 * v + 1], m->nrm[3 * v + 2]);
  for (int t = 0; t < m->nt; t++) {
    unsigned a = m->idx[3 * t] + 1, b = m->idx[3 * t + 1] + 1, c = m->idx[3 * t + 2] + 1;
    if (m->uv) PUT("f %u/%u/%u %u/%u/%u %u/%u/%u\n", a, a, a, b, b, b, c, c, c);
    else PUT("f %u//%u %u//%u %u//%u\n", a, a, b, b, c, c);
  }
#undef PUT
  wv_status st = n < cap ? wv_write_file_atomic(path, buf, n, err)
                         : wv_fail(err, WV_ERR_INTERNAL, "%s: OBJ text overflowed its buffer", path);
  free(buf);
  return st;
}
