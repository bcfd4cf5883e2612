/* woven: triangle meshes for the mesh renderer. Loading (OBJ, PLY, STL, glTF 2.0
 * and GLB through assimp's C API, after woven's own checks of the file), validation, per-vertex tangent
 * frames from the UVs, the built-in shapes of scene files (quad, sphere,
 * cylinder), transforms and an OBJ writer (the cloth simulation's output).
 *
 * Fabric frame on a mesh: the weft (fabric x) runs along +u, the warp (fabric y)
 * along +v, z is the shading normal. A material's scale (mm of fabric per UV
 * unit) turns a UV into the fabric position the yarn model is evaluated at. */
#ifndef WOVEN_MESH_H
#define WOVEN_MESH_H

#include <stddef.h>
#include <stdint.h>

#include "woven/error.h"

typedef struct {
  int nv, nt;
  float *pos;     /* nv x 3 */
  float *nrm;     /* nv x 3, unit */
  float *uv;      /* nv x 2, or NULL when the mesh has none */
  float *tan;     /* nv x 4 after wv_mesh_tangents (else NULL): unit tangent along +u, orthogonal
                     to the normal; w = +1 when normal x tangent points along +v, -1 when mirrored */
  uint32_t *idx;  /* nt x 3 */
} wv_mesh;

/* Default memory limit for one mesh (its arrays and the ray tracer's index). */
#define WV_MESH_DEFAULT_LIMIT_MB 2048

/* Limits on what a mesh file may declare and bring (docs/hardening.md). */
#define WV_MESH_MAX_ELEMENTS 0x7fffffff /* vertices, faces or accessor elements */
#define WV_MESH_MAX_NODE_DEPTH 256      /* levels of a glTF node tree */
#define WV_MESH_MAX_COORD 1e8           /* |coordinate| in mm (100 km), after the object's transform */
#define WV_MESH_MAX_UV 1e8              /* |texture coordinate| */
#define WV_MESH_JSON_COST 32            /* a glTF's JSON text costs up to this many times its size parsed */

/* Bytes a mesh of nv vertices and nt triangles costs: its arrays plus about
 * 96 bytes a triangle for the ray tracer's acceleration structure. */
size_t wv_mesh_bytes(long long nv, long long nt);

/* Arrays for nv vertices and nt triangles (uv when with_uv), zeroed. */
wv_status wv_mesh_alloc(wv_mesh *m, int nv, int nt, int with_uv, size_t limit_bytes, wv_error *err);
void wv_mesh_free(wv_mesh *m);

/* Loads every triangle of a mesh file (all meshes of the file merged, node
 * transforms applied; points and lines dropped). A file larger than limit_bytes,
 * or a mesh whose wv_mesh_bytes exceed it, is refused (WV_ERR_NOMEM); 0 means
 * the default limit. Missing normals are computed (smooth). The mesh is then
 * checked with wv_mesh_validate(need_uv). Messages name the file. */
wv_status wv_mesh_load(const char *path, size_t limit_bytes, int need_uv, wv_mesh *m, wv_error *err);

/* What wv_mesh_load checks before assimp reads the file: a regular file whose name
 * ends in .obj, .ply, .stl, .gltf or .glb; no larger than limit_bytes (0: the
 * default); the counts a PLY header or binary STL declares, the faces of an OBJ,
 * a GLB's chunk lengths, and a glTF's JSON size, buffers (files beside it must be
 * regular and long enough), accessor ranges and counts (once per node that places
 * the mesh) against the limit and the file's size; a glTF node tree at most
 * WV_MESH_MAX_NODE_DEPTH deep. OBJ material libraries must be regular files. */
wv_status wv_mesh_check_file(const char *path, size_t limit_bytes, wv_error *err);

/* Finite values, coordinates within WV_MESH_MAX_COORD and UVs within WV_MESH_MAX_UV,
 * indices in range, no degenerate triangle (zero area), and with
 * need_uv: UVs present, finite, and no triangle with zero UV area (no tangent
 * frame there). name is used in messages. */
wv_status wv_mesh_validate(const wv_mesh *m, const char *name, int need_uv, wv_error *err);

/* Per-vertex tangent frames from the UVs (the triangles' dP/du, dP/dv summed at
 * each vertex, made orthogonal to the normal). Needs UVs. */
wv_status wv_mesh_tangents(wv_mesh *m, const char *name, wv_error *err);

/* Applies x' = A x + b (A row-major 3x3) to positions; normals by the inverse
 * transpose, renormalised. Tangents, if any, are dropped (recompute them). */
wv_status wv_mesh_transform(wv_mesh *m, const double A[9], const double b[3], wv_error *err);

/* Built-in shapes. UVs are lengths on the surface in the shape's units, so a
 * material's mm-per-UV scale is its mm per scene unit.
 * quad: centre c, edge directions eu (along +u) and ev (along +v), size su x sv;
 *   uv = (distance along eu, distance along ev) from the corner c - su/2 eu - sv/2 ev.
 * sphere: centre, radius, rings x segments; u = radius * longitude (rad), v = radius * (latitude (rad)).
 * cylinder: around the x axis through c, radius, length, segments around;
 *   u = -radius * atan2(y, z) (arc length, growing downward on the side facing +z),
 *   v = x - c_x (along the axis). */
wv_status wv_mesh_quad(const double c[3], const double eu[3], const double ev[3], double su, double sv, int n,
                       wv_mesh *m, wv_error *err);
wv_status wv_mesh_sphere(const double c[3], double radius, int rings, int segments, wv_mesh *m, wv_error *err);
wv_status wv_mesh_cylinder(const double c[3], double radius, double length, int segments, wv_mesh *m,
                           wv_error *err);

/* Writes positions, UVs (if any), normals and triangles as Wavefront OBJ, atomically. */
wv_status wv_mesh_write_obj(const char *path, const wv_mesh *m, const char *comment, wv_error *err);

#endif
